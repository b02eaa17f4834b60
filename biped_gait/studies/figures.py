"""Figures of the arm-swing study, drawn with matplotlib's Agg backend (no display needed).

- ``effort_figure``: W (N m s) against alpha (deg), one colour per (L, T), the normal gait
  solid and the anti-normal gait dashed, optima marked (the paper's Fig. 4; also the sweep's
  per-(L, T) figures); ``period_figure``: W against T, one colour per (L, alpha) (the figures
  of a sweep over periods).
- ``momentum_figure``: the yaw angular momentum (kg m^2/s) about the vertical through the
  current stance foot over two successive steps, normal against anti-normal (Fig. 5).
- ``plan_figure``: one planned step: its joint angles (deg), the ground reaction (N) with its
  friction ratio against the coefficient, and the yaw angular momentum (kg m^2/s).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..core.gait.configurations import GaitMode
from ..core.model.biped import SWING_TIP, BipedModel
from ..core.gait.arm_optimum import ArmOptimum
from ..core.gait.gait import Gait

LINE_STYLES = {GaitMode.NORMAL.value: "-", GaitMode.ANTI_NORMAL.value: "--"}
DPI = 120
MAX_CURVES = 8  # curves of one W-vs-T figure: more cannot be told apart


def _new_figure() -> tuple[Figure, object]:
    fig = Figure(figsize=(9.0, 4.6), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot()


def save(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as PNG to ``path`` (parent folders created); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI)
    return path


def _effort_curves(ax, results: Sequence[Gait], group: Callable[[Gait], tuple],
                   x: Callable[[Gait], float]) -> dict[tuple, str]:
    """W against ``x`` (one curve per ``group`` and mode: normal solid, anti-normal dashed, a
    colour per group); gaits that fail or are not admissible leave gaps, and those with a W are
    marked with a grey x. Returns the colour of each group."""
    colours = {key: f"C{i}" for i, key in enumerate(dict.fromkeys(group(r) for r in results))}
    for key, colour in colours.items():
        for mode, style in LINE_STYLES.items():
            curve = sorted((r for r in results if group(r) == key and r.mode == mode), key=x)
            if not curve:
                continue
            xs = [x(r) for r in curve]
            ax.plot(xs, [r.W if r.usable else np.nan for r in curve], style, marker=".", markersize=3, color=colour)
            bad = [(v, r.W) for v, r in zip(xs, curve) if not r.usable and math.isfinite(r.W)]
            if bad:
                ax.plot(*zip(*bad), "x", color="grey")
    return colours


def _legend(ax, results: Sequence[Gait], colours: dict[tuple, str], label: Callable[[tuple], str],
            extra: Sequence[Line2D] = ()) -> None:
    """A compact legend beside the axes (never over the data): a colour per group, the line
    style per mode, the grey x if any gait is drawn as not admissible, and ``extra`` marks."""
    handles = [Line2D([], [], color=colour, label=label(key)) for key, colour in colours.items()]
    handles += [Line2D([], [], color="k", linestyle=style, label=mode) for mode, style in LINE_STYLES.items()
                if any(r.mode == mode for r in results)]
    if any(not r.usable and math.isfinite(r.W) for r in results):
        handles.append(Line2D([], [], color="grey", marker="x", linestyle="none", label="not admissible (its W)"))
    handles += list(extra)
    if not any(r.usable for r in results):
        ax.text(0.5, 0.5, "no admissible gait", transform=ax.transAxes, ha="center")
    ax.set_ylabel("effort W (N m s)")
    ax.grid(True, alpha=0.3)
    ax.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def effort_figure(results: Sequence[Gait], optima: Sequence[ArmOptimum] = (), title: str = "") -> Figure:
    """W against alpha for every (L, T) in ``results``: normal solid, anti-normal dashed.

    Gaits that fail or are not admissible leave gaps in the curves; those with a W are
    marked with a grey x. Each optimum is marked with a dot (interior minimum) or a ring
    (least W at an end point or admissibility edge: not an optimum).
    """
    fig, ax = _new_figure()
    group = lambda r: (r.step_length, r.period)  # noqa: E731
    label = lambda case: f"L = {case[0]:g} m, T = {case[1]:g} s"  # noqa: E731
    colours = _effort_curves(ax, results, group, lambda r: math.degrees(r.arm_amplitude))
    marks = []
    for opt in optima:
        colour = colours.get((opt.gait.step_length, opt.gait.period), "k")
        face = colour if opt.interior else "none"
        what = "optimum" if opt.interior else f"least W ({opt.where})"
        marks += ax.plot(math.degrees(opt.alpha), opt.W, "o", markersize=7, color=colour, markerfacecolor=face,
                         label=f"{what} {math.degrees(opt.alpha):.1f} deg, W = {opt.W:.2f} N m s")
    ax.set_xlabel("arm amplitude alpha (deg)")
    ax.set_title(title or "Effort of the double support against the arm amplitude")
    _legend(ax, results, colours, label, marks)
    return fig


def period_figure(results: Sequence[Gait], title: str = "") -> Figure:
    """W against the period T for every (L, alpha) in ``results``: normal solid, anti-normal
    dashed; gaits that fail or are not admissible as in ``effort_figure``."""
    fig, ax = _new_figure()
    group = lambda r: (r.step_length, r.arm_amplitude)  # noqa: E731
    label = lambda case: f"L = {case[0]:g} m, alpha = {math.degrees(case[1]):.4g} deg"  # noqa: E731
    colours = _effort_curves(ax, results, group, lambda r: r.period)
    ax.set_xlabel("step period T (s)")
    ax.set_title(title or "Effort of the double support against the step period")
    _legend(ax, results, colours, label)
    return fig


def two_step_momentum(gait: Gait) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) and yaw angular momentum (kg m^2/s) about the vertical through the current
    stance foot over two steps: h(t) on [0, T], then -h(t - T) on [T, 2T] (step 2 is the
    mirror image of step 1, and the mirror changes the sign of yaw momentum).

    The time T appears twice, at the end of step 1 (value at T-, about the old stance foot)
    and at the start of step 2 (value at T+, about the new stance foot).
    """
    t = gait.figures.samples.t
    h = gait.figures.h_vertical
    return np.concatenate([t, t + gait.period]), np.concatenate([h, -h])


