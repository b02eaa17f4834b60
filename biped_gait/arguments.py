"""Command-line parsing shared by the project's commands: one-line errors, and output paths
checked before any work starts."""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path


class OneLineParser(argparse.ArgumentParser):
    """Bad usage is one line on stderr and exit status 2, like every other input error."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def _nearest_existing(path: Path) -> Path:
    """``path`` or its closest ancestor that exists."""
    path = path.absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _check_folder_writable(folder: Path, what: str) -> None:
    """``ValueError`` unless ``folder`` can be written in or created (its closest existing
    ancestor is a folder this process may write in)."""
    existing = _nearest_existing(folder)
    if not existing.is_dir():
        raise ValueError(f"{what}: {existing} is not a folder")
    try:
        tempfile.TemporaryFile(dir=existing).close()  # what a write will meet (root, read-only mounts)
    except OSError as exc:
        raise ValueError(f"{what}: cannot write in {existing} ({exc.strerror or exc})") from None


def check_output_file(path: Path, what: str) -> None:
    """``ValueError`` (one line) unless a file can be written at ``path`` (its folder is
    created when written): checked before any work, so that nothing is lost at the end."""
    if path.is_dir():
        raise ValueError(f"{what} {path} is a folder, not a file")
    _check_folder_writable(path.parent, f"{what} {path}")


def check_output_folder(path: Path, what: str, force: bool) -> None:
    """``ValueError`` (one line) unless ``path`` is a folder that can be written in (created if
    missing) and is empty, or ``force`` allows replacing what it holds."""
    if path.exists() and not path.is_dir():
        raise ValueError(f"{what} {path} is a file, not a folder")
    if path.is_dir() and any(path.iterdir()) and not force:
        raise ValueError(f"{what} {path} is not empty (an earlier run?): give another folder, or --force to "
                         "replace its files")
    _check_folder_writable(path, f"{what} {path}")
