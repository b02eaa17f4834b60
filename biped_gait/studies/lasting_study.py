"""The lasting double support against its duration d and the arm amplitude alpha (docs/results.md,
"A double support that lasts"): E(d) beside W and E(0+), the peak torque and the friction used, at
the default gait; and the arm amplitude of least E at a few d, both arm swings.

    python -m biped_gait.studies.lasting_study --out docs/lasting-study.json

Each solve is the planner's (``GaitPlanner.lasting``): the gait at (L, T, alpha, mode), then its
periodic cycle with the lasting double support, started cold. Writes one JSON file.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

from ..core.gait.lasting import LastingRequest
from ..core.gait.planner import GaitPlanner, GaitRequest

DURATIONS = (0.05, 0.1, 0.15, 0.2, 0.3)
ALPHAS_DEG = (0.0, 7.5, 15.0, 22.5, 30.0, 37.5, 45.0)
ALPHA_DURATIONS = (0.05, 0.1, 0.2)


def _row(planner: GaitPlanner, request: GaitRequest, duration: float) -> dict:
    gait = planner.plan(request)
    limit = planner.lasting.limit(gait)
    support = planner.lasting.periodic(gait, LastingRequest(duration), limit=limit)
    return {"L": request.step_length, "T": request.period, "alpha_deg": math.degrees(request.arm_amplitude),
            "mode": request.mode if isinstance(request.mode, str) else request.mode.value, "d": duration,
            "W": gait.W, "E0": limit.effort_total, "E": support.effort_total if support.success else None,
            "success": support.success, "message": support.message,
            "peak_torque": support.peak_torque.tolist(), "friction_used": support.friction_used,
            "iterations": support.iterations, "solve_time_s": support.solve_time_s}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="the JSON file to write")
    args = parser.parse_args(argv)
    planner = GaitPlanner()
    rows = []
    for d in DURATIONS:
        rows.append(_row(planner, GaitRequest(0.45, 0.45, math.radians(23.5)), d))
        print(json.dumps(rows[-1]), flush=True)
    alphas = []
    for mode in ("normal", "anti-normal"):
        for d in ALPHA_DURATIONS:
            for alpha in ALPHAS_DEG:
                alphas.append(_row(planner, GaitRequest(0.45, 0.45, math.radians(alpha), mode), d))
                print(json.dumps(alphas[-1]), flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    args.out.write_text(json.dumps({"date": time.strftime("%Y-%m-%d"), "commit": commit, "durations": rows,
                                    "alphas": alphas}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
