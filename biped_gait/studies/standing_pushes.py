"""The largest push standing recovers, per direction, in both engines (docs/model.md section 13.2):
for each parameter set, engine and direction (forward, backward, left, right: +x, -x, +y, -y of
the world, the back foot the right one), a push on the trunk at ``PUSH_AT`` s of standing,
bisected between ``UPPER`` N s and nothing to ``RESOLUTION`` N s: the largest that does not fall
within ``WATCHED`` s, the reason the next one falls, and how far from the posture the largest
leaves the robot at the end.

Run: ``.venv/bin/python -m biped_gait.studies.standing_pushes [set ...]`` (a Markdown table, each row
also on the standard error as it comes; a few minutes per set).
"""

from __future__ import annotations

import math
import sys

import numpy as np

from ..core.dynamics.closed_chain import ClosedChain
from ..core.gait.planner import GaitPlanner, GaitRequest
from ..core.walking.balance import Balance, balance, standing_pose
from ..core.walking.engines.mujoco import MujocoEngine
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.phases.standing import Standing
from ..core.walking.push import Push
from ..core.walking.runner import Walker

SETS = ("aoustin2013", "aoustin2013-hips")
ENGINES = ("hybrid", "mujoco")
DIRECTIONS = {"forward": (1.0, 0.0, 0.0), "backward": (-1.0, 0.0, 0.0), "left": (0.0, 1.0, 0.0),
              "right": (0.0, -1.0, 0.0)}
PUSH_AT = 0.2  # s
WATCHED = 3.0  # s of standing
UPPER = 8.0  # N s
RESOLUTION = 0.02  # N s
RATE = 100.0  # samples per second


def outcome(planner: GaitPlanner, held: Balance, orbit: PlannedOrbit, engine: str,
            impulse: np.ndarray) -> tuple[str, float]:
    """Stand with ``impulse`` (N s) at ``PUSH_AT`` s: the fall's reason ('' if none within
    ``WATCHED`` s), and the posture's largest offset at the end (rad)."""
    stepper = MujocoEngine(planner.hybrid, RATE) if engine == "mujoco" else None
    walker = Walker(planner.hybrid, orbit, RATE, engine=stepper, phase=Standing(held))
    walker.push(Push(impulse, PUSH_AT))
    while walker.state.t_step < WATCHED - 1e-9:
        run = walker.run_phase()
        if run.fall:
            return run.fall, math.nan
    return "", float(np.max(np.abs(walker.state.q - held.pose.q)))


def limit(planner: GaitPlanner, held: Balance, orbit: PlannedOrbit, engine: str,
          direction: np.ndarray) -> tuple[float, str, float]:
    """The largest push along ``direction`` that does not fall (N s, bisection), the reason of the
    smallest that does, and the offset the largest leaves."""
    low, high, reason, offset = 0.0, UPPER, "", 0.0
    while high - low > RESOLUTION:
        middle = 0.5 * (low + high)
        fall, end = outcome(planner, held, orbit, engine, middle * direction)
        if fall:
            high, reason = middle, fall
        else:
            low, offset = middle, end
    return low, reason, offset


def table(sets: tuple[str, ...]) -> str:
    rows = ["| set | engine | direction | largest recovered (N s) | the next falls: why | offset left (rad) |",
            "|---|---|---|---|---|---|"]
    for name in sets:
        planner = GaitPlanner(name)
        chain = ClosedChain(planner.model, planner.hybrid.exchange)
        held = balance(chain, standing_pose(chain))
        orbit = PlannedOrbit.of(planner.plan(GaitRequest(0.45, 0.45, math.radians(20.0), "normal")))
        for engine in ENGINES:
            for label, direction in DIRECTIONS.items():
                low, reason, offset = limit(planner, held, orbit, engine, np.array(direction))
                why = reason.replace("|", "\\|")  # a Markdown cell
                rows.append(f"| {name} | {engine} | {label} | {low:.2f} | {why} | {offset:.1e} |")
                print(rows[-1], file=sys.stderr, flush=True)
    return "\n".join(rows)


if __name__ == "__main__":
    print(table(tuple(sys.argv[1:]) or SETS))
