"""``biped-gait mjcf`` (the MJCF export) and ``biped-gait check-mujoco`` (the plan checked by
MuJoCo, docs/model.md section 9.2). MuJoCo is imported by the verbs that use it."""

from __future__ import annotations

import argparse
import math
import sys

from ..arguments import check_output_file, check_output_folder, request_fields
from .output import check_json, write_json, write_model
from ..core.model.params import load_params

CHECK_TOLERANCE = 1e-8  # rad: the ballistic step's agreement that check-mujoco asks for


def mjcf(args: argparse.Namespace) -> int:
    from ..core.model.mjcf import make_mjcf

    if args.out:
        check_output_file(args.out, "--out")
    return write_model(make_mjcf(load_params(args.params), args.kind), args.out)


def check(args: argparse.Namespace) -> int:
    """Exit status 0 if the ballistic step agrees within ``CHECK_TOLERANCE``, 1 if not (or the plan
    did not converge)."""
    from ..core.gait.planner import GaitPlanner, GaitRequest, validate_request

    if not args.timestep > 0 or not math.isfinite(args.timestep):
        raise ValueError(f"--timestep must be a positive number of seconds, got {args.timestep}")
    check_json(args.json)
    if args.out is not None:
        check_output_folder(args.out, "--out", force=True)
    request = GaitRequest(args.step_length, args.period, math.radians(args.alpha_deg),
                          **request_fields(args, exclude=("params",)))
    params = load_params(args.params)
    validate_request(request, params)
    if math.isfinite(request.turn_radius):
        raise ValueError("check-mujoco checks one straight step: give no --turn-radius")
    from ..core.dynamics.hybrid import HybridStep
    from ..studies.mujoco_check import check_gait

    planner = GaitPlanner(args.params)
    gait = planner.plan(request)
    if not gait.converged:
        print(f"biped-gait: the plan did not converge: {gait.step.message}", file=sys.stderr)
        return 1
    result = check_gait(gait, HybridStep(planner.model), args.timestep)
    print("\n".join(result.lines()))
    written = [write_json(args.json, result.to_dict())]
    if args.out is not None:
        written.append(write_json(str(args.out / "check.json"), result.to_dict()))
    files = [str(path) for path in written if path is not None]
    if files:
        print("written: " + ", ".join(files))
    agrees = result.max_joint_error < CHECK_TOLERANCE
    print(f"{'agrees' if agrees else 'DISAGREES'}: max joint error {'<' if agrees else '>='} {CHECK_TOLERANCE:g} rad")
    return 0 if agrees else 1
