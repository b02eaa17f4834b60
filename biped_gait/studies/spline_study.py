"""The stop or the start of the default gait as a B-spline (core/gait/spline_support.py,
docs/model.md section 14), solved by its continuation and kept in the package, where the walk and
its tests read it.

    python -m biped_gait.studies.spline_study --out biped_gait/core/data/stop/aoustin2013-default.npz
    python -m biped_gait.studies.spline_study --out NEW.npz --from biped_gait/core/data/stop/aoustin2013-default.npz
    python -m biped_gait.studies.spline_study --kind start --out START.npz --keep-stages STAGES/

From nothing: the 10-interval collocation phase (``GaitPlanner.lasting.stop`` or ``.start``, the
walk's margins) lends its impulses (the stop's I^- and held impact, the start's I^+) and its moving
end's velocity to the least-acceleration spline (``spline_support.seed``); the continuation
``spline_support.STAGES`` on the mesh with the feet-line roll row at the closure points only; then
its last stage again with the roll row over the phase's first and last ``END_ROLL`` s too (the
same unknowns: the walk needs it, docs/model.md 14). The stop: about an hour and a half on one core
(the free stage alone 1,500 iterations), measured stage by stage, not yet in one run (docs/model.md
14 says how the kept plan was reached). ``--from`` skips to the last solve, from a kept plan (the
stop from the kept one itself: 19 and 47 iterations, 10 and 25 s, two runs); ``--keep-stages`` writes
each stage's plan as it comes (a long run stopped can go on from its last with ``--from``).
Prints one line per solve; writes one ``.npz`` (``save``).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ..core.dynamics.closed_chain import ClosedChain
from ..core.gait.lasting import LastingRequest
from ..core.gait.planner import GaitPlanner, GaitRequest
from ..core.gait.spline_support import (END_ROLL, KINDS, STAGES, SplineProgram, continuation, seed, spline_mesh,
                                        usable)
from ..core.walking.balance import standing_pose

DURATION = 2.0  # s: the shortest double support whose continuation reached the floor's mu within 200 N m
SEED = LastingRequest(1.0, "l1", 50.0, 0.1)  # the collocation phase that lends its impulses and moving end
GAIT = GaitRequest(0.45, 0.45, math.radians(23.5))  # the default gait


def save(path: Path, support, at, request: GaitRequest, stage, kind: str) -> None:
    """The plan ``support`` (a solved ``LastingSupport`` of the spline) as arrays: ``t`` (s),
    ``q``, ``qd``, ``qdd`` (rad, rad/s, rad/s^2; the single support's coordinates, ``at`` of the
    program's), ``torques`` (N m),
    ``contact_forces`` (old and new tip, N), ``i_minus`` and ``i_plus`` (N m s), ``held_impulses``
    (N s), ``x`` (the program's scaled unknowns, a start for ``--from``) and ``meta`` (JSON: the
    ``kind``, the gait, the margins, the effort, the solve, the date and commit)."""
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    meta = {"kind": kind, "L": request.step_length, "T": request.period, "alpha": request.arm_amplitude, "mode": "normal",
            "duration": support.duration, "least_normal_force": stage.least_normal_force,
            "friction": stage.friction, "effort_total": support.effort_total, "success": support.success,
            "message": support.message, "iterations": support.iterations, "date": time.strftime("%Y-%m-%d"),
            "commit": commit}
    np.savez_compressed(path, t=support.t, q=support.x[:, at], qd=support.xd[:, at], qdd=support.xdd[:, at],
                        torques=support.torques, contact_forces=support.contact_forces, i_minus=support.i_minus,
                        i_plus=support.i_plus,
                        held_impulses=support.held_impact_impulses, x=support.solution["x"],
                        meta=np.array(json.dumps(meta)))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="the .npz file to write")
    parser.add_argument("--kind", choices=KINDS, default="stop", help="the phase (default: the stop)")
    parser.add_argument("--from", dest="start", type=Path,
                        help="a kept plan (.npz) of one of the stages to go on from (the last stage's: the last solve only)")
    parser.add_argument("--keep-stages", type=Path, help="a folder to write each stage's plan into")
    args = parser.parse_args(argv)
    kind = args.kind
    planner = GaitPlanner(modes=("normal",))
    gait = planner.plan(GAIT)
    lasting = planner.lasting
    pose = standing_pose(ClosedChain(planner.model, planner.hybrid.exchange), GAIT.step_length)
    boundary = lasting.boundary(gait, pose.q)

    def report(stage, support) -> None:
        if args.keep_stages is not None:
            args.keep_stages.mkdir(parents=True, exist_ok=True)
            name = f"{kind}-{stage.least_normal_force:g}N-mu{stage.friction:g}.npz"
            save(args.keep_stages / name, support, planner.model.ds_of_single, GAIT, stage, kind)
        print(json.dumps({"least_normal_force": stage.least_normal_force, "friction": stage.friction,
                          "success": support.success, "E": support.effort_total, "iterations": support.iterations,
                          "seconds": round(support.solve_time_s, 1), "message": support.message}), flush=True)

    def program(end_roll: float, near: bool) -> SplineProgram:
        return SplineProgram(lasting.bm, spline_mesh(DURATION, end_roll, kind), "l1", lasting.friction,
                                 lasting.exchange, lasting.flow, near)

    if args.start is None:
        collocation = getattr(lasting, kind)(gait, SEED, pose.q)
        if not collocation.success:
            print(f"spline_study: the collocation {kind} that seeds the spline failed: {collocation.message}",
                  file=sys.stderr)
            return 1
        free = program(0.0, False)
        moving = collocation.xd[0 if kind == "stop" else -1, planner.model.ds_of_single]
        start = seed(free, boundary, lasting.program(kind, "l1").values(collocation.solution), moving)
        stages = STAGES
    else:
        with np.load(args.start) as kept:
            start, meta = kept["x"], json.loads(str(kept["meta"]))
        done = [k for k, stage in enumerate(STAGES)
                if (stage.least_normal_force, stage.friction) == (meta["least_normal_force"], meta["friction"])]
        stages = STAGES[done[0] + 1:] if done else ()
        free = program(0.0, False) if stages else None
    if stages:
        support = continuation(free, boundary, start, stages, report)
        if not usable(free, support):
            return 1
        start = support.solution["x"]
    final = continuation(program(END_ROLL, True), boundary, start, STAGES[-1:], report)
    save(args.out, final, planner.model.ds_of_single, GAIT, STAGES[-1], kind)
    return 0 if final.success else 1


if __name__ == "__main__":
    sys.exit(main())
