"""Markdown pieces of the generated pages."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A Markdown table's lines: ``header``, its rule, one line per row of cells."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return lines + ["| " + " | ".join(row) + " |" for row in rows]


def stored_study(name: str, command: str, date: str, commit: str, note: str = "") -> str:
    """The sentence naming a section's stored study ``name``, the ``command`` that makes it (with
    ``note``), its date and commit."""
    return (f"From the stored study `{name}` (`{command}`{note}), computed on {date} at commit {commit}; the page "
            "reads it and solves nothing.")


def missing_study(path, command: str, cost: str) -> list[str]:
    """A section's text when no stored study was found at ``path``: how to make it (``cost``: how long)."""
    return [f"No stored study at `{path}`: run `{command}` ({cost}) and the page again."]


def _section_end(text: list[str], start: int) -> int:
    return next((k for k in range(start + 1, len(text)) if text[k].startswith("## ")), len(text))


def splice_section(page: str, heading: str, lines: list[str], after: str) -> str:
    """``page`` with its section ``heading`` (up to the next ``## ``) replaced by ``lines``; a page
    without one gets it after the section ``after`` (where ``results_page.render`` puts it), or at
    its end."""
    text = page.splitlines()
    if heading in text:
        start = text.index(heading)
        end = _section_end(text, start)
    else:
        start = end = _section_end(text, text.index(after)) if after in text else len(text)
    return "\n".join([*text[:start], heading, "", *lines, "", *text[end:]]) + "\n"


def page_argument(argv: list[str] | None, section: str, source: str) -> Path:
    """The ``--page`` (default docs/results.md) of a command that rewrites the page's ``section``
    from ``source`` alone."""
    parser = argparse.ArgumentParser(description=f"rewrite the results page's {section} section from {source} alone "
                                     "(the rest of the page untouched)")
    parser.add_argument("--page", type=Path, default=Path("docs/results.md"))
    return parser.parse_args(argv).page
