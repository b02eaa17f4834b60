"""``docs/results.md``: the arm-swing study against the paper's numbers (docs/model.md section 7) for
the default parameter set and the paper's table verbatim, with its figures, the paper's
claims checked on the computed numbers, and where the project and the paper differ,
written from the computed evidence; then the maps of where walking is possible and the walk
beyond the paper (stability, pushes, commanded speed: ``walking_page``), and the double support
that lasts and the actuated swing, read from their stored studies beside the page (``lasting_page``,
``actuated_page``), and the stop and the start the package keeps (``spline_page``).

Everything on the page is computed when it is generated (``biped-gait results-page``); only
the paper's own numbers are constants here. W in N m s, angular momentum in kg m^2/s,
angles in degrees on the page.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace
from pathlib import Path

from ..core.gait.atlas import Atlas, atlas_path
from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Gait
from ..core.model.params import DEFAULT_PARAMS, load_params
from ..core.gait.planner import GaitPlanner, GaitRequest
from .effort_checks import effort_readings, rate_bound_curve, rate_bound_figure
from .figures import save
from .markdown import markdown_table
from .human_walking import human_comparison
from .maps import MAP_STRIDE, WalkingMaps, compute_maps, file_suffix, optimum_figure, ratio_figure, reading, region_figure, stability_figure
from ..core.gait.arm_optimum import ALPHA_RANGE, COARSE_STEP, ArmOptimum
from .push_study import STUDY_DIRECTIONS
from .reviewer import ReviewerChecks, reviewer_lines
from .stability_study import PointStability, point_stability, stability_lines
from .hips_page import HIPS_PARAMS, hips_lines, hips_study
from .actuated_page import (ACTUATED_FIGURE, ACTUATED_STUDY, HEADING as ACTUATED_HEADING, ActuatedStudy,
                            actuated_figure, actuated_lines)
from .spline_page import FIGURES as SPLINE_FIGURES, HEADINGS as SPLINE_HEADINGS, kept_plans, section_figure, section_lines
from .lasting_page import HEADING as LASTING_HEADING, LASTING_STUDY, LastingStudy, lasting_figures, lasting_lines
from .mujoco_pulses import DURATIONS as PULSE_DURATIONS, PulseRow, pulse_lines, pulse_rows
from .turning_page import FIGURE as TURNING_FIGURE, Turning, turning_figure, turning_lines, turning_study
from .study import FIG4_CASES, FIG5_CASE, PAPER_PERIOD, TABLE_CASES, Study, run_study
from .walking_page import ALPHA_STEP as WALK_ALPHA_STEP, Walking, compute_walking, walking_figures, walking_section

PARAMETER_SETS = (DEFAULT_PARAMS, "aoustin2013-table")  # the default and the paper's table verbatim
LONG_PERIOD_CASE = max(TABLE_CASES, key=lambda case: case[1])  # (L m, T s)
# Spec section 7 (T = 0.45 s): L (m) -> optimal alpha of the normal gait (deg), W normal, W anti-normal (N m s).
PAPER_EFFORT = {0.40: (21.1, 101.22, 106.07), 0.45: (23.5, 101.9, 111.5), 0.50: (25.76, 103.92, 117.9)}
# Spec section 6: yaw angular momentum (kg m^2/s) at L = T = 0.45 m/s, alpha = 23.5 deg.
PAPER_ALPHA_DEG = 23.5
PAPER_MOMENTUM = {
    "T+ about the new stance foot": {"normal": 7.65, "anti-normal": 11.98},
    "T- about the old stance foot": {"normal": -11.94, "anti-normal": -16.04},
}


# The paper's jump: H(T+) about the new stance foot minus H(T-) about the old one, as it reports them.
PAPER_JUMP = {mode: PAPER_MOMENTUM["T+ about the new stance foot"][mode] - PAPER_MOMENTUM["T- about the old stance foot"][mode]
              for mode in ("normal", "anti-normal")}
PAPER_JUMP_ROW = "jump, paper's definition: H(T+) new foot - H(T-) old foot"


def paper_momentum_jump(gait: Gait) -> float:
    """|H(T+) about the new stance foot - H(T-) about the old one| (kg m^2/s): the paper's jump,
    which also counts the change of reference point between the two feet."""
    return abs(gait.double_support.h_t_plus[1] - gait.double_support.h_t_minus[0])


def _momenta(gait: Gait) -> dict[str, float]:
    """The page's two momentum figures, keyed like ``PAPER_MOMENTUM``."""
    return {"T+ about the new stance foot": gait.double_support.h_t_plus[1], "T- about the old stance foot": gait.double_support.h_t_minus[0]}


