"""Benchmark: the simulator's real-time factor at 1 kHz with recording, ``engine:=mujoco`` (pulses
of 5 ms) beside ``engine:=hybrid`` in the same run: 10 steps of the default gait, as fast as
possible, planner and simulator as real node processes, the two engines' runs alternated (so
that the machine's load falls on both alike), each figure the median of ``--repeat`` runs (the
range beside it). Beside them the walks alone (the core's ``Walk``, no ROS, no world view), and
where the MuJoCo walk's time goes: MuJoCo's own steps, and the planner's model planning each
double support (the prediction, the walker's re-aim and LP, the pulses' correction). Run:

    .venv/bin/python benchmarks/bench_mujoco.py [--steps N] [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time
from pathlib import Path

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "93")

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest  # noqa: E402
from biped_gait.core.walking.engines.mujoco import MujocoEngine  # noqa: E402
from biped_gait.core.walking.phases.pulses import Coast  # noqa: E402
from biped_gait.core.walking.steering import DEFAULT_RATE  # noqa: E402
from biped_gait.core.walking.events import Finished  # noqa: E402
from biped_gait.core.walking.orbit import PlannedOrbit  # noqa: E402
from biped_gait.core.walking.walk import Walk  # noqa: E402
from harness import RATE, Timed, median_range, simulator_factor  # noqa: E402

PULSE = 0.005
REQUEST = GaitRequest(0.45, 0.45, math.radians(23.5), "normal")


def core_walk(planner: GaitPlanner, steps: int, engine: str) -> tuple[float, float, float]:
    """The real-time factor of the core's walk (samples with their world view, no ROS) with
    ``engine``; and, for MuJoCo, the seconds spent in MuJoCo's steps and in planning the double
    supports (zero for the hybrid walk)."""
    walk = Walk(PlannedOrbit.of(planner.plan(REQUEST)), RATE, steps, engine=engine, pulse_duration=PULSE,
                momentum_rate=DEFAULT_RATE)
    stepping = planning = None
    plan = Coast._plan
    if isinstance(walk.walker.engine, MujocoEngine):
        stepping, planning = Timed(walk.walker.engine, "_advance"), Timed(Coast, "_plan")
    start = time.perf_counter()
    try:
        items = list(walk.batches())
    finally:
        Coast._plan = plan
    wall = time.perf_counter() - start
    assert isinstance(items[-1], Finished), items[-1]
    return (items[-1].t / wall, stepping.total if stepping else 0.0, planning.total if planning else 0.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    planner = GaitPlanner()
    nodes: dict[str, list[float]] = {"hybrid": [], "mujoco": []}
    cores: dict[str, list[tuple[float, float, float]]] = {"hybrid": [], "mujoco": []}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeat):
            for engine in ("hybrid", "mujoco"):
                nodes[engine].append(simulator_factor(Path(tmp) / f"{engine}_{k}", args.steps, [
                    "record:=true", f"engine:={engine}", f"pulse_duration:={PULSE}"], timeout=900.0))
                cores[engine].append(core_walk(planner, args.steps, engine))
    simulated = args.steps * REQUEST.period
    print(f"{args.steps} steps of the default gait at {RATE:g} Hz, MuJoCo's pulses {PULSE * 1e3:g} ms; "
          f"real-time factor, median of {args.repeat} [range]")
    for engine in ("hybrid", "mujoco"):
        print(f"  node, engine:={engine}, every topic published and recorded: {median_range(nodes[engine])}")
    for engine in ("hybrid", "mujoco"):
        print(f"  walk alone (core Walk, world view, no ROS), {engine}:        {median_range([c[0] for c in cores[engine]])}")
    stepping = statistics.median(c[1] for c in cores["mujoco"])
    planning = statistics.median(c[2] for c in cores["mujoco"])
    print(f"  MuJoCo walk of about {simulated:.1f} s simulated: MuJoCo's steps {stepping:.3f} s, planning the double "
          f"supports {planning:.3f} s ({1e3 * planning / args.steps:.1f} ms each)")
    ratio = statistics.median(nodes["mujoco"]) / statistics.median(nodes["hybrid"])
    print(f"  node mujoco / node hybrid: {ratio:.2f}")


if __name__ == "__main__":
    main()
