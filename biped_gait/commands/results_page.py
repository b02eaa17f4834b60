"""``biped-gait results-page``: the study computed and docs/results.md written with its figures."""

from __future__ import annotations

import argparse
import math

from ..arguments import check_output_file
from ..studies.executors import open_executor
from ..studies.results_page import write_results_page
from ..core.gait.chains import inclusive_range


def run(args: argparse.Namespace) -> int:
    check_output_file(args.out, "--out")
    inclusive_range(0.0, 45.0, args.walk_alpha_step, "--walk-alpha-step's")  # checked before any work
    if args.map_stride < 1:
        raise ValueError(f"--map-stride: must be 1 or more, got {args.map_stride}")
    for duration in args.pulse_durations:
        if not 0.1 <= duration <= 100.0:
            raise ValueError(f"--pulse-durations: each must be in [0.1, 100] ms, got {duration:g}")
    with open_executor(args.workers, args.scheduler) as executor:
        paths = write_results_page(args.out, executor, math.radians(args.alpha_step), math.radians(args.walk_alpha_step),
                                   [d * 1e-3 for d in args.pulse_durations], tuple(args.push_directions),
                                   args.map_stride)
    print("written: " + ", ".join(str(p) for p in paths))
    return 0
