"""``biped-gait plan``: one gait, its summary printed; ``--json`` its every figure, ``--out DIR``
the JSON and a figure of the step (with ``--turn-radius``: the stride of two steps on that
circle, its first step drawn). Exit status 1 when the gait is not admissible."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..arguments import check_output_folder, request_fields
from ..core.gait import views
from ..core.gait.planner import GaitPlanner, GaitRequest
from .output import check_json, write_json

JSON_NAME = "plan.json"
FIGURE_NAME = "plan.png"


def run(args: argparse.Namespace) -> int:
    check_json(args.json)
    if args.out is not None:
        check_output_folder(args.out, "--out", force=True)
    fields = request_fields(args, exclude=("params",))
    request = GaitRequest(args.step_length, args.period, math.radians(args.alpha_deg), **fields)
    planner = GaitPlanner(args.params, modes=(request.mode,))  # one gait: one mode's atlas
    if math.isfinite(request.turn_radius):  # a stride of two steps on a circle
        gait = planner.plan_stride(request)
        print(views.stride_summary(gait))
        result, drawn = views.stride_to_dict(gait), gait.steps[0]
    else:
        gait = planner.plan(request)
        print(views.summary(gait))
        result, drawn = views.to_dict(gait), gait
    written = [write_json(args.json, result)]
    if args.out is not None:
        from ..studies.figures import plan_figure, save  # matplotlib only when a figure is asked

        written += [write_json(str(args.out / JSON_NAME), result),
                    save(plan_figure(drawn, planner.model), Path(args.out) / FIGURE_NAME)]
    files = [str(path) for path in written if path is not None]
    if files:
        print("written: " + ", ".join(files))
    return 0 if gait.admissible else 1