@dataclass(frozen=True, eq=False)
class Reference:
    """Gaits at the paper's momentum point (L = T = 0.45, alpha = 23.5 deg): both modes with
    the theta closure, the normal gait with the paper-comparison closure (theta = 0, s), and
    the normal gait at the table's longest period and alpha = 0 solved cold (no continuation
    in T), where the study's sweeps at that period start."""

    normal: Gait
    anti_normal: Gait
    normal_slack: Gait
    cold_long_period: Gait

    @classmethod
    def compute(cls, params_name: str) -> "Reference":
        planner = GaitPlanner(params_name)
        alpha = math.radians(PAPER_ALPHA_DEG)

        def cold(*request, **options) -> Gait:
            return planner.plan(GaitRequest(*request, **options), cold=True)

        return cls(
            normal=cold(*FIG5_CASE, alpha, "normal"),
            anti_normal=cold(*FIG5_CASE, alpha, "anti-normal"),
            normal_slack=cold(*FIG5_CASE, alpha, "normal", closure="slack"),
            cold_long_period=cold(*LONG_PERIOD_CASE, ALPHA_RANGE[0], "normal"),
        )


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims, whether the computed numbers bear it out, and the numbers."""

    text: str
    holds: bool
    evidence: str


def _grows(values: Sequence[float]) -> bool:
    return all(b > a for a, b in zip(values, values[1:]))


def _list(values: Sequence[float], fmt: str) -> str:
    return ", ".join(format(v, fmt) for v in values)


def paper_claims(study: Study) -> list[Claim]:
    """The shape of the paper's results (docs/model.md section 7), checked on ``study``'s numbers."""
    optima = study.fig4_optima()
    lengths = _list([o.gait.step_length for o in optima], "g")
    alphas = [math.degrees(o.alpha) for o in optima]
    efforts = [o.W for o in optima]
    comparisons = list(study.comparisons.items())
    premium = [(case, c.other.W - c.optimum.W) for case, c in comparisons]
    jumps = [(case, c.optimum.gait.double_support.yaw_momentum_jump, c.other.double_support.yaw_momentum_jump)
             for case, c in comparisons]
    case = lambda c: f"L = {c[0]:g}, T = {c[1]:g}"  # noqa: E731
    return [
        Claim(
            f"W(alpha) has an interior minimum for L = {lengths} m (T = {PAPER_PERIOD:g} s)",
            all(o.interior for o in optima),
            "; ".join(f"L = {o.gait.step_length:g}: {o.where} at {math.degrees(o.alpha):.2f} deg" for o in optima),
        ),
        Claim("the optimal alpha grows with L", _grows(alphas),
              f"alpha* = {_list(alphas, '.2f')} deg for L = {lengths} m"),
        Claim("W at the optimum grows with L", _grows(efforts),
              f"W = {_list(efforts, '.3f')} N m s for L = {lengths} m"),
        Claim(
            "the anti-normal gait costs more than the normal gait at the normal optimum",
            all(d > 0 for _, d in premium),
            "; ".join(f"{case(c)}: W anti-normal - W normal = {d:+.3f} N m s" for c, d in premium),
        ),
        Claim(
            "the yaw angular-momentum jump at double support is smaller for the normal gait",
            all(n < a for _, n, a in jumps),
            "; ".join(f"{case(c)}: {n:.3f} normal, {a:.3f} anti-normal kg m^2/s" for c, n, a in jumps),
        ),
    ]


def _effort_table(study: Study) -> list[str]:
    header = ["L (m)", "T (s)", "alpha* (deg)", "paper", "W normal", "paper", "W anti-normal at alpha*", "paper",
              "anti / normal", "paper", "theta (deg)", "least W is"]
    rows = []
    for case, c in study.comparisons.items():
        paper = PAPER_EFFORT.get(case[0]) if case[1] == PAPER_PERIOD else None
        alpha_p, normal_p, anti_p, ratio_p = (
            (f"{paper[0]:.2f}", f"{paper[1]:.2f}", f"{paper[2]:.2f}", f"{paper[2] / paper[1]:.3f}") if paper else
            ("-",) * 4
        )
        rows.append([
            f"{case[0]:.2f}", f"{case[1]:.2f}", f"{math.degrees(c.optimum.alpha):.2f}", alpha_p,
            f"{c.optimum.W:.3f}", normal_p, f"{c.other.W:.3f}", anti_p,
            f"{c.other.W / c.optimum.W:.3f}", ratio_p, f"{math.degrees(c.optimum.gait.theta):.3f}",
            c.optimum.where,
        ])
    return markdown_table(header, rows)


def _momentum_table(study: Study) -> list[str]:
    header = ["L (m)", "T (s)", "alpha* (deg)", "H(T-) old foot, normal", "anti-normal", "H(T+) new foot, normal",
              "anti-normal", "jump, normal", "anti-normal"]
    rows = []
    for case, c in study.comparisons.items():
        n, a = c.optimum.gait, c.other
        rows.append([f"{case[0]:.2f}", f"{case[1]:.2f}", f"{math.degrees(c.optimum.alpha):.2f}",
                     f"{n.double_support.h_t_minus[0]:.3f}", f"{a.double_support.h_t_minus[0]:.3f}", f"{n.double_support.h_t_plus[1]:.3f}", f"{a.double_support.h_t_plus[1]:.3f}",
                     f"{n.double_support.yaw_momentum_jump:.3f}", f"{a.double_support.yaw_momentum_jump:.3f}"])
    return markdown_table(header, rows)


def _reference_table(references: dict[str, Reference]) -> list[str]:
    header = ["yaw angular momentum (kg m^2/s)", "mode", "paper"] + [f"`{name}`" for name in references]
    rows = []
    for quantity, paper in PAPER_MOMENTUM.items():
        for mode, value in paper.items():
            gaits = [ref.normal if mode == "normal" else ref.anti_normal for ref in references.values()]
            project = [_momenta(gait)[quantity] for gait in gaits]
            rows.append([quantity, mode, f"{value:.2f}"] + [f"{v:.3f}" for v in project])
    for mode, value in PAPER_JUMP.items():
        gaits = [ref.normal if mode == "normal" else ref.anti_normal for ref in references.values()]
        rows.append([PAPER_JUMP_ROW, mode, f"{value:.2f}"] + [f"{paper_momentum_jump(g):.3f}" for g in gaits])
    return markdown_table(header, rows)


def _claims_section(studies: Sequence[Study]) -> list[str]:
    lines = []
    for study in studies:
        lines += ["", f"Parameter set `{study.params.name}`:", ""]
        for claim in paper_claims(study):
            lines.append(f"- **{'holds' if claim.holds else 'does not hold'}**: {claim.text} ({claim.evidence}).")
        if all(c.optimum.alpha == 0 for c in study.comparisons.values()):
            lines.append("- Here the least W is at alpha = 0 in every case: the arms do not swing, so the normal "
                         "and anti-normal gaits are the same gait.")
    return lines


def _effort_scale(optima: Sequence[ArmOptimum]) -> str:
    ratios = [PAPER_EFFORT[o.gait.step_length][1] / o.W for o in optima]
    pairs = "; ".join(f"L = {o.gait.step_length:g}: {PAPER_EFFORT[o.gait.step_length][1]:g} against {o.W:.2f}"
                      for o in optima)
    return (
        f"- **The absolute effort differs by a factor {min(ratios):.2f} to {max(ratios):.2f}.** The paper's W against "
        f"the project's at the optimum, T = {PAPER_PERIOD:g} s (N m s): {pairs}. The paper leaves its double-support "
        "configurations to a figure that is not in its text, so this project fixes them (docs/model.md section 3: "
        "straight legs, feet 0.40 m apart, no torso yaw, the pelvis at pitch theta at both double supports); with "
        "other configurations the impulses differ, and the paper's absolute W is not reproducible from what it "
        "states. What must reproduce is the shape of the results (docs/model.md section 7), not these numbers. "
        "W sums impulses of joint torques, so its unit is N m s (the paper writes N m)."
    )


def _closure(reference: Reference, optima: Sequence[ArmOptimum]) -> str:
    slack, theta = reference.normal_slack, reference.normal
    ratio = min(PAPER_EFFORT[o.gait.step_length][1] / o.W for o in optima)
    return (
        "- **The cycle closure is not the cause.** The paper's linear program is infeasible as it states it "
        "(docs/model.md section 4), so the project solves the trunk pitch theta for an exact cycle (theta = "
        f"{math.degrees(theta.theta):.3f} deg at L = T = 0.45, alpha = {PAPER_ALPHA_DEG} deg). With the "
        f"paper-comparison closure instead (theta = 0 and a velocity correction s = {slack.double_support.slack:.2e} rad/s), "
        f"W = {slack.W:.3f} against {theta.W:.3f} N m s: a change of {100 * abs(slack.W / theta.W - 1):.2f} %, "
        f"not a factor {ratio:.1f}."
    )


def _optimal_amplitude(optima: Sequence[ArmOptimum]) -> str:
    ours = [math.degrees(o.alpha) for o in optima]
    paper = [PAPER_EFFORT[o.gait.step_length][0] for o in optima]
    shifts = [a - b for a, b in zip(ours, paper)]
    return (
        f"- **The optimal amplitude is {min(shifts):+.2f} to {max(shifts):+.2f} deg from the paper's** "
        f"({_list(ours, '.2f')} deg against {_list(paper, 'g')} deg for "
        f"L = {_list([o.gait.step_length for o in optima], 'g')} m); "
        + ("in both it grows with L." if _grows(ours) and _grows(paper) else "it does not grow with L in both.")
    )


def _anti_normal_premium(study: Study) -> str:
    optima = study.fig4_optima()
    ours = [study.comparisons[case].other.W / study.comparisons[case].optimum.W - 1 for case in FIG4_CASES]
    paper = [PAPER_EFFORT[o.gait.step_length][2] / PAPER_EFFORT[o.gait.step_length][1] - 1 for o in optima]
    trend = "grows" if _grows(ours) else "does not grow"
    return (
        f"- **The anti-normal gait's extra cost** at the normal optimum is {_list([100 * p for p in ours], '+.1f')} % "
        f"for L = {_list([o.gait.step_length for o in optima], 'g')} m, against "
        f"{_list([100 * p for p in paper], '+.1f')} % in the paper, where it grows with L; in the project it {trend}."
    )


def _table_inertia(default: Study, table: Study) -> str:
    optima = table.fig4_optima()
    interior = sum(o.interior for o in optima)
    values = []
    for o in optima:
        curve = [r for r in table.curves if (r.step_length, r.mode) == (o.gait.step_length, "normal")]
        values.append(f"L = {o.gait.step_length:g}: least W {o.W:.2f} at {math.degrees(o.alpha):g} deg ({o.where}), "
                      f"W(0) = {curve[0].W:.2f}, W(45 deg) = {curve[-1].W:.2f}")
    found = f"an interior minimum for {interior} of {len(optima)} L" if interior else "no interior minimum for any L"
    return (
        f"- **The table's arm inertia: {found}.** With the table verbatim (`{table.params.name}`, arm transverse "
        f"inertia {table.params.arm.inertia[0]:g} kg m^2, the thigh's value repeated), on [0, 45] deg: "
        + "; ".join(values)
        + f". With the default set's uniform-rod arm ({default.params.arm.inertia[0]:g} kg m^2) the optima are at "
        f"{_list([math.degrees(o.alpha) for o in default.fig4_optima()], '.2f')} deg "
        f"({sum(o.interior for o in default.fig4_optima())} of {len(default.fig4_optima())} interior), which is why "
        "the default set corrects the table (docs/model.md section 1)."
    )


def _momentum_at_paper_point(reference: Reference) -> str:
    moments = {"normal": _momenta(reference.normal), "anti-normal": _momenta(reference.anti_normal)}
    larger = all(abs(moments["anti-normal"][q]) > abs(moments["normal"][q]) for q in PAPER_MOMENTUM)
    pairs = "; ".join(
        f"{q}: normal {PAPER_MOMENTUM[q]['normal']:g} against {moments['normal'][q]:.2f}, anti-normal "
        f"{PAPER_MOMENTUM[q]['anti-normal']:g} against {moments['anti-normal'][q]:.2f}"
        for q in PAPER_MOMENTUM
    )
    jumps = {"normal": paper_momentum_jump(reference.normal), "anti-normal": paper_momentum_jump(reference.anti_normal)}
    return (
        f"- **Angular momentum at L = T = 0.45, alpha = {PAPER_ALPHA_DEG} deg** (kg m^2/s, paper against project): "
        f"{pairs}. The anti-normal gait's momentum is larger in magnitude at both instants in the paper, and "
        + ("in the project too" if larger else "not at both in the project")
        + "; the magnitudes differ for the same reason as W (the boundary configurations). Signs are those of a "
        "right stance foot (docs/model.md section 6). With the paper's definition of the jump (H(T+) about the new "
        f"stance foot minus H(T-) about the old one) the project gives {jumps['normal']:.2f} (normal) against the "
        f"paper's {PAPER_JUMP['normal']:.2f}, and {jumps['anti-normal']:.2f} (anti-normal) against "
        f"{PAPER_JUMP['anti-normal']:.2f}; the tables' jump is on one fixed axis (see the top of the page)."
    )


def _other_periods(default: Study, reference: Reference) -> str:
    cold = reference.cold_long_period
    if not cold.converged:
        outcome = "does not converge"
    elif cold.reasons:
        outcome = f"finds a gait that is not admissible ({'; '.join(cold.reasons)})"
    else:
        outcome = f"finds an admissible gait (W = {cold.W:.3f} N m s)"
    continued = [c for case, c in default.comparisons.items() if case[1] == cold.period]
    admissible = all(c.optimum.gait.usable and c.other.usable for c in continued)
    return (
        f"- **Periods other than {PAPER_PERIOD:g} s** (the paper gives no numbers for them): the planner finds "
        "each alpha sweep's first gait on the human-like branch from the gait atlas (built by continuation from "
        "L = T = 0.45 s), because Newton's method from the straight-line start does not find the human-like gait "
        f"everywhere. From that start at L = {cold.step_length:g} m, T = {cold.period:g} s, "
        f"alpha = {math.degrees(cold.arm_amplitude):g} deg it {outcome}; from the atlas, the tables' gaits at "
        "that period are " + ("admissible." if admissible else "not all admissible.")
    )


def differences(default: Study, table: Study, reference: Reference) -> list[str]:
    """The section "Where the project and the paper differ, and why", from computed numbers:
    ``default`` is the default set's study, ``table`` the table-verbatim set's, ``reference``
    the default set's gaits at the paper's momentum point."""
    optima = default.fig4_optima()
    return [
        _effort_scale(optima),
        _closure(reference, optima),
        _optimal_amplitude(optima),
        _anti_normal_premium(default),
        _table_inertia(default, table),
        _momentum_at_paper_point(reference),
        _other_periods(default, reference),
    ]


def maps_figures(maps: WalkingMaps) -> dict[str, tuple]:
    """Caption -> (figure, file name) of one parameter set's maps (their margins, if any, in both)."""
    name, suffix = maps.params, file_suffix(maps)
    margins = f", margins: {maps.margins}" if maps.margins else ""
    return {
        f"Where walking is possible, parameter set {name}{margins}: the admissible region and its limits": (
            region_figure(maps), f"map-region-{name}{suffix}.png"),
        f"Optimal arm amplitude and least effort over the admissible region, parameter set {name}{margins}": (
            optimum_figure(maps), f"map-optimum-{name}{suffix}.png"),
        f"Anti-normal over normal effort at the optimal alpha, parameter set {name}{margins}": (
            ratio_figure(maps), f"map-ratio-{name}{suffix}.png"),
    }


