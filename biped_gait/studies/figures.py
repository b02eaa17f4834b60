"""Figures of the arm-swing study, drawn with matplotlib's Agg backend (no display needed).

- ``effort_figure``: W (N m s) against alpha (deg), one colour per (L, T), the normal gait
  solid and the anti-normal gait dashed, optima marked (the paper's Fig. 4; also the sweep's
  per-(L, T) figures).
- ``momentum_figure``: the yaw angular momentum (kg m^2/s) about the vertical through the
  current stance foot over two successive steps, normal against anti-normal (Fig. 5).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..core.configurations import GaitMode
from .optimize import ArmOptimum
from ..core.gait import Gait

LINE_STYLES = {GaitMode.NORMAL.value: "-", GaitMode.ANTI_NORMAL.value: "--"}
DPI = 120


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


def effort_figure(results: Sequence[Gait], optima: Sequence[ArmOptimum] = (), title: str = "") -> Figure:
    """W against alpha for every (L, T) in ``results``: normal solid, anti-normal dashed.

    Gaits that fail or are not admissible leave gaps in the curves; those with a W are
    marked with a grey x. Each optimum is marked with a dot (interior minimum) or a ring
    (least W at an end point or admissibility edge: not an optimum).
    """
    fig, ax = _new_figure()
    cases = list(dict.fromkeys((r.step_length, r.period) for r in results))
    colours = {case: f"C{i}" for i, case in enumerate(cases)}
    for (length, period), colour in colours.items():
        for mode, style in LINE_STYLES.items():
            curve = sorted(
                (r for r in results if (r.step_length, r.period, r.mode) == (length, period, mode)),
                key=lambda r: r.arm_amplitude,
            )
            if not curve:
                continue
            alpha = np.degrees([r.arm_amplitude for r in curve])
            ax.plot(alpha, [r.W if r.usable else np.nan for r in curve], style, marker=".", markersize=3,
                    color=colour, label=f"L = {length:g} m, T = {period:g} s, {mode}")
            bad = [(a, r.W) for a, r in zip(alpha, curve) if not r.usable and math.isfinite(r.W)]
            if bad:
                ax.plot(*zip(*bad), "x", color="grey")
    for opt in optima:
        colour = colours.get((opt.gait.step_length, opt.gait.period), "k")
        face = colour if opt.interior else "none"
        what = "optimum" if opt.interior else f"least W ({opt.where})"
        ax.plot(math.degrees(opt.alpha), opt.W, "o", markersize=7, color=colour, markerfacecolor=face,
                label=f"{what} {math.degrees(opt.alpha):.1f} deg, W = {opt.W:.2f}")
    if not any(r.usable for r in results):
        ax.text(0.5, 0.5, "no admissible gait", transform=ax.transAxes, ha="center")
    ax.set_xlabel("arm amplitude alpha (deg)")
    ax.set_ylabel("effort W (N m s)")
    ax.set_title(title or "Effort of the double support against the arm amplitude")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.01, 0.5))
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


def momentum_figure(normal: Gait, anti_normal: Gait) -> Figure:
    """Fig. 5: yaw angular momentum about the stance foot over two steps, both arm modes."""
    fig, ax = _new_figure()
    for gait in (normal, anti_normal):
        t, h = two_step_momentum(gait)
        ax.plot(t, h, LINE_STYLES[gait.mode], label=f"{gait.mode}, alpha = {math.degrees(gait.arm_amplitude):.1f} deg")
    ax.axvline(normal.period, color="grey", linewidth=0.8)
    ax.axhline(0.0, color="grey", linewidth=0.5)
    ax.set_xlabel("time t (s)  (double support at t = T)")
    ax.set_ylabel("yaw angular momentum about the stance foot (kg m^2/s)")
    ax.set_title(f"Two steps, L = {normal.step_length:g} m, T = {normal.period:g} s, params {normal.params}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig


def sweep_figures(results: Sequence[Gait], out_dir: Path) -> list[Path]:
    """One ``W_vs_alpha_L{L}_T{T}.png`` per (L, T) of a sweep in ``out_dir``; returns the paths."""
    paths = []
    for length, period in dict.fromkeys((r.step_length, r.period) for r in results):
        case = [r for r in results if (r.step_length, r.period) == (length, period)]
        name = f"W_vs_alpha_L{length:.3f}_T{period:.3f}.png"
        title = f"W against alpha, L = {length:g} m, T = {period:g} s, params {case[0].params}"
        paths.append(save(effort_figure(case, title=title), out_dir / name))
    return paths
