"""Command line: ``biped-gait plan`` (one gait, printed and optionally saved as JSON) and
``biped-gait urdf`` (the robot description). Degrees at this edge; SI and radians inside.

Errors in the input print one line on stderr and exit with status 2; a gait that does not
converge or is not admissible is printed with its reasons and exits with status 1.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .gait import GaitPlanner, GaitRequest
from .params import DEFAULT_PARAMS, load_params, shipped_param_names
from .urdf import make_urdf


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="biped-gait",
        description="Ballistic walking gaits of a 3D seven-link biped with swinging arms "
        "(Aoustin & Formal'skii): periodic single support and minimum-effort impulsive double support.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    plan = sub.add_parser("plan", help="solve one periodic gait and print its summary")
    plan.add_argument("--step-length", type=float, default=0.45, help="step length L (m), default 0.45")
    plan.add_argument("--period", type=float, default=0.45, help="step period T (s), default 0.45")
    plan.add_argument("--arm-amplitude", type=float, default=23.5, help="arm amplitude alpha (deg), default 23.5")
    plan.add_argument("--mode", default="normal", help="normal (arms opposite to legs) or anti-normal")
    plan.add_argument(
        "--params", default=DEFAULT_PARAMS, help=f"parameter set ({', '.join(shipped_param_names())}) or YAML file"
    )
    plan.add_argument("--closure", default="theta", choices=("theta", "slack"),
                      help="theta: solve the trunk pitch for an exact cycle (default); slack: theta = 0 and "
                      "the smallest velocity correction s (paper comparison)")
    plan.add_argument("--effort", default="l1", choices=("l1", "l2"),
                      help="l1: W = sum |I| by LP/HiGHS (default); l2: sum I^2 by OSQP")
    plan.add_argument("--json", type=Path, help="write the full result (SI, radians) to this JSON file")
    urdf = sub.add_parser("urdf", help="print (or write) the URDF of the biped")
    urdf.add_argument("--params", default=DEFAULT_PARAMS, help="parameter set name or YAML file")
    urdf.add_argument("--output", type=Path, help="write to this file instead of stdout")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``biped-gait``; returns the process exit status."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "urdf":
            text = make_urdf(load_params(args.params))
            if args.output:
                args.output.write_text(text)
            else:
                sys.stdout.write(text)
            return 0
        planner = GaitPlanner(args.params)
        request = GaitRequest(
            step_length=args.step_length,
            period=args.period,
            arm_amplitude=math.radians(args.arm_amplitude),
            mode=args.mode,
            closure=args.closure,
            effort=args.effort,
        )
        result = planner.plan(request)
    except ValueError as exc:
        print(f"biped-gait: error: {exc}", file=sys.stderr)
        return 2
    print(result.summary())
    if args.json:
        args.json.write_text(result.to_json())
        print(f"result written to {args.json}")
    return 0 if result.admissible else 1


if __name__ == "__main__":
    sys.exit(main())
