"""Recording off the caller's path: messages are queued and a writer thread of the recorder's own
hands them to the ``McapRecorder`` in batches, so that a simulation step or a service answer
never waits for encoding or the disk. The recorder may run in a process of its own
(``RecorderProcess``: the simulator's, whose thread keeps the interpreter busy).

A queued message is CDR bytes, or a function giving them, called on the writer thread (a
service's exchange is serialized there, after the answer has gone). Stamps are taken when a
message is queued (ns since the epoch). Samples of several topics come as rows
(``write_samples``: a simulation step's at once, one entry of the queue). The queue is bounded
(``max_pending`` entries): past it, the caller waits for the writer (a disk slower than the
caller for long).

Failures are those of ``McapRecorder`` (a full disk, a deleted folder): the writer thread stops
there, the file finished as far as it got, and the error (``RecordingError``, one line) is
reported once: to ``on_failure`` where the owner gives one (called on the writer thread, so that
the failure reaches the owner whichever thread writes next: a node writes from its walk, its
timers and its services), else raised by the next ``write`` or by ``close``. Later writes are
ignored.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable

from .recorder_process import RecorderProcess
from .writer import McapRecorder, RecordingError, SampleRows

Payload = bytes | Callable[[], bytes]
BATCH_PERIOD = 0.02  # s: the longest a queued message waits for the writer thread
MAX_PENDING = 200_000  # queue entries at most (messages, or steps of samples)


class BackgroundRecorder:
    """Queues messages for ``recorder`` and writes them from a thread of its own; ``add_topic``
    goes straight to the recorder. ``close`` writes what is queued, then finalizes the file."""

    def __init__(self, recorder: McapRecorder | RecorderProcess, max_pending: int = MAX_PENDING,
                 on_failure: Callable[[RecordingError], None] | None = None) -> None:
        self.recorder = recorder
        self._on_failure = on_failure
        self.bag_dir, self.path = recorder.bag_dir, recorder.path
        self._queue: deque[tuple[str, Payload, int] | SampleRows] = deque()
        self._max_pending = max_pending
        self._wake = threading.Event()
        self._room = threading.Condition()
        self._closing = False
        self._error: RecordingError | None = None
        self._reported = False
        self._thread = threading.Thread(target=self._run, name="recorder", daemon=True)
        self._thread.start()

    @property
    def closed(self) -> bool:
        """True once closed or failed: nothing more is recorded."""
        return self._closing or self._error is not None

    @property
    def failure(self) -> str:
        """Why recording stopped early ('' while it goes on or closed cleanly)."""
        return str(self._error) if self._error is not None else self.recorder.failure

    def add_topic(self, topic: str, datatype: str, qos: list[dict], type_hash: str | None = None) -> None:
        """``McapRecorder.add_topic``."""
        self.recorder.add_topic(topic, datatype, qos, type_hash)

    def write(self, topic: str, data: Payload, stamp_ns: int | None = None) -> None:
        """Queue ``data`` (CDR bytes, or a function giving them) on ``topic`` at ``stamp_ns``
        (default: now); ``RecordingError`` once after the writer failed (unless ``on_failure``
        took it); nothing once closed."""
        self._enqueue((topic, data, time.time_ns() if stamp_ns is None else stamp_ns))

    def write_samples(self, samples: SampleRows) -> None:
        """Queue rows of samples (one entry); as ``write``."""
        self._enqueue(samples)

    def _enqueue(self, entry: tuple[str, Payload, int] | SampleRows) -> None:
        if self._error is not None or self._closing:
            self._check()
            return
        queue = self._queue
        queue.append(entry)
        if len(queue) >= self._max_pending:
            self._wait_for_room()

    def _check(self) -> None:
        if self._error is not None and not self._reported:
            self._reported = True
            raise self._error

    def _wait_for_room(self) -> None:
        self._wake.set()
        with self._room:
            self._room.wait_for(lambda: len(self._queue) < self._max_pending // 2 or self._error is not None
                                or not self._thread.is_alive())
        self._check()

    def _run(self) -> None:
        """Write what is queued every ``BATCH_PERIOD`` s (or when woken) until closed, then the rest."""
        queue = self._queue
        while True:
            self._wake.wait(BATCH_PERIOD)
            self._wake.clear()
            closing = self._closing
            batch = [queue.popleft() for _ in range(len(queue))]
            try:
                self.recorder.write_many([entry if isinstance(entry, SampleRows) else _message(*entry)
                                          for entry in batch])
            except RecordingError as exc:
                self._failed(exc)
            except Exception as exc:  # noqa: BLE001  a payload that could not be serialized
                self._failed(RecordingError(f"recording failed: {self.path}: {type(exc).__name__}: {exc}"))
                self._finish_failed()
            with self._room:
                self._room.notify_all()
            if closing or self._error is not None:
                return

    def _failed(self, error: RecordingError) -> None:
        """The writer failed: ``error`` to ``on_failure`` (marked reported before any write can
        see it), or kept for the next ``write`` or ``close`` to raise."""
        self._reported = self._on_failure is not None
        self._error = error
        if self._on_failure is not None:
            self._on_failure(error)

    def _finish_failed(self) -> None:
        try:
            self.recorder.close()
        except RecordingError:
            pass  # the first error is the one reported

    def close(self) -> None:
        """Write what is queued, then finalize the file (``McapRecorder.close``). Idempotent.
        ``RecordingError`` if the writer failed and no write reported it, or finishing fails."""
        self._closing = True
        self._wake.set()
        self._thread.join()
        self._check()
        self.recorder.close()


def _message(topic: str, data: Payload, stamp: int) -> tuple[str, bytes, int]:
    """A queued message as the recorder takes it (the bytes made now if they were deferred)."""
    return topic, data if isinstance(data, bytes) else data(), int(stamp)
