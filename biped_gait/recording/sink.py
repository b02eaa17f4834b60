"""The MCAP writer's output file, built so that a failed write loses nothing the writer handed
over: bytes are kept in memory until ``flush`` writes them, and what a failed write (a full
disk) did not store stays pending, so that a later ``flush`` (after space was freed) continues
exactly where the file stopped. The file under it is any unbuffered binary file object
(``open(path, "wb", buffering=0)`` by default; tests pass one that fails on purpose)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import BinaryIO, Callable

Opener = Callable[[Path], BinaryIO]


def open_unbuffered(path: Path) -> BinaryIO:
    """The default file under a sink: ``path`` created (never overwritten), unbuffered."""
    return open(path, "xb", buffering=0)


class FileSink:
    """A write-behind file for ``mcap.writer.Writer``: ``write`` and ``tell`` in memory,
    ``flush`` to the file. ``deleted`` says whether the file was unlinked while open."""

    def __init__(self, path: Path, opener: Opener = open_unbuffered) -> None:
        self.path = Path(path)
        self._file = opener(self.path)
        self._pending = bytearray()
        self._offset = 0  # bytes handed over by the writer
        self.written = 0  # bytes the file holds

    def write(self, data: bytes) -> int:
        self._pending += data
        self._offset += len(data)
        return len(data)

    def tell(self) -> int:
        return self._offset

    @property
    def pending(self) -> int:
        """Bytes handed over and not yet in the file."""
        return len(self._pending)

    def flush(self) -> None:
        """Write what is pending; ``OSError`` if the file refuses (what it did not take stays pending)."""
        while self._pending:
            count = self._file.write(self._pending)
            if not count:
                raise OSError(28, os.strerror(28))  # a file that takes nothing: no space
            del self._pending[:count]
            self.written += count

    @property
    def deleted(self) -> bool:
        """True if the file (or its folder) was removed while recording."""
        try:
            return os.fstat(self._file.fileno()).st_nlink == 0
        except (OSError, AttributeError, ValueError):
            return False

    def close(self) -> None:
        """Close the file; pending bytes, if any, are dropped."""
        self._pending.clear()
        self._file.close()
