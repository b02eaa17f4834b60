"""The swing actuated at its two ends against tau and d, and the arms' optimum under it
(docs/model.md section 15): at the default gait E, the peak torque per joint and the friction used
against tau for d = 0 and d = 0.1 s, every torque within the joint table's 200 N m (the smallest
tau that stays within them); E against tau with the limits lifted, tending to the impulsive
cycle's E as tau -> 0; and E against the arm amplitude alpha at (tau, d) = (0.05, 0.1), (0.1, 0.1)
and (0.15, 0.1) s, both arm swings.

    python -m biped_gait.studies.actuated_swing_study --out docs/actuated-swing-study.json

Each solve is ``ActuatedSwingPlanner.cycle``: the first of a sweep from the impulsive cycle of the
same d (``LastingPlanner.periodic``, cold), the next ones by continuation from the previous solved
one. Writes one JSON file.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

from ..core.gait.actuated_swing import ActuatedSwingPlanner, SwingRequest
from ..core.gait.lasting import LastingRequest
from ..core.gait.planner import GaitPlanner, GaitRequest

DEFAULT = (0.45, 0.45, 23.5)  # L (m), T (s), alpha (deg)
TAUS = (0.15, 0.1, 0.075, 0.05, 0.04, 0.03, 0.025, 0.02)  # s, from the longest: each starts from the last solved
DURATIONS = (0.0, 0.1)
FREE_TAUS = (0.1, 0.05, 0.02, 0.01, 0.005)  # s: the limits lifted, tau -> 0
ALPHAS_DEG = (0.0, 7.5, 15.0, 22.5, 30.0, 37.5, 45.0)
ALPHA_TAUS = (0.15, 0.1, 0.05)
ALPHA_DURATION = 0.1


def _row(gait, request: SwingRequest, cycle, impulsive: float) -> dict:
    problem = gait.problem
    return {"L": problem.step_length, "T": problem.period, "alpha_deg": math.degrees(problem.arm_amplitude),
            "mode": problem.mode.value, "tau": request.actuated_swing, "d": request.support.duration,
            "within_limits": request.within_limits, "W": gait.W, "E_impulsive": impulsive,
            "E": cycle.effort_l1 if cycle.success else None, "success": cycle.success, "message": cycle.message,
            "peak_torque": cycle.peak_torque.tolist(), "friction_used": cycle.friction_used,
            "held_impact_impulses": cycle.support.held_impact_impulses.tolist(),
            "iterations": cycle.iterations, "solve_time_s": cycle.solve_time_s}


def _sweep(swing: ActuatedSwingPlanner, gait, requests, impulsive, rows: list) -> None:
    """Solve ``requests`` in order, each from the last one solved (the first from ``impulsive``)."""
    near = None
    for request in requests:
        cycle = swing.cycle(gait, request, impulsive, near)
        rows.append(_row(gait, request, cycle, impulsive.effort_total))
        print(json.dumps(rows[-1]), flush=True)
        if cycle.success:
            near = cycle


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="the JSON file to write")
    args = parser.parse_args(argv)
    planner = GaitPlanner()
    swing = ActuatedSwingPlanner(planner.lasting)
    L, T, alpha = DEFAULT
    gait = planner.plan(GaitRequest(L, T, math.radians(alpha)))
    taus, free, alphas = [], [], []
    for d in DURATIONS:
        impulsive = planner.lasting.periodic(gait, LastingRequest(d))
        _sweep(swing, gait, [SwingRequest(tau, LastingRequest(d)) for tau in TAUS], impulsive, taus)
        if d == 0.0:
            _sweep(swing, gait, [SwingRequest(tau, LastingRequest(d), within_limits=False) for tau in FREE_TAUS],
                   impulsive, free)
    for mode in ("normal", "anti-normal"):
        for tau in ALPHA_TAUS:
            near = None
            for a in ALPHAS_DEG:
                g = planner.plan(GaitRequest(L, T, math.radians(a), mode))
                impulsive = planner.lasting.periodic(g, LastingRequest(ALPHA_DURATION)) if near is None else None
                request = SwingRequest(tau, LastingRequest(ALPHA_DURATION))
                cycle = swing.cycle(g, request, impulsive, near)
                alphas.append(_row(g, request, cycle, None if impulsive is None else impulsive.effort_total))
                print(json.dumps(alphas[-1]), flush=True)
                if cycle.success:
                    near = cycle
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    args.out.write_text(json.dumps({"date": time.strftime("%Y-%m-%d"), "commit": commit, "taus": taus,
                                    "free_taus": free, "alphas": alphas}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
