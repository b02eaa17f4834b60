"""The MCAP recorder in a process of its own, for a node whose thread is busy: a
``McapRecorder`` in a child process, driven over a pipe with the same calls (``add_topic``,
``write_many``, ``close``), so that encoding the records takes no time from the node's Python
interpreter (one interpreter runs one thread at a time: a recorder thread would share it).

Each call waits for the child's answer; ``BackgroundRecorder`` makes the calls from its writer
thread, in batches, so the node does not wait. Failures are the recorder's (``RecordingError``
with its one line; ``FileExistsError`` for a bag folder that exists), raised in the caller. The
child ignores SIGINT and SIGTERM (the node finalizes the file through ``close``); if the node
dies (SIGKILL) the child sees the pipe close and ends without finalizing, as a killed recorder:
``biped-gait recover`` rebuilds the file from its closed chunks.
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import threading
from multiprocessing.connection import Connection
from pathlib import Path

from .writer import DEFAULT_CHUNK_SIZE, McapRecorder, Message, RecordingError, SampleRows


class RecorderProcess:
    """``McapRecorder(directory, name, chunk_size)`` in a child process (see the module)."""

    def __init__(self, directory: str | Path, name: str, chunk_size: int = DEFAULT_CHUNK_SIZE) -> None:
        ours, theirs = socket.socketpair()
        # A fresh interpreter running this module (no fork of the node's threads, no import of its modules).
        self._process = subprocess.Popen(
            [sys.executable, "-m", __name__, str(theirs.fileno()), str(directory), name, str(chunk_size)],
            pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL)
        theirs.close()
        self._conn = Connection(ours.detach())
        self.bag_dir = Path(directory) / name
        self._lock = threading.Lock()
        self.failure = ""
        self.closed = False  # after close or a failure: calls do nothing
        self._ended = False  # the child was told to close
        try:
            _, path = self._call("open")
        except (RecordingError, FileExistsError):
            self._ended = True
            self._process.wait(timeout=5.0)
            raise
        self.path = Path(path)

    def _call(self, command: str, *args):
        """Send ``command`` and return the child's answer; raise its failure (once: the child's
        recorder is closed after a failure, and later calls do nothing)."""
        with self._lock:
            if self.closed:
                return None
            kind, value = self._exchange(command, *args)
            if kind == "error":
                self.failure, self.closed = value, True
        if kind == "exists":
            raise FileExistsError(value)
        if kind == "error":
            raise RecordingError(value)
        return value

    def _exchange(self, command: str, *args) -> tuple[str, object]:
        try:
            self._conn.send((command, args))
            return self._conn.recv()
        except (EOFError, OSError):
            return "error", f"recording failed: {self.bag_dir}: the recorder process ended"

    def add_topic(self, topic: str, datatype: str, qos: list[dict], type_hash: str | None = None) -> None:
        """``McapRecorder.add_topic``."""
        self._call("add_topic", topic, datatype, qos, type_hash)

    def write_many(self, messages: list[Message | SampleRows]) -> None:
        """``McapRecorder.write_many``."""
        if messages:
            self._call("write_many", messages)

    def close(self) -> None:
        """``McapRecorder.close`` (``RecordingError`` if finishing the file fails, unless a
        failure was raised before); the child then ends. Idempotent."""
        with self._lock:
            kind, value = ("ok", None) if self._ended else self._exchange("close")
            self._ended = self.closed = True
        try:
            self._process.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            self._process.kill()
        if kind == "error" and not self.failure:
            self.failure = value
            raise RecordingError(value)


def serve(conn: Connection, directory: str, name: str, chunk_size: int) -> None:
    """The child: open the recorder, then answer calls until ``close`` or the pipe closes."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    recorder: McapRecorder | None = None
    while True:
        try:
            command, args = conn.recv()
        except (EOFError, OSError):
            return  # the node is gone: end as a killed recorder would
        try:
            if command == "open":
                recorder = McapRecorder(directory, name, chunk_size=chunk_size)
                answer = ("ok", (str(recorder.bag_dir), str(recorder.path)))
            else:
                answer = ("ok", getattr(recorder, command)(*args))
        except FileExistsError as exc:
            answer = ("exists", str(exc))
        except RecordingError as exc:
            answer = ("error", str(exc))
        conn.send(answer)
        if command == "close" or recorder is None:
            return


if __name__ == "__main__":
    serve(Connection(int(sys.argv[1])), sys.argv[2], sys.argv[3], int(sys.argv[4]))