def _maps_section(all_maps: Sequence[WalkingMaps], figures: dict[str, str]) -> list[str]:
    lines = ["", "## Where walking is possible (maps beyond the paper)", "",
             "The paper studied three points. From the gait atlas (every (L, T, alpha) node solved on the human-like "
             f"branch by continuation, `biped-gait atlas build`) and from optimizations on {all_maps[0].optima_nodes}, "
             "these maps show where an admissible ballistic gait exists, what limits it elsewhere, and how the "
             "optimal arm swing and its effort vary. `biped-gait maps` draws them for any parameter set.", ""]
    for maps in all_maps:
        lines += [f"### Parameter set `{maps.params}`", ""]
        lines += reading(maps)
        lines.append("")
        lines += [f"![{caption}]({path})\n\n*{caption}*\n" for caption, path in figures.items()
                  if path.startswith("map-") and path.endswith(f"-{maps.params}.png")]
    return lines


@dataclass(frozen=True, eq=False)
class Extensions:
    """The page's sections beyond the paper: the maps per parameter set, the stability of the
    paper's gaits, the reviewer's checks, the walk (closed loops, pushes, commanded speed)."""

    maps: Sequence[WalkingMaps] = ()
    stability: Sequence[PointStability] = ()
    reviewer: ReviewerChecks | None = None
    walking: Walking | None = None
    hips: Study | None = None
    turning: Turning | None = None
    pulses: Sequence[PulseRow] = ()
    lasting: LastingStudy | None = None
    lasting_path: Path | None = None  # where the lasting study was looked for (None: no such section)
    actuated: ActuatedStudy | None = None
    actuated_path: Path | None = None  # where the actuated swing's study was looked for (None: no such section)
    spline: dict | None = None  # the kept stop and start by kind (``spline_page.kept_plans``; None: no such sections)


