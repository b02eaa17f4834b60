"""The results page's section "The physics a reviewer would check": the friction cone and the
effort's reading beside the paper's optima, the joint rates the impulses drive (with the effort's
growth under a bound), why the paper's W is not reproduced, and the comparison with human
walking. Everything from computed numbers (``effort_checks``, ``human_walking``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .effort_checks import PAPER_POINTS, READINGS, Readings
from .human_walking import HumanComparison, comparison_lines

PAPER_OPTIMA = {0.40: 21.1, 0.45: 23.5, 0.50: 25.76}  # deg, docs/model.md section 7
PAPER_W = {0.40: (101.22, 106.07), 0.45: (101.9, 111.5), 0.50: (103.92, 117.9)}  # N m s, normal, anti-normal


@dataclass(frozen=True, eq=False)
class ReviewerChecks:
    """The numbers of the section: the readings at the paper's points, the rate-bound curve
    (bound rad/s, W N m s, largest rate rad/s), the human comparison."""

    readings: Readings
    rate_curve: list[tuple[float, float, float]]
    human: HumanComparison


def _readings_table(readings: Readings) -> list[str]:
    header = ("| reading | " + " | ".join(f"alpha* at L = {L:.2f}" for L, _ in PAPER_POINTS) + " | "
              + " | ".join(f"W normal / anti-normal at L = {L:.2f}" for L, _ in PAPER_POINTS) + " |")
    lines = [header, "|---|" + "---:|" * (2 * len(PAPER_POINTS))]
    paper = " | ".join(f"{PAPER_OPTIMA[L]:.2f}" for L, _ in PAPER_POINTS)
    paper_w = " | ".join(f"{PAPER_W[L][0]:.2f} / {PAPER_W[L][1]:.2f}" for L, _ in PAPER_POINTS)
    lines.append(f"| the paper | {paper} | {paper_w} |")
    for label, comparisons in readings.comparisons.items():
        alphas = " | ".join(f"{math.degrees(c.optimum.alpha):.2f}" for c in comparisons)
        efforts = " | ".join(f"{c.optimum.W:.2f} / {c.other.W:.2f}" for c in comparisons)
        lines.append(f"| {label} | {alphas} | {efforts} |")
    return lines


def _impulse_friction(gaits) -> str:
    """What friction the reaction impulses of ``gaits`` need: the largest finite ratio, and how
    many impulses are purely tangential (no vertical part: an infinite ratio)."""
    ratios = np.concatenate([gait.double_support.impulse_friction_ratios for gait in gaits])
    finite = ratios[np.isfinite(ratios)]
    text = f"up to {finite.max():.2f}" if finite.size else "no finite ratio"
    tangential = int(np.sum(np.isinf(ratios)))
    return text + (f", and {tangential} of {ratios.size} impulses are purely tangential" if tangential else "")


def reviewer_lines(checks: ReviewerChecks, rate_figure: str) -> list[str]:
    """The section's Markdown lines (``rate_figure``: the path of the rate-bound figure)."""
    comparisons = checks.readings.comparisons
    labels = list(READINGS)
    cone, free, absolute_free = comparisons[labels[0]], comparisons[labels[1]], comparisons[labels[2]]
    rise = [100 * (c.optimum.W / f.optimum.W - 1) for c, f in zip(cone, free)]
    rise_anti = [100 * (c.other.W / f.other.W - 1) for c, f in zip(cone, free)]
    need_normal = _impulse_friction([c.optimum.gait for c in free])
    need_anti = _impulse_friction([c.other for c in free])
    lines = ["", "## The physics a reviewer would check (beyond the paper)", "",
             "### The friction cone, and the effort's reading", "",
             "The double support's reaction impulses must stay in the floor's friction cone (coefficient mu = 0.5 "
             "by default, per parameter set; linearized as the inscribed octagonal pyramid, so that no impulse needs "
             "more than mu). The effort can be read on joint angles (the paper's eq. 12) or on the links' absolute "
             "angles (each link's net torque impulse). Optimal alpha (deg) and W (N m s) at T = 0.45 s:", ""]
    lines += _readings_table(checks.readings)
    lines += ["",
              f"- Without the cone the reaction impulses need friction {need_normal} (normal), {need_anti} "
              f"(anti-normal; a purely tangential impulse has no vertical part for a floor to hold it by); the cone raises W by {min(rise):.1f} to {max(rise):.1f} % (normal) and "
              f"{min(rise_anti):.1f} to {max(rise_anti):.1f} % (anti-normal): the anti-normal swing leans on friction "
              "a floor does not give.",
              "- With the cone, the joint reading puts the optimal alpha at "
              + ", ".join(f"{math.degrees(c.optimum.alpha):.1f}" for c in cone)
              + " deg against the paper's " + ", ".join(f"{PAPER_OPTIMA[L]:g}" for L, _ in PAPER_POINTS)
              + " deg; without the cone the absolute reading does too ("
              + ", ".join(f"{math.degrees(c.optimum.alpha):.1f}" for c in absolute_free)
              + " deg), the joint reading does not ("
              + ", ".join(f"{math.degrees(c.optimum.alpha):.1f}" for c in free) + " deg).", ""]
    unbounded = next((w, r) for b, w, r in checks.rate_curve if not math.isfinite(b))
    feasible = [(b, w) for b, w, _ in checks.rate_curve if math.isfinite(b) and math.isfinite(w)]
    infeasible = [b for b, w, _ in checks.rate_curve if math.isfinite(b) and not math.isfinite(w)]
    lines += ["### The pump: joint rates between the sub-phases", "",
              f"At L = T = 0.45 s, alpha = 23.5 deg the optimal impulses drive joint rates up to {unbounded[1]:.1f} "
              "rad/s between the sub-phases of the double support (in Xd- and Xd+); real joints of a biped this size "
              "are limited to about 10 rad/s. With a bound on those rates, W grows: "
              + ", ".join(f"{w:.2f} at {b:g} rad/s" for b, w in feasible)
              + f" (N m s; {unbounded[0]:.2f} unbounded)"
              + (f"; below {min(b for b, _ in feasible):g} rad/s ({', '.join(f'{b:g}' for b in infeasible)}) the "
                 "double support has no solution." if infeasible else "."), "",
              f"![Effort against the joint-rate bound]({rate_figure})", ""]
    ratio = [PAPER_W[L][0] / c.optimum.W for (L, _), c in zip(PAPER_POINTS, cone)]
    ratio_abs = [PAPER_W[L][0] / c.optimum.W for (L, _), c in zip(PAPER_POINTS, absolute_free)]
    lines += ["### Why the paper's W is not reproduced", "",
              "The paper's 42 impulse equations have rank 41: the angular momentum of the locked biped about the "
              "foot-to-foot line is conserved through the double support (no joint impulse excites that rotation and "
              "neither foot moves under it), so the linear program as the paper states it has a solution only if the "
              "ballistic step ends with the momentum the next step starts with. A boundary-value solution with the "
              "trunk upright misses that by a little, and the LP is then infeasible; the project solves the trunk "
              "pitch theta for an exact cycle (docs/model.md section 4.5). What was tried to reach the paper's W "
              "(about 101 N m s at the optimum):",
              "- the paper-comparison closure (theta = 0 and the smallest velocity correction s): W changes by a "
              "fraction of a percent (see above);",
              "- the friction cone: W at the optimum is still " + ", ".join(f"{r:.1f}" for r in ratio)
              + " times smaller than the paper's;",
              "- the absolute reading: " + ", ".join(f"{r:.1f}" for r in ratio_abs)
              + " times smaller; it reproduces the paper's optimal amplitudes, not its W;",
              "- an earlier investigation of this project found that only an unclosed or perturbed system (the "
              "equations solved while they are not consistent) inflates W by that much, paying for a momentum the "
              "impulses cannot change (not recomputed on this page). The paper's absolute W is most likely that of "
              "such a system; the project does not tune to it, and the shape of the paper's results reproduces.",
              "", "### Beside human walking", ""]
    lines += comparison_lines(checks.human)
    return lines

