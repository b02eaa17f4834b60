"""Pacing a simulation against the wall clock: sample at simulated time t is released at
``start + t / factor`` (s, monotonic clock); a factor of 0 runs as fast as possible. A pause
moves ``start`` later by its length."""

from __future__ import annotations

import threading
import time


class Pacer:
    """Real-time pacing with ``factor`` simulated seconds per wall second (0: unpaced); the wall
    clock starts at construction."""

    def __init__(self, factor: float) -> None:
        if not factor >= 0:
            raise ValueError(f"real-time factor must be 0 (unpaced) or positive, got {factor}")
        self.factor = factor
        self.start = time.monotonic()

    def wait(self, t: float, stop: threading.Event) -> bool:
        """Wait until simulated time ``t`` (s) is due; False if ``stop`` was set meanwhile."""
        if self.factor > 0:
            delay = self.start + t / self.factor - time.monotonic()
            if delay > 0:
                return not stop.wait(delay)
        return not stop.is_set()

    def delay(self, seconds: float) -> None:
        """Move the schedule ``seconds`` (s) later: the time the simulation was held (a pause)."""
        self.start += seconds

    def elapsed(self) -> float:
        """Wall time since the start, less the delays (s)."""
        return time.monotonic() - self.start
