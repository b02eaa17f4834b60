"""The ``biped-gait`` verbs of the second engine: ``mjcf`` (the MJCF export) and ``check-mujoco``
(the plan checked by MuJoCo). MuJoCo is imported by the verbs that
use it, not by the command's start. Errors in the input are ``ValueError`` (one line, exit
status 2 from ``cli.main``)."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from .arguments import check_output_file
from .core.model.params import DEFAULT_PARAMS, load_params, shipped_param_names

CHECK_TOLERANCE = 1e-8  # rad: the ballistic step's agreement that check-mujoco asks for


def _gait_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--params", default=DEFAULT_PARAMS,
                        help=f"parameter set ({', '.join(shipped_param_names())}) or YAML file")
    parser.add_argument("--step-length", type=float, default=0.45, help="step length L (m), default 0.45")
    parser.add_argument("--period", type=float, default=0.45, help="step period T (s), default 0.45")
    parser.add_argument("--arm-amplitude", type=float, default=23.5, help="arm amplitude alpha (deg), default 23.5")
    parser.add_argument("--mode", default="normal", help="normal (arms opposite to legs) or anti-normal")


def add_parsers(sub) -> None:
    """The verbs, on the ``biped-gait`` parser's subparsers ``sub``."""
    from .core.model.mjcf import KINDS

    mjcf = sub.add_parser("mjcf", help="print (or write) the MJCF (MuJoCo) model of the biped")
    mjcf.add_argument("--params", default=DEFAULT_PARAMS, help="parameter set name or YAML file")
    mjcf.add_argument("--kind", default="floating", choices=KINDS,
                      help="floating: the robot with a free pelvis, motors, floor and point feet (default); "
                      "stance: the single-support tree rooted at the stance foot (the model's coordinates); "
                      "extended: that tree with the stance foot's translation (the double support's coordinates)")
    mjcf.add_argument("--output", type=Path, help="write to this file instead of stdout")
    check = sub.add_parser("check-mujoco", help="the planned ballistic step integrated by MuJoCo from the export, "
                           "and the impact equations with MuJoCo's matrices, against the plan")
    _gait_arguments(check)
    check.add_argument("--timestep", type=float, default=1e-4, help="MuJoCo's RK4 step (s), default 1e-4")
    check.add_argument("--json", type=Path, help="write the figures to this JSON file")


def _write(text: str, output: Path | None) -> None:
    if output:
        output.parent.mkdir(parents=True, exist_ok=True)
        output.write_text(text)
    else:
        sys.stdout.write(text)


def _request(args: argparse.Namespace):
    """The gait the verb is about, checked (``ValueError``: one line, before any work)."""
    from .core.gait.planner import GaitRequest, validate_request

    request = GaitRequest(step_length=args.step_length, period=args.period,
                          arm_amplitude=math.radians(args.arm_amplitude), mode=args.mode)
    validate_request(request, load_params(args.params))
    return request


def run_mjcf(args: argparse.Namespace) -> int:
    from .core.model.mjcf import make_mjcf

    if args.output:
        check_output_file(args.output, "--output")
    _write(make_mjcf(load_params(args.params), args.kind), args.output)
    return 0


def run_check(args: argparse.Namespace) -> int:
    """Exit status 0 if the ballistic step agrees within ``CHECK_TOLERANCE``, 1 if not (or the plan
    is not admissible)."""
    if not args.timestep > 0 or not math.isfinite(args.timestep):
        raise ValueError(f"--timestep must be a positive number of seconds, got {args.timestep}")
    if args.json:
        check_output_file(args.json, "--json")
    from .core.dynamics.hybrid import HybridStep
    from .core.gait.planner import GaitPlanner
    from .studies.mujoco_check import check_gait

    request = _request(args)
    planner = GaitPlanner(args.params)
    gait = planner.plan(request)
    if not gait.converged:
        print(f"biped-gait: the plan did not converge: {gait.step.message}", file=sys.stderr)
        return 1
    check = check_gait(gait, HybridStep(planner.model), args.timestep)
    print("\n".join(check.lines()))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(check.to_dict(), indent=2) + "\n")
    agrees = check.max_joint_error < CHECK_TOLERANCE
    print(f"{'agrees' if agrees else 'DISAGREES'}: max joint error {'<' if agrees else '>='} {CHECK_TOLERANCE:g} rad")
    return 0 if agrees else 1


COMMANDS = {"mjcf": run_mjcf, "check-mujoco": run_check}
