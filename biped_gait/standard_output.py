"""Standard output whose reader may go, as in ``biped-gait plan --out X | head -3``: no error
then, and nothing more written there, as with a Unix tool; the command goes on (its files are
written) and exits with its own status."""

from __future__ import annotations

import os
from typing import Any, Callable, TextIO


def drop_standard_output(stream: TextIO) -> None:
    """The reader of ``stream`` (standard output) is gone: from now on what is written there goes
    to /dev/null, the interpreter's flush at exit included."""
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, stream.fileno())
    os.close(null)


class QuietStdout:
    """``stream`` (standard output), where a closed reader drops what is printed after it
    (``drop_standard_output``) instead of raising ``BrokenPipeError``."""

    def __init__(self, stream: TextIO):
        self._stream = stream

    def write(self, text: str) -> int:
        self._quietly(self._stream.write, text)
        return len(text)

    def flush(self) -> None:
        self._quietly(self._stream.flush)

    def _quietly(self, call: Callable[..., Any], *args: Any) -> None:
        try:
            call(*args)
        except BrokenPipeError:
            drop_standard_output(self._stream)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)
