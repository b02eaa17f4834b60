"""Benchmark: the simulator's real-time factor, publishing at 1 kHz with recording on, as fast
as possible (real_time_factor 0), 10 steps of the default gait, planner and simulator as real
node processes. Also times the walker alone (no ROS) and with the world view of every sample, for
the split. Run:

    .venv/bin/python benchmarks/bench_simulator.py
"""

from __future__ import annotations

import math
import os
import re
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "92")

from biped_gait.core.planner import GaitPlanner, GaitRequest  # noqa: E402
from biped_gait.core.samples import NativeSamples  # noqa: E402
from biped_gait.core.walk import PlannedOrbit, Walker  # noqa: E402
from biped_gait.core.world import WorldView  # noqa: E402
from biped_gait.ros.launch import start_entry, stop_process  # noqa: E402

STEPS, RATE = 10, 1000.0


def core_only() -> tuple[float, float]:
    """Real-time factors of the walker alone and of the walker with the world view of every
    sample (evaluated per step in one call, then one WorldState a sample, as ``Walk`` does)."""
    planner = GaitPlanner()
    plan = planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5), "normal"))
    walker, view = Walker(planner.hybrid, PlannedOrbit.of(plan), RATE), WorldView(planner.model)
    start = time.perf_counter()
    world_time = 0.0
    for _ in range(STEPS):
        side, foot = walker.state.stance_side, walker.state.stance_foot
        outcome = walker.walk_step()
        t0 = time.perf_counter()
        pictures = view.pictures(np.array([s.q for s in outcome.samples]), np.array([s.qd for s in outcome.samples]),
                                 side, foot)
        [pictures.state(k) for k in range(len(pictures))]
        world_time += time.perf_counter() - t0
    wall = time.perf_counter() - start
    return walker.state.t / (wall - world_time), walker.state.t / wall


def main() -> None:
    walk_rtf, with_world_rtf = core_only()
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        planner = start_entry("biped-gait-planner", ["-p", "record:=false"], log=where / "biped-gait-planner.log",
                              cwd=where)
        sim = start_entry("biped-gait-simulator", ["-p", f"steps:={STEPS}", "-p", "real_time_factor:=0.0",
                          "-p", f"publish_rate:={RATE}", "-p", "exit_when_done:=true", "-p", f"record_dir:={where}/bags"],
                          log=where / "biped-gait-simulator.log", cwd=where)
        sim.wait(timeout=600)
        stop_process(planner)
        log = (where / "biped-gait-simulator.log").read_text()
    match = re.search(r"walk finished: .* in ([0-9.]+) s wall time \(real-time factor ([0-9.]+)\)", log)
    assert match, log
    print(f"simulator, {STEPS} steps at {RATE:g} Hz, as fast as possible:")
    print(f"  node with publishing and MCAP recording: real-time factor {float(match.group(2)):.2f} "
          f"({match.group(1)} s wall for {STEPS * 0.45:.2f} s simulated)")
    print(f"  walker alone (integration, events, double support, samples): real-time factor {walk_rtf:.1f}")
    print(f"  walker + world view (poses, momenta, link transforms):        real-time factor {with_world_rtf:.1f}")
    print(f"  (samples evaluated {'in the compiled twin' if NativeSamples is not None else 'by the Python loops'})")


if __name__ == "__main__":
    main()