STABILITY_FIGURE = "stability.png"
RATE_FIGURE = "rate-bound.png"


def render(
    studies: Sequence[Study], references: dict[str, Reference], figures: dict[str, str], coarse_step: float,
    extensions: Extensions = Extensions(),
) -> str:
    """The whole page as Markdown. ``studies``: the default set's and the table set's (in
    that order); ``references`` by set name; ``figures`` maps a caption to a path relative to
    the page; ``coarse_step`` (rad) is the study's alpha spacing; ``extensions`` the sections
    beyond the paper (the walk section's figures' paths start with ``walk-``)."""
    default, table = studies
    lines = [
        "# Arm-swing study: results",
        "",
        "Generated by `biped-gait results-page` (docs/cli.md); do not edit by hand, run the command again.",
        "",
        f"For each (L, T) the normal gait's effort W is minimized over the arm amplitude alpha in [0, 45] deg "
        f"(a continuation sweep every {math.degrees(coarse_step):g} deg brackets the minimum, a bounded scalar "
        "minimizer refines it), and the anti-normal gait is solved at the same alpha, as in the paper. "
        "W is in N m s, angular momentum in kg m^2/s, about the vertical through a foot: at T- (before the double "
        "support) about the old stance foot, at T+ (after it) about the new stance foot, as the paper reports them. "
        "The **jump** in the tables is |H(T+) - H(T-)|, both about the new stance foot: what the double support "
        "changes on one fixed axis. The paper's jump is H(T+) about the new stance foot minus H(T-) about the old "
        "one, which also counts the change of reference point; it is compared at the paper's point below. The stance foot of the computed step is the right one; the next step is its mirror image. "
        "Paper: Aoustin and Formal'skii, numbers from docs/model.md section 7 (T = 0.45 s only).",
        "",
        "## Figures",
        "",
    ]
    lines += [f"![{caption}]({path})\n\n*{caption}*\n" for caption, path in figures.items()
              if not path.startswith(("map-", "walk-", "lasting-", "actuated-", f"fig4-{HIPS_PARAMS}"))
              and path not in (STABILITY_FIGURE, RATE_FIGURE, TURNING_FIGURE)]
    for study in studies:
        label = " (default)" if study is default else ""
        lines += ["", f"## Parameter set `{study.params.name}`{label}", "", "Effort of the double support (N m s):",
                  ""]
        lines += _effort_table(study)
        lines += ["", "Yaw angular momentum at the double support of the optimal normal gait and the anti-normal "
                  "gait at the same alpha (kg m^2/s):", ""]
        lines += _momentum_table(study)
    lines += ["", f"## Angular momentum at the paper's point (L = T = 0.45, alpha = {PAPER_ALPHA_DEG} deg)", ""]
    lines += _reference_table(references)
    lines += ["", "## The paper's claims, checked on these numbers"]
    lines += _claims_section(studies)
    lines += ["", "## Where the project and the paper differ, and why", ""]
    lines += differences(default, table, references[default.params.name])
    if extensions.hips is not None:
        lines += ["", "## A joint in each hip: the 13-DOF biped (beyond the paper)", "",
                  f"The paper's conclusion asks for it: `{extensions.hips.params.name}` is the default set with a yaw, "
                  "a roll and a pitch joint in each hip (docs/model.md sections 2.1 and 5.2), all actuated by impulses "
                  "at the double support and free in the single support, 13 coordinates instead of 9, 11 actuated "
                  "joints instead of 7. The same BVP and closure, the same LP with the friction cone. At the paper's "
                  "three points, the 9-DOF default set (first number) beside the 13-DOF set (second); the optimal "
                  "normal gait, the anti-normal one at its amplitude:", ""]
        lines += hips_lines(default, extensions.hips)
        lines += ["", f"![Fig. 4, parameter set {extensions.hips.params.name}]"
                  f"(fig4-{extensions.hips.params.name}.png)", ""]
    if extensions.turning is not None:
        lines += ["", "## Walking on circles (beyond the paper)", "",
                  "The paper's last perspective: with the hips' yaw and roll joints the biped walks curves. On a circle "
                  "of radius R (R > 0 turns left) the periodic orbit is a stride of two steps, periodic modulo a yaw "
                  "rotation of 2 L / R (docs/model.md sections 3.1 and 4.9), planned like the straight gait and walked "
                  "by the simulator (`-p turn_radius:=R`, or `/cmd_vel` angular.z).", ""]
        lines += turning_lines(extensions.turning)
    if extensions.lasting_path is not None:
        lines += ["", LASTING_HEADING, ""]
        lines += lasting_lines(extensions.lasting, extensions.lasting_path)
    if extensions.actuated_path is not None:
        lines += ["", ACTUATED_HEADING, ""]
        lines += actuated_lines(extensions.actuated, extensions.actuated_path)
    for kind, plan in (extensions.spline or {}).items():
        lines += ["", SPLINE_HEADINGS[kind], ""]
        lines += section_lines(kind, *plan)
    if extensions.pulses:
        lines += ["", "## A double support that lasts, walked in MuJoCo (beyond the paper)", "",
                  "The paper's caveat: impulsive torques cannot be realized. In MuJoCo (`engine:=mujoco`, docs/model.md "
                  "section 11) each double support is d seconds of torque pulses, half before and half after the "
                  "touchdown, corrected with the planner's model so that the next step lands where the re-aim aims; "
                  "the default gait, 20 steps, momentum steering, the floor's mu = 0.5. E is the pulses' effort "
                  "(d / 2) sum |u| of the last double support beside the impulses' W there; the contraction per step "
                  "is that of a shove of 1e-4 rad/s on every joint at step 10 (below 1: the closed loop is stable):",
                  ""]
        lines += pulse_lines(list(extensions.pulses))
    if extensions.maps:
        lines += _maps_section(extensions.maps, figures)
    if extensions.stability:
        lines += ["", "## Stability of the gaits (beyond the paper)", "",
                  "Floquet multipliers of the Poincare map just after the double support (docs/model.md section 8): "
                  "open loop, the plan's impulses held fixed; closed loop, what the simulator's walker does (impulses "
                  "re-solved from the actual state, the next step re-aimed), by differences of its step. At the "
                  "paper's three points, the normal gait at its optimal alpha and the anti-normal gait at the same "
                  "alpha:", ""]
        lines += stability_lines(extensions.stability, default.curves)
        lines += ["", f"![Open-loop spectral radius over (L, T)]({STABILITY_FIGURE})", ""]
    if extensions.reviewer is not None:
        lines += reviewer_lines(extensions.reviewer, RATE_FIGURE)
    if extensions.walking is not None:
        lines += walking_section(extensions.walking,
                                 {c: path for c, path in figures.items() if path.startswith("walk-")})
    return "\n".join(lines) + "\n"


