"""Plots of a walk recording (PNG, matplotlib's Agg canvas): the joint angles over the steps,
the yaw angular momentum about the stance foot over two successive steps with the double
support marked (the paper's Fig. 5), and the centre of mass and the stance feet seen from
above. Angles in degrees, times in s from the walk's first sample (its start), lengths in m,
angular momentum in kg m^2/s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from .summaries import WalkRecording

LEG_JOINTS = ("hip", "knee")  # joint-name parts drawn in the legs' panel; the others in the upper body's
DPI = 120


def _mark_touchdowns(ax, touchdowns: list[tuple[float, Any]], offset: float = 0.0, label: str = "touchdown") -> None:
    for i, (t, _) in enumerate(touchdowns):
        ax.axvline(t - offset, color="grey", linestyle=":", linewidth=1.0, label=label if i == 0 else None)


def _joint_figure(fig, walk: WalkRecording) -> None:
    """Joint angles (deg) against time, legs above, torso and arms below, touchdowns dotted."""
    legs, upper = fig.subplots(2, 1, sharex=True)
    angles = np.degrees(np.array(walk.joint_positions))
    for j, name in enumerate(walk.joint_names):
        ax = legs if any(part in name for part in LEG_JOINTS) else upper
        ax.plot(walk.joint_time, angles[:, j], label=name)
    for ax, what in ((legs, "legs"), (upper, "torso and arms")):
        _mark_touchdowns(ax, walk.touchdowns())
        ax.set_ylabel(f"{what}: angle (deg)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.01, 0.5))
    upper.set_xlabel("time from the walk's start, its first sample (s)")
    legs.set_title(f"Joint angles over {len(walk.touchdowns())} steps")


def _momentum_figure(fig, walk: WalkRecording) -> None:
    """Yaw angular momentum about the stance foot over the first two successive steps, the
    double support (instantaneous, at the touchdown) marked; time from the first step's start."""
    ax = fig.add_subplot()
    starts = walk.step_starts()
    first = next((s for s in starts if s + 1 in starts), min(starts))
    shown = [s for s in (first, first + 1) if s in starts]
    step, t, h = np.array(walk.momentum_step), np.array(walk.momentum_time), np.array(walk.yaw_about_foot)
    t0 = starts[first][0]
    for i, s in enumerate(shown):  # one line per step: the jump at the double support stays a jump
        ax.plot(t[step == s] - t0, h[step == s], color=f"C{i}", label=f"step {s}, {starts[s][1]} stance")
    ends = [(td, e) for td, e in walk.touchdowns() if e.step in shown]
    _mark_touchdowns(ax, ends, offset=t0, label="double support (touchdown)")
    ax.axhline(0.0, color="grey", linewidth=0.5)
    ax.set_xlabel(f"time from the start of step {first} (s)")
    ax.set_ylabel("yaw angular momentum about the stance foot (kg m^2/s)")
    ax.set_title(f"Yaw angular momentum, steps {' and '.join(str(s) for s in shown)}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")


def _top_view_figure(fig, walk: WalkRecording) -> None:
    """The centre of mass's path and the stance feet, x-y plane of the world (m); the y axis
    spans the data (a walk is metres long and centimetres wide: at equal scales its sway would
    be a flat line), as its label says."""
    ax = fig.add_subplot()
    com = np.array(walk.com)
    ax.plot(com[:, 0], com[:, 1], color="C0", label="centre of mass")
    starts = walk.step_starts()
    for side, marker, colour in (("right", "s", "C1"), ("left", "o", "C2")):
        feet = {step: foot for step, (_, stance, foot) in starts.items() if stance == side}
        if feet:
            ax.plot([f[0] for f in feet.values()], [f[1] for f in feet.values()], marker, color=colour,
                    linestyle="none", label=f"{side} stance foot")
        for step, foot in feet.items():
            ax.annotate(f"step {step}", foot[:2], textcoords="offset points", xytext=(4, 4), fontsize="small")
    ys = np.concatenate([com[:, 1], [foot[1] for _, _, foot in starts.values()]])
    pad = 0.15 * float(np.ptp(ys)) + 0.01
    ax.set_ylim(float(ys.min()) - pad, float(ys.max()) + pad)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m, scale stretched)")
    ax.set_title("Centre of mass and stance feet, seen from above")
    ax.grid(True, alpha=0.3)
    fig.legend(fontsize="small", loc="outside lower center", ncols=3)  # below: the feet's labels fill the plot


def write_plots(walk: WalkRecording, out_dir: Path) -> list[Path]:
    """The walk's PNG plots in ``out_dir`` (those its data allow); returns their paths."""
    plots = []
    if walk.joint_time:
        plots.append(("joint_angles.png", _joint_figure, (9.0, 6.5)))
    if walk.momentum_time:
        plots.append(("yaw_momentum_two_steps.png", _momentum_figure, (9.0, 4.6)))
        plots.append(("com_feet_top_view.png", _top_view_figure, (9.0, 4.6)))
    paths = []
    for name, draw, size in plots:
        fig = Figure(figsize=size, layout="constrained")
        draw(fig, walk)
        fig.savefig(out_dir / name, dpi=DPI)
        paths.append(out_dir / name)
    return paths
