"""The results page's section on walking circles (the 13-DOF set ``aoustin2013-hips``): the effort
per metre against the turn radius and the speed, the smallest admissible radius, the optimal
arm swing while turning and what the inner and the outer step do (their efforts, arm swings and
the yaw angular momentum at their touchdowns). From the turning atlases (``core.gait.turning_atlas``)
and strides solved at the default gait. L in m, T in s, R in m, angles in rad inside, degrees on
the page; W in N m s, W per metre in N s.
"""

from __future__ import annotations

import math
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure
from scipy.optimize import minimize_scalar

from ..core.gait.atlas import NodeStatus
from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Stride
from ..core.gait.planner import GaitRequest
from ..core.gait.turning_atlas import TurningAtlas, turning_atlas_path
from ..core.model.params import load_params
from .executors import planner_for

TURNING_PARAMS = "aoustin2013-hips"
POINT = (0.45, 0.45)  # (L m, T s) of the strides solved
ALPHA = math.radians(20.0)  # rad: the arm amplitude of the radius table and the maps
RADII = (1.0, 2.0, 5.0, math.inf)  # m
OPTIMUM_CURVATURES = (0.0, 0.25, 0.5)  # 1/m: where the optimal arm swing is found
ALPHA_BOUNDS = (0.0, math.radians(40.0))
ALPHA_TOLERANCE = math.radians(0.25)
FIGURE = "turning-effort.png"


@dataclass(frozen=True)
class StrideFigures:
    """One stride's figures: radius (m), alpha (rad), W of the stride (N m s), per metre (N s),
    admissible and why not, each step's W (N m s; A on the right foot, the outer one of a left
    turn), its shoulders' largest swing (rad) and its yaw angular momentum about the new stance
    foot at T- (kg m^2/s)."""

    radius: float
    alpha: float
    W: float
    per_metre: float
    admissible: bool
    reasons: tuple[str, ...]
    step_W: tuple[float, float]
    arm_swing: tuple[float, float]
    yaw_momentum: tuple[float, float]
    hint: str = ""


def stride_figures(stride: Stride) -> StrideFigures:
    """The figures of a solved stride (a straight gait: ``Stride`` of the same step twice)."""
    steps = stride.steps
    length = stride.problem.step_length
    swings = []
    for gait in steps:  # a stride that did not converge (a radius below the smallest) has no samples: NaN
        names = gait.names.joints
        q = gait.figures.samples.q if gait.figures is not None else None
        swings.append(math.nan if q is None else
                      max(float(np.ptp(q[:, names.index(side)])) for side in ("stance_side_shoulder", "swing_side_shoulder")))
    return StrideFigures(stride.radius, stride.problem.arm_amplitude, stride.W, stride.W / (2 * length),
                         stride.admissible, stride.reasons, tuple(g.W for g in steps), tuple(swings),
                         tuple(g.double_support.h_t_minus[1] if g.double_support is not None else math.nan
                               for g in steps), stride.hint)


def solve_point(radius: float, alpha: float, mode: GaitMode) -> StrideFigures:
    """Worker entry: the stride at ``POINT`` on the circle of ``radius`` (m; inf: the straight
    gait, as a stride of two equal steps) at ``alpha`` (rad) and ``mode``."""
    planner = planner_for(load_params(TURNING_PARAMS))
    request = GaitRequest(*POINT, alpha, mode, turn_radius=radius)
    if math.isinf(radius):
        gait = planner.plan(request)
        return stride_figures(Stride(math.inf, (gait, gait), gait.stability, gait.solve_time_s, gait.found))
    return stride_figures(planner.plan_stride(request, stability=False))


def optimal_alpha(curvature: float, mode: GaitMode) -> StrideFigures:
    """Worker entry: the stride of least W over alpha in ``ALPHA_BOUNDS`` at ``POINT`` and
    ``curvature`` (1/m) (bounded scalar minimization to ``ALPHA_TOLERANCE``)."""
    radius = math.inf if curvature == 0 else 1.0 / curvature
    result = minimize_scalar(lambda alpha: _effort(radius, alpha, mode), bounds=ALPHA_BOUNDS, method="bounded",
                             options={"xatol": ALPHA_TOLERANCE})
    return solve_point(radius, float(result.x), mode)


def _effort(radius: float, alpha: float, mode: GaitMode) -> float:
    figures = solve_point(radius, alpha, mode)
    return figures.W if math.isfinite(figures.W) else 1e6


@dataclass(frozen=True, eq=False)
class Turning:
    """What the section shows: the turning atlases by mode, the strides at ``RADII`` (normal,
    ``ALPHA``), and the optimal strides at ``OPTIMUM_CURVATURES`` by mode."""

    atlases: dict[GaitMode, TurningAtlas]
    radii: list[StrideFigures]
    optima: dict[GaitMode, list[StrideFigures]]


