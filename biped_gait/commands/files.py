"""``biped-gait urdf`` (the robot description) and ``biped-gait recover`` (a complete MCAP
file from a killed recorder's)."""

from __future__ import annotations

import argparse

from ..arguments import check_output_file
from .output import write_model
from ..core.model.params import load_params
from ..core.model.urdf import make_urdf
from ..recording.recover import check_mcap, is_complete, recover as recover_file


def urdf(args: argparse.Namespace) -> int:
    if args.out:
        check_output_file(args.out, "--out")
    return write_model(make_urdf(load_params(args.params)), args.out)


def recover(args: argparse.Namespace) -> int:
    files = sorted(args.bag.glob("*.mcap")) if args.bag.is_dir() else [args.bag]
    if not files or not files[0].is_file():
        raise ValueError(f"no MCAP file at {args.bag}")
    source = files[0]
    check_mcap(source)
    name = source.stem.removesuffix("_0") + "_recovered"
    out = args.out or source.parent.parent / name / f"{name}_0.mcap"
    check_output_file(out, "--out")
    out.parent.mkdir(parents=True, exist_ok=True)
    count = recover_file(source, out)
    state = "was complete" if is_complete(source) else "was truncated"
    print(f"{source} {state}; {count} messages written to {out}")
    return 0
