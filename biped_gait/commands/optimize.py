"""``biped-gait optimize-arms``: the arm amplitude of least effort W for one (L, T, mode) with
the gait options; ``--json`` the optimum and every amplitude solved, ``--out DIR`` those and
W against alpha. Exit status 1 when no amplitude of the range gives an admissible gait."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ..arguments import alpha_range, check_output_folder, request_fields
from ..core.gait import views
from ..core.gait.gait import Gait
from ..core.gait.planner import GaitPlanner
from ..core.gait.arm_optimum import ArmOptimum, NoAdmissibleGait, optimal_arm_amplitude
from .output import check_json, write_json

JSON_NAME = "optimum.json"
FIGURE_NAME = "W_vs_alpha.png"


def document(optimum: ArmOptimum, solved: list[Gait]) -> dict:
    """The optimum as JSON-ready values (radians, with degrees beside), and every gait solved."""
    solved = sorted(solved, key=lambda g: g.arm_amplitude)
    return {
        "alpha": optimum.alpha, "alpha_deg": math.degrees(optimum.alpha), "W": optimum.W, "where": optimum.where,
        "interior": optimum.interior, "alpha_range": list(optimum.alpha_range), "evaluations": optimum.evaluations,
        "describe": optimum.describe(),
        "solved": [{"alpha": g.arm_amplitude, "W": g.W if g.usable else None, "admissible": g.admissible,
                    "reasons": list(g.reasons)} for g in solved],
        "gait": views.to_dict(optimum.gait, trajectory=False),
    }


def run(args: argparse.Namespace) -> int:
    low, high, step = alpha_range(args)
    check_json(args.json)
    if args.out is not None:
        check_output_folder(args.out, "--out", force=True)
    solved: list[Gait] = []
    try:
        optimum = optimal_arm_amplitude(GaitPlanner(args.params), args.step_length, args.period, args.mode, (low, high),
                                        step, on_result=solved.append, options=request_fields(args, ("mode", "params")))
    except NoAdmissibleGait as exc:
        print(f"biped-gait: {exc}", file=sys.stderr)
        return 1
    print(optimum.describe())
    print(f"{optimum.evaluations} arm amplitudes solved")
    written = [write_json(args.json, document(optimum, solved))]
    if args.out is not None:
        from ..studies.figures import effort_figure, save

        title = (f"W against alpha, L = {args.step_length:g} m, T = {args.period:g} s, {args.mode}, params "
                 f"{optimum.gait.params}")
        written += [write_json(str(Path(args.out) / JSON_NAME), document(optimum, solved)),
                    save(effort_figure(solved, [optimum], title), Path(args.out) / FIGURE_NAME)]
    files = [str(path) for path in written if path is not None]
    if files:
        print("written: " + ", ".join(files))
    return 0