def write_results_page(out: Path, executor: Executor, coarse_step: float = COARSE_STEP,
                       walk_alpha_step: float = WALK_ALPHA_STEP,
                       pulse_durations: Sequence[float] = PULSE_DURATIONS,
                       push_directions: Sequence[str] = tuple(STUDY_DIRECTIONS),
                       map_stride: int = MAP_STRIDE) -> list[Path]:
    """Compute the study for both parameter sets (``PARAMETER_SETS``) on ``executor``, write
    the figures beside ``out`` and the page to ``out``; returns the paths written.
    ``walk_alpha_step`` (rad): the alpha spacing of the walk section's closed loops and pushes;
    ``pulse_durations`` (s): the double supports walked in MuJoCo (none: no such section);
    ``push_directions``: the walk section's push directions (names of ``push_study.STUDY_DIRECTIONS``);
    ``map_stride``: the maps' optima on one atlas node in ``map_stride`` along L and T. The lasting
    double support's section reads ``LASTING_STUDY`` beside ``out`` (absent: the page says so)."""
    out = Path(out)
    studies = run_study(executor, [load_params(n) for n in PARAMETER_SETS], TABLE_CASES, coarse_step=coarse_step)
    references = {n: Reference.compute(n) for n in PARAMETER_SETS}
    default = studies[0]
    figures = {
        f"Fig. 4, parameter set {default.params.name}: W against alpha, normal solid, anti-normal dashed":
            (default.fig4(), "fig4.png"),
        f"Fig. 5, parameter set {default.params.name}: yaw angular momentum about the stance foot over two steps, "
        "L = T = 0.45, the normal gait's optimal alpha": (default.fig5(), "fig5.png"),
    }
    for study in studies[1:]:
        figures[f"Fig. 4, parameter set {study.params.name}"] = (study.fig4(), f"fig4-{study.params.name}.png")
    all_maps = [compute_maps(study.params, executor, map_stride, coarse_step) for study in studies]
    for maps in all_maps:
        figures.update(maps_figures(maps))
    extensions = _extensions(default, executor, all_maps, coarse_step, walk_alpha_step, pulse_durations, push_directions)
    figures["Open-loop spectral radius over (L, T)"] = (
        stability_figure(Atlas.load(atlas_path(default.params, GaitMode.NORMAL), default.params)), STABILITY_FIGURE)
    figures["Effort against the joint-rate bound"] = (
        rate_bound_figure(extensions.reviewer.rate_curve, default.params.name), RATE_FIGURE)
    figures.update(walking_figures(extensions.walking, default.params.name))
    figures[f"Fig. 4, parameter set {extensions.hips.params.name}"] = (extensions.hips.fig4(),
                                                                    f"fig4-{extensions.hips.params.name}.png")
    figures["Effort per metre against the turn radius"] = (turning_figure(extensions.turning), TURNING_FIGURE)
    lasting_path = out.parent / LASTING_STUDY
    lasting = LastingStudy.load(lasting_path) if lasting_path.is_file() else None
    actuated_path = out.parent / ACTUATED_STUDY
    actuated = ActuatedStudy.load(actuated_path) if actuated_path.is_file() else None
    spline = kept_plans()
    extensions = replace(extensions, lasting=lasting, lasting_path=lasting_path, actuated=actuated,
                         actuated_path=actuated_path, spline=spline)
    for kind, plan in spline.items():
        figures[f"The {kind}: joint angles, torques and the feet's reactions"] = (section_figure(kind, *plan),
                                                                                 SPLINE_FIGURES[kind])
    figures.update(lasting_figures(lasting))
    if actuated is not None:
        figures["The actuated swing: E against tau and against alpha"] = (actuated_figure(actuated), ACTUATED_FIGURE)
    paths = [save(fig, out.parent / name) for fig, name in figures.values()]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(render(studies, references, {c: name for c, (_, name) in figures.items()}, coarse_step, extensions))
    return [*paths, out]


def _extensions(default: Study, executor: Executor, all_maps: Sequence[WalkingMaps], coarse_step: float,
                walk_alpha_step: float, pulse_durations: Sequence[float], push_directions: Sequence[str]) -> Extensions:
    """The sections beyond the paper, for the default parameter set, computed on ``executor``
    (optima bracketed every ``coarse_step`` rad, the walk's alphas every ``walk_alpha_step``, its
    pushes in ``push_directions``)."""
    params = default.params
    points = [executor.submit(point_stability, params, *case, comparison.optimum.alpha, mode)
              for case, comparison in default.comparisons.items() if case in FIG4_CASES
              for mode in (GaitMode.NORMAL, GaitMode.ANTI_NORMAL)]
    readings = effort_readings(params, executor, coarse_step)
    checks = ReviewerChecks(readings, rate_bound_curve(params, math.radians(PAPER_ALPHA_DEG)),
                            human_comparison(params, coarse_step=coarse_step))
    walking = compute_walking(executor, default, walk_alpha_step, push_directions)
    return Extensions(all_maps, [p.result() for p in points], checks, walking, hips_study(executor, coarse_step),
                      turning_study(executor), pulse_rows(executor, tuple(pulse_durations)))
