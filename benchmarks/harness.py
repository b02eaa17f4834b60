"""What the benchmarks share beside their yardsticks (``yardsticks``): the simulator node's
real-time factor from a run of the planner and simulator nodes as processes, the wall time of a
method or function measured over its calls, and a figure over runs as its median and range."""

from __future__ import annotations

import re
import statistics
import time
from pathlib import Path

from biped_gait.ros.launch import start_entry, stop_process

RATE = 1000.0  # Hz: the simulator's publishing rate in the benchmarks
_FINISHED = re.compile(r"walk finished: .* in ([0-9.]+) s wall time \(real-time factor ([0-9.]+)\)")


def simulator_factor(where: Path, steps: int, parameters: list[str], tag: str = "", timeout: float = 600.0) -> float:
    """The simulator node's real-time factor (from its log) walking ``steps`` steps at ``RATE``
    as fast as possible against a planner node of its own (no recording there), with the extra
    ``parameters`` (``name:=value``), within ``timeout`` (s); logs and recordings go to ``where``
    (its logs named with ``tag``)."""
    where.mkdir(exist_ok=True)
    suffix = f"_{tag}" if tag else ""
    planner = start_entry("biped-gait-planner", ["-p", "record:=false"], log=where / f"planner{suffix}.log", cwd=where)
    try:
        options = ["initial_state:=walking", f"steps:={steps}", "real_time_factor:=0.0", f"publish_rate:={RATE}",
                   "exit_when_done:=true", f"record_dir:={where}/bags", *parameters]
        sim = start_entry("biped-gait-simulator", [arg for option in options for arg in ("-p", option)],
                          log=where / f"simulator{suffix}.log", cwd=where)
        sim.wait(timeout=timeout)
    finally:
        stop_process(planner)
    log = (where / f"simulator{suffix}.log").read_text()
    match = _FINISHED.search(log)
    assert match, log
    return float(match.group(2))


class Timed:
    """Replaces ``owner.name`` (a method of an object, or a module's function) by itself timed:
    the wall time (s) of each call in ``calls``."""

    def __init__(self, owner: object, name: str) -> None:
        self.calls: list[float] = []
        function = getattr(owner, name)

        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                self.calls.append(time.perf_counter() - start)

        setattr(owner, name, timed)

    @property
    def total(self) -> float:
        """The wall time of all the calls (s)."""
        return sum(self.calls)


def median_range(values: list[float]) -> str:
    """``values`` (a figure over runs) as their median and [min, max]."""
    return f"{statistics.median(values):6.2f} [{min(values):.2f}, {max(values):.2f}]"