def momentum_figure(optimum: Gait, other: Gait) -> Figure:
    """Fig. 5: yaw angular momentum about the stance foot over two steps, both arm modes (the
    optimal gait of one, the other at its alpha)."""
    fig, ax = _new_figure()
    for gait in (optimum, other):
        t, h = two_step_momentum(gait)
        ax.plot(t, h, LINE_STYLES[gait.mode], label=f"{gait.mode}, alpha = {math.degrees(gait.arm_amplitude):.1f} deg")
    ax.axvline(optimum.period, color="grey", linewidth=0.8)
    ax.axhline(0.0, color="grey", linewidth=0.5)
    ax.set_xlabel("time t (s)  (double support at t = T)")
    ax.set_ylabel("yaw angular momentum about the stance foot (kg m^2/s)")
    ax.set_title(f"Two steps, L = {optimum.step_length:g} m, T = {optimum.period:g} s, params {optimum.params}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def skeleton(model: BipedModel, q: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """The biped's segments at configuration ``q`` of the single-support model (m; stance tip at
    the origin): (start, end, part) from each joint to its parent's, the swing shin to its tip,
    and each arm (``part``: 'arm' or 'body')."""
    pin_model, data = model.single, model.single_data
    pin.forwardKinematics(pin_model, data, q)
    pin.updateFramePlacements(pin_model, data)
    segments = []
    for joint in range(2, pin_model.njoints):
        start = data.oMi[pin_model.parents[joint]].translation.copy()
        segments.append((start, data.oMi[joint].translation.copy(), "body"))
        if "shoulder" in pin_model.names[joint]:
            hand = data.oMi[joint].act(np.array([0.0, 0.0, -model.params.arm.length]))
            segments.append((data.oMi[joint].translation.copy(), hand, "arm"))
    knee = pin_model.getJointId("swing_knee")
    segments.append((data.oMi[knee].translation.copy(), data.oMf[pin_model.getFrameId(SWING_TIP)].translation.copy(), "body"))
    return segments


def _draw_skeletons(ax, model: BipedModel, gait: Gait, snapshots: int = 5) -> None:
    """The biped seen from the side (x forward, z up, m) at ``snapshots`` instants of the step."""
    samples = gait.figures.samples
    for k, index in enumerate(np.linspace(0, len(samples.t) - 1, snapshots).round().astype(int)):
        colour = colormaps["viridis"](k / max(1, snapshots - 1))
        for n, (start, end, part) in enumerate(skeleton(model, samples.q[index])):
            ax.plot([start[0], end[0]], [start[2], end[2]], color=colour, linewidth=2.6 if part == "arm" else 1.6,
                    solid_capstyle="round", label=f"t = {samples.t[index]:.2f} s" if n == 0 else None)
    ax.axhline(0.0, color="grey", linewidth=0.8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, forward (m)")
    ax.set_ylabel("z, up (m)")
    ax.set_title("the step from the side (arms thicker)", fontsize="medium")
    ax.legend(fontsize="x-small", loc="upper left")


def plan_figure(gait: Gait, model: BipedModel) -> Figure:
    """The ballistic step of a planned gait over t in [0, T]: the biped from the side at five
    instants (``model``: the planner's), the joint angles (deg), the vertical ground reaction (N)
    and the friction ratio |F_xy| / F_z against the coefficient, the yaw angular momentum about
    the stance foot (kg m^2/s)."""
    fig = Figure(figsize=(14.0, 4.8), layout="constrained")
    FigureCanvasAgg(fig)
    side, angles, reaction, momentum = (fig.add_subplot(1, 4, k + 1) for k in range(4))
    title = (f"L = {gait.step_length:g} m, T = {gait.period:g} s, alpha = {math.degrees(gait.arm_amplitude):.1f} deg, "
             f"{gait.mode}, params {gait.params}: {'admissible' if gait.admissible else 'not admissible'}")
    fig.suptitle(title, fontsize="medium")
    if gait.figures is None or gait.figures.samples is None:
        angles.text(0.5, 0.5, "no converged step", transform=angles.transAxes, ha="center")
        return fig
    _draw_skeletons(side, model, gait)
    t, q, grf = gait.figures.samples.t, gait.figures.samples.q, gait.figures.grf
    for name, column in zip(gait.names.joints, q.T):
        angles.plot(t, np.degrees(column), label=name.replace("_", " "))
    angles.set_ylabel("joint angle (deg)")
    angles.legend(fontsize="xx-small", ncols=3, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    # Both axes from 0, the friction ratio's up to twice the larger of mu and itself: the ground's
    # push (F_z > 0) and the friction used (ratio < mu) each read as a margin, the mu line apart
    # from the curves, not as a bound they reach.
    reaction.plot(t, grf[:, 2], color="C0")
    reaction.set_ylim(min(0.0, 1.1 * float(grf[:, 2].min())), 1.1 * max(float(grf[:, 2].max()), 0.0) or 1.0)
    reaction.set_ylabel("vertical ground reaction F_z (N)", color="C0")
    ratio = reaction.twinx()
    used = np.hypot(grf[:, 0], grf[:, 1]) / grf[:, 2]
    ratio.plot(t, used, color="C3")
    mu = gait.problem.options.friction
    if math.isfinite(mu):
        ratio.axhline(mu, color="C3", linestyle=":", linewidth=1.0)
        ratio.text(0.03, mu, f"mu = {mu:g}, the floor's friction", color="C3", fontsize="small", va="bottom",
                   transform=ratio.get_yaxis_transform())
    top = max(mu if math.isfinite(mu) else 0.0, float(np.nanmax(np.abs(used))) if np.isfinite(used).any() else 0.0)
    ratio.set_ylim(0.0, 2.0 * top or 1.0)
    ratio.set_ylabel("friction ratio |F_xy| / F_z", color="C3")
    h = np.asarray(gait.figures.h_vertical)
    momentum.plot(t, h, color="C2")
    if h.min() <= 0.0 <= h.max():  # the zero line only where the momentum crosses it: the scale shows its variation
        momentum.axhline(0.0, color="grey", linewidth=0.5)
    momentum.set_ylabel("yaw momentum about the stance foot (kg m^2/s)")
    for ax in (angles, reaction, momentum):
        ax.set_xlabel("time in the step t (s)")
        ax.grid(True, alpha=0.3)
    return fig


def sweep_figures(results: Sequence[Gait], out_dir: Path) -> list[Path]:
    """The figures of a sweep in ``out_dir``; returns the paths: ``W_vs_alpha_L{L}_T{T}.png``
    per (L, T) swept over two or more alphas; ``W_vs_T_L{L}.png`` per L swept over two or more
    periods, one curve per alpha (``MAX_CURVES`` of them, evenly spaced, when more were swept);
    if neither, the W-vs-alpha points per (L, T)."""
    def groups(key) -> dict[tuple, list[Gait]]:
        out: dict[tuple, list[Gait]] = {}
        for r in results:
            out.setdefault(key(r), []).append(r)
        return out

    def count(case: list[Gait], field: str) -> int:
        return len({getattr(r, field) for r in case})

    by_alpha = groups(lambda r: (r.step_length, r.period))
    by_length = groups(lambda r: r.step_length)
    periods_swept = any(count(case, "period") > 1 for case in by_length.values())
    paths = []
    for (length, period), case in by_alpha.items():
        if count(case, "arm_amplitude") > 1 or not periods_swept:
            title = f"W against alpha, L = {length:g} m, T = {period:g} s, params {case[0].params}"
            paths.append(save(effort_figure(case, title=title), out_dir / f"W_vs_alpha_L{length:.3f}_T{period:.3f}.png"))
    for length, case in by_length.items():
        if count(case, "period") > 1:
            alphas = sorted({r.arm_amplitude for r in case})
            shown = [alphas[round(k)] for k in np.linspace(0, len(alphas) - 1, min(len(alphas), MAX_CURVES))]
            note = f" ({len(shown)} of {len(alphas)} amplitudes)" if len(shown) < len(alphas) else ""
            title = f"W against T, L = {length:g} m, params {case[0].params}{note}"
            curves = [r for r in case if r.arm_amplitude in shown]
            paths.append(save(period_figure(curves, title=title), out_dir / f"W_vs_T_L{length:.3f}.png"))
    return paths
