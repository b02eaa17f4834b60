"""``biped-gait figure fig4|fig5``: one of the paper's figures as PNG, with the gait options;
``--json`` its numbers."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..arguments import alpha_range, check_output_file, request_fields
from ..core.model.params import load_params
from ..studies.executors import open_executor
from ..studies.figures import save, two_step_momentum
from ..studies.study import FIG4_CASES, FIG5_CASE, Study, run_study
from ..studies.sweep_output import case_record
from .output import check_json, write_json


def _optimum_record(study: Study, case: tuple[float, float]) -> dict:
    comparison = study.comparisons[case]
    optimum = comparison.optimum
    return {"step_length": case[0], "period": case[1], "mode": str(optimum.gait.mode), "alpha": optimum.alpha,
            "alpha_deg": math.degrees(optimum.alpha), "W": optimum.W, "where": optimum.where,
            "other_mode_W": comparison.other.W if comparison.other.usable else None}


def document(name: str, study: Study) -> dict:
    """The figure's numbers: Fig. 4's optima and curves (every gait, less its samples), Fig. 5's
    two momentum curves (t s, h kg m^2/s)."""
    if name == "fig4":
        return {"figure": name, "optima": [_optimum_record(study, case) for case in FIG4_CASES],
                "curves": [case_record(gait) for gait in study.curves]}
    comparison = study.comparisons[FIG5_CASE]
    curves = {}
    for gait in (comparison.optimum.gait, comparison.other):
        t, h = two_step_momentum(gait)
        curves[str(gait.mode)] = {"alpha": gait.arm_amplitude, "t": t, "h_vertical": h}
    return {"figure": name, "optimum": _optimum_record(study, FIG5_CASE), "momentum": curves}


def run(args: argparse.Namespace) -> int:
    params = load_params(args.params)
    low, high, step = alpha_range(args)
    fig4 = args.name == "fig4"
    out = args.out or Path(f"{args.name}.png")
    check_output_file(out, "--out")
    check_json(args.json)
    with open_executor(args.workers, args.scheduler) as executor:
        [study] = run_study(executor, [params], FIG4_CASES if fig4 else (FIG5_CASE,), curves=fig4, coarse_step=step,
                            alpha_range=(low, high), options=request_fields(args, ("mode", "params")), mode=args.mode)
    save(study.fig4() if fig4 else study.fig5(), out)
    for comparison in study.comparisons.values():
        print(comparison.optimum.describe())
    write_json(args.json, document(args.name, study))
    print(f"{args.name} written to {out}")
    return 0