def turning_study(executor: Executor) -> Turning:
    """The section's computations on ``executor`` (the atlases must be current: ``AtlasError``
    says how to rebuild one)."""
    params = load_params(TURNING_PARAMS)
    atlases = {mode: TurningAtlas.load(turning_atlas_path(params, mode), params, TURNING_PARAMS) for mode in GaitMode}
    radii = [executor.submit(solve_point, radius, ALPHA, GaitMode.NORMAL) for radius in RADII]
    optima = {mode: [executor.submit(optimal_alpha, curvature, mode) for curvature in OPTIMUM_CURVATURES]
              for mode in GaitMode}
    return Turning(atlases, [f.result() for f in radii], {m: [f.result() for f in fs] for m, fs in optima.items()})


def _number(value: float, spec: str) -> str:
    """``value`` formatted by ``spec``, or "-" where there is none (NaN: a stride not solved)."""
    return "-" if math.isnan(value) else format(value, spec)


def _radius(radius: float) -> str:
    return "inf" if math.isinf(radius) else f"{radius:.3g}"


def turning_lines(turning: Turning) -> list[str]:
    """The section's tables and reading."""
    length, period = POINT
    lines = [f"Strides at L = {length} m, T = {period} s (v = {length / period:.2f} m/s), alpha = "
             f"{math.degrees(ALPHA):.0f} deg, normal (docs/model.md section 4.9): W of the stride (two steps) and per "
             "metre walked, each step's W (A on the right foot: the outer one of a left turn), the largest swing of "
             "an arm over the step and the yaw angular momentum about the new stance foot before each touchdown:", "",
             "| R (m) | admissible | W stride | W per metre (N s) | W A / B | arm swing A / B (deg) | H(T-) A / B |",
             "|---:|---|---:|---:|---|---|---|"]
    for f in turning.radii:
        verdict = "yes" if f.admissible else "no: " + "; ".join(f.reasons)
        swing = [_number(math.degrees(a), ".1f") for a in f.arm_swing]
        lines.append(f"| {_radius(f.radius)} | {verdict} | {_number(f.W, '.2f')} | {_number(f.per_metre, '.2f')} | "
                     f"{_number(f.step_W[0], '.2f')} / {_number(f.step_W[1], '.2f')} | {swing[0]} / {swing[1]} | "
                     f"{_number(f.yaw_momentum[0], '.3f')} / {_number(f.yaw_momentum[1], '.3f')} |")
    smallest = next((f.hint for f in turning.radii if f.hint), "")
    lines += ["", f"Refused below the smallest radius: {smallest or 'every radius of the table is admissible'}.", ""]
    lines += ["Smallest admissible radius on the turning atlas's grid (every curvature up to it admissible), "
              f"alpha = {math.degrees(ALPHA):.0f} deg, normal, by speed v = L / T:", "",
              "| L (m) | T (s) | v (m/s) | smallest R (m) | W per metre straight / at 1/R = 0.5 (N s) |",
              "|---:|---:|---:|---:|---|"]
    atlas = turning.atlases[GaitMode.NORMAL]
    grid = atlas.grid
    k = int(np.argmin(np.abs(grid.alphas - ALPHA)))
    half = int(np.argmin(np.abs(grid.curvatures - 0.5)))
    for i, j in np.ndindex(len(grid.step_lengths), len(grid.periods)):
        length_ij, period_ij = float(grid.step_lengths[i]), float(grid.periods[j])
        found = atlas.smallest_radius((length_ij, period_ij, float(grid.alphas[k])))
        status = atlas.nodes["status"][i, j, k]
        w = atlas.nodes["W"][i, j, k] / (2 * length_ij)
        straight = f"{w[0]:.2f}" if status[0] == NodeStatus.ADMISSIBLE else "-"
        turned = f"{w[half]:.2f}" if status[half] == NodeStatus.ADMISSIBLE else "-"
        lines.append(f"| {length_ij:.2f} | {period_ij:.2f} | {length_ij / period_ij:.2f} | "
                     f"{_radius(found[0]) if found else 'none'} | {straight} / {turned} |")
    lines += ["", f"The optimal arm swing while turning (least W of the stride over alpha in [0, "
              f"{math.degrees(ALPHA_BOUNDS[1]):.0f}] deg, to {math.degrees(ALPHA_TOLERANCE):g} deg) at L = {length} m, "
              f"T = {period} s:", "",
              "| mode | R (m) | alpha* (deg) | W* stride | W* A / B | arm swing A / B (deg) | H(T-) A / B |",
              "|---|---:|---:|---:|---|---|---|"]
    for mode, optima in turning.optima.items():
        for f in optima:
            lines.append(f"| {mode.value} | {_radius(f.radius)} | {math.degrees(f.alpha):.2f} | {f.W:.2f} | "
                         f"{f.step_W[0]:.2f} / {f.step_W[1]:.2f} | {math.degrees(f.arm_swing[0]):.1f} / "
                         f"{math.degrees(f.arm_swing[1]):.1f} | {f.yaw_momentum[0]:.3f} / {f.yaw_momentum[1]:.3f} |")
    lines += ["", *_reading(turning), "", f"![Effort per metre against the turn radius]({FIGURE})", ""]
    return lines


