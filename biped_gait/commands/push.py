"""``biped-gait push-study``: the largest push on the trunk the walker recovers from, per
direction and arm amplitude, for one gait with the gait options; ``--json`` every limit with its
trials."""

from __future__ import annotations

import argparse
import math

from ..arguments import check_output_folder, point_values, request_fields
from ..core.gait.planner import GaitPlanner, GaitRequest, validate_request
from ..core.model.params import load_params
from ..studies import push_study
from ..studies.executors import open_executor
from ..studies.figures import save
from ..core.gait.arm_optimum import optimal_arm_amplitude
from .output import check_json, write_json


def run(args: argparse.Namespace) -> int:
    params = load_params(args.params)
    options = request_fields(args, ("mode", "params"))
    validate_request(GaitRequest(args.step_length, args.period, 0.0, args.mode, **options), params)
    if not 0.0 <= args.phase < 1.0:
        raise ValueError(f"--phase must be in [0, 1), got {args.phase:g}")
    steering = None if args.momentum_rate < 0 else args.momentum_rate
    if steering is not None and not steering < 1.0:
        raise ValueError(f"--momentum-rate must be below 1, got {args.momentum_rate:g}")
    check_json(args.json)
    check_output_folder(args.out, "--out", force=True)
    if args.alpha_deg is None and args.alpha_deg_range is None:
        optimum = optimal_arm_amplitude(GaitPlanner(params), args.step_length, args.period, args.mode, options=options)
        alphas = [0.0, optimum.alpha]
        print(f"optimal arm amplitude {math.degrees(optimum.alpha):.2f} deg ({optimum.where})")
    else:
        alphas = list(point_values(args, "arm_amplitude"))
    cases = push_study.study_cases(alphas, args.directions)
    with open_executor(args.workers, args.scheduler) as executor:
        pushed = push_study.PushedGait(params, args.step_length, args.period, args.mode, args.phase, steering, options)
        limits = push_study.run_push_study(executor, pushed, cases)
    paths = push_study.write_results(limits, args.out)
    title = f"Largest push recovered, L = {args.step_length:g} m, T = {args.period:g} s, phase {args.phase:g} T"
    paths.append(save(push_study.polar_figure(limits, title), args.out / "push-polar.png"))
    if len(alphas) > 1:
        paths.append(save(push_study.limit_vs_alpha_figure(limits, title), args.out / "push-vs-alpha.png"))
    print("\n".join(push_study.describe(limit) for limit in limits))
    write_json(args.json, push_study.document(limits))
    print("written: " + ", ".join(str(p) for p in paths))
    return 0
