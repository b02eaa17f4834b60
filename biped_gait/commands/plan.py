"""``biped-gait plan``: one gait, its summary printed; ``--json`` its every figure, ``--out DIR``
the JSON and a figure of the step (with ``--turn-radius``: the stride of two steps on that
circle, its first step drawn). Exit status 1 when the gait is not admissible."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..arguments import check_output_folder, request_fields
from ..core.gait import views
from ..core.gait.lasting_support import LastingSupport
from ..core.gait.planner import GaitPlanner, GaitRequest, lasting_request, swing_request
from .output import check_json, write_json

JSON_NAME = "plan.json"
FIGURE_NAME = "plan.png"


def run(args: argparse.Namespace) -> int:
    check_json(args.json)
    if args.out is not None:
        check_output_folder(args.out, "--out", force=True)
    fields = request_fields(args, exclude=("params",))
    request = GaitRequest(args.step_length, args.period, math.radians(args.alpha_deg), **fields)
    lasting = lasting_request(request, args.double_support)
    swing = swing_request(request, args.actuated_swing, args.double_support)
    if args.start_stop:
        from ..core.walking.kept import check_phases_request, kept_phases  # the walk's modules only when asked
        from ..core.walking.orbit import PlannedOrbit

        check_phases_request(args.double_support, args.actuated_swing)
    planner = GaitPlanner(args.params, modes=(request.mode,))  # one gait: one mode's atlas
    if math.isfinite(request.turn_radius):  # a stride of two steps on a circle
        gait = planner.plan_stride(request)
        print(views.stride_summary(gait))
        result, drawn = views.stride_to_dict(gait), gait.steps[0]
    else:
        gait = planner.plan(request)
        print(views.summary(gait))
        result, drawn = views.to_dict(gait), gait
    admissible = gait.admissible
    if swing is not None and gait.usable:
        from ..core.gait.actuated_swing import cycle_view  # CasADi only when asked

        cycle = planner.swing_cycle(gait, swing)
        print(swing_summary(cycle, gait.W))
        result.update(cycle_view(cycle))
        admissible = admissible and cycle.success
    elif lasting is not None and gait.usable:
        support, limit = planner.lasting_cycle(gait, lasting)
        print(lasting_summary(support, limit.effort_total, gait.W))
        result["double_support_phase"] = views.double_support_phase(support, limit.effort_total)
        admissible = admissible and support.success
    if args.start_stop and gait.usable:
        start, stop = kept_phases(planner.model, PlannedOrbit.of(drawn))
        print(phases_summary(start, stop))
        result["start_phase"], result["stop_phase"] = (views.double_support_phase(p, math.nan) for p in (start, stop))
        admissible = admissible and start.success and stop.success
    written = [write_json(args.json, result)]
    if args.out is not None:
        from ..studies.figures import plan_figure, save  # matplotlib only when a figure is asked

        written += [write_json(str(args.out / JSON_NAME), result),
                    save(plan_figure(drawn, planner.model), Path(args.out) / FIGURE_NAME)]
    files = [str(path) for path in written if path is not None]
    if files:
        print("written: " + ", ".join(files))
    return 0 if admissible else 1


def swing_summary(cycle, paper_effort: float) -> str:
    """A few lines on a cycle with an actuated swing."""
    head = (f"swing actuated for {cycle.actuated_swing:g} s at each end, double support of "
            f"{cycle.support.duration:g} s")
    if not cycle.success:
        return f"{head}: refused: {cycle.message}"
    peak = ", ".join(f"{v:.0f}" for v in cycle.peak_torque)
    return (f"{head}: E = {cycle.effort_l1:.3f} N m s (no impulse), W = {paper_effort:.3f} N m s\n"
            f"  peak torques {peak} N m; friction used {cycle.friction_used:.3f}; held impact "
            f"{abs(cycle.support.held_impact_impulses).max():.2g} N s; IPOPT {cycle.iterations} iterations, "
            f"{cycle.solve_time_s:.2f} s")


def lasting_summary(support: LastingSupport, limit_effort: float, paper_effort: float) -> str:
    """A few lines on a double support that lasts."""
    if not support.success:
        return f"double support of {support.duration:g} s: refused: {support.message}"
    peak = ", ".join(f"{v:.0f}" for v in support.peak_torque)
    return (f"double support of {support.duration:g} s: E = {support.effort_total:.3f} N m s "
            f"(impulses {abs(support.i_minus).sum():.2f} + {abs(support.i_plus).sum():.2f}, "
            f"torques {support.effort_l1:.2f}); "
            f"E(0+) = {limit_effort:.3f}, W = {paper_effort:.3f} N m s\n"
            f"  peak torques {peak} N m; friction used {support.friction_used:.3f}; IPOPT {support.iterations} "
            f"iterations, {support.solve_time_s:.2f} s")


def phases_summary(start: LastingSupport, stop: LastingSupport) -> str:
    """A line each on the gait's start from standing and its stop to standing."""
    lines = []
    for kind, phase in (("start from standing", start), ("stop to standing", stop)):
        if not phase.success:
            lines.append(f"{kind}: refused: {phase.message}")
            continue
        impulses = abs(phase.i_plus if kind.startswith("start") else phase.i_minus).sum()
        lines.append(f"{kind}: {phase.duration:g} s with both feet down, E = {phase.effort_total:.1f} N m s "
                     f"({'I+' if kind.startswith('start') else 'I-'} {impulses:.1f}, torques {phase.effort_l1:.1f}); "
                     f"peak torque {phase.peak_torque.max():.0f} N m, friction used {phase.friction_used:.3f}")
    return "\n".join(lines)