def _reading(turning: Turning) -> list[str]:
    """What the numbers say, from the numbers."""
    straight = next(f for f in turning.radii if math.isinf(f.radius))
    turned = [f for f in turning.radii if f.admissible and math.isfinite(f.radius)]
    normal = turning.optima[GaitMode.NORMAL]
    anti = turning.optima[GaitMode.ANTI_NORMAL]
    out = []
    if turned:
        tight = min(turned, key=lambda f: f.radius)
        out.append(f"- **Turning costs effort**: W per metre grows from {straight.per_metre:.2f} N s straight to "
                   f"{tight.per_metre:.2f} N s at R = {tight.radius:g} m "
                   f"({100 * (tight.per_metre / straight.per_metre - 1):.0f} % more); W is even in 1/R (a right turn is "
                   "the left one's mirror image) with its minimum at the straight gait.")
        swings = [math.degrees(a) for a in tight.arm_swing]
        same = abs(swings[0] - swings[1]) < 0.05
        arms = (f"the arms swing {swings[0]:.1f} deg peak to peak in both steps (one amplitude per stride: the double "
                "supports' configurations put the shoulders at +-alpha, so the inner and the outer step cannot swing "
                "them differently; two amplitudes per stride would be a further unknown)" if same else
                f"the arms swing {swings[0]:.1f} and {swings[1]:.1f} deg peak to peak")
        out.append(f"- **The inner and the outer step differ**: at R = {tight.radius:g} m the outer step (A) costs "
                   f"{tight.step_W[0]:.2f} and the inner (B) {tight.step_W[1]:.2f} N m s, and the yaw momentum before "
                   f"the touchdowns is {tight.yaw_momentum[0]:.3f} and {tight.yaw_momentum[1]:.3f} kg m^2/s against "
                   f"{straight.yaw_momentum[0]:.3f} straight: the stride carries the turn's yaw rotation, the outer "
                   f"step more of it; {arms}.")
    shift = [math.degrees(f.alpha - normal[0].alpha) for f in normal[1:]]
    out.append(f"- **The optimal arm swing while turning** moves by {', '.join(f'{s:+.2f}' for s in shift)} deg from "
               f"the straight gait's {math.degrees(normal[0].alpha):.2f} deg at R = "
               f"{', '.join(_radius(f.radius) for f in normal[1:])} m (normal swing); the anti-normal swing's optimum "
               f"costs {', '.join(f'{a.W / n.W:.3f}' for a, n in zip(anti, normal))} times the normal one's at the "
               "same radii.")
    return out


def turning_figure(turning: Turning) -> Figure:
    """W per metre against the curvature 1/R at each (L, T) of the turning atlas (alpha =
    ``ALPHA``, normal), admissible strides solid, the rest dotted."""
    atlas = turning.atlases[GaitMode.NORMAL]
    grid = atlas.grid
    k = int(np.argmin(np.abs(grid.alphas - ALPHA)))
    fig = Figure(figsize=(7.0, 4.5))
    ax = fig.add_subplot()
    for i, j in np.ndindex(len(grid.step_lengths), len(grid.periods)):
        length = float(grid.step_lengths[i])
        per_metre = atlas.nodes["W"][i, j, k] / (2 * length)
        ok = atlas.nodes["status"][i, j, k] == NodeStatus.ADMISSIBLE
        line, = ax.plot(grid.curvatures, np.where(ok, per_metre, np.nan), "-",
                        label=f"L = {length:.2f}, T = {float(grid.periods[j]):.2f}")
        ax.plot(grid.curvatures, np.where(ok, np.nan, per_metre), ":", color=line.get_color())
    ax.set_xlabel("curvature 1/R (1/m)")
    ax.set_ylabel("W per metre (N s)")
    ax.set_title(f"{TURNING_PARAMS}: effort per metre on a circle, alpha = {math.degrees(ALPHA):.0f} deg, normal")
    ax.legend(fontsize=6, ncol=3)
    return fig
