"""Text shown to a user or written to a log that may come from outside (a request, a file):
one line, and clipped, so that a 100 kB string is not echoed whole."""

from __future__ import annotations

MAX_SHOWN = 200  # characters of outside text shown in a message or a log line


def clip(text: object, limit: int = MAX_SHOWN) -> str:
    """``text`` on one line (whitespace runs made single spaces), cut to ``limit`` characters
    with the number of characters left out."""
    line = " ".join(str(text).split())
    if len(line) <= limit:
        return line
    return f"{line[:limit]}... ({len(line) - limit} more characters)"
