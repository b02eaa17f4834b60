"""What a reviewer of the paper would check about the effort W (docs/model.md section 4.4):
the friction cone on the double support's reaction impulses, a bound on the joint rates the
impulses drive between the sub-phases, and the paper's reading of the effort (joint angles or
absolute link angles), at the paper's three points (T = 0.45 s, L = 0.40, 0.45, 0.50 m).

W in N m s, alpha in rad, joint rates in rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..core.model.params import BipedParams
from ..core.gait.planner import GaitRequest
from .executors import planner_for
from ..core.gait.arm_optimum import COARSE_STEP
from .mode_comparison import ModeComparison, compare_modes

PAPER_POINTS = ((0.40, 0.45), (0.45, 0.45), (0.50, 0.45))  # (L m, T s)
# The readings compared: label -> GaitRequest fields.
READINGS = {
    "joint angles, friction cone mu = 0.5 (default)": {},
    "joint angles, no friction cone": {"friction": math.inf},
    "absolute angles, no friction cone": {"effort_coordinates": "absolute", "friction": math.inf},
    "absolute angles, friction cone mu = 0.5": {"effort_coordinates": "absolute"},
}
RATE_BOUNDS = (math.inf, 30.0, 25.0, 20.0, 15.0, 12.0, 10.0, 8.0)  # rad/s


@dataclass(frozen=True, eq=False)
class Readings:
    """Per reading (``READINGS``' labels), the mode comparison at each of ``PAPER_POINTS``."""

    params: str
    comparisons: dict[str, list[ModeComparison]]


def effort_readings(params: BipedParams, executor: Executor, coarse_step: float = COARSE_STEP) -> Readings:
    """The optimal normal gait (alpha bracketed every ``coarse_step`` rad) and the anti-normal
    gait at its alpha, for every reading and paper point, as tasks on ``executor``."""
    futures = {label: [executor.submit(compare_modes, params, length, period, coarse_step=coarse_step, options=options)
                       for length, period in PAPER_POINTS]
               for label, options in READINGS.items()}
    return Readings(params.name, {label: [f.result() for f in tasks] for label, tasks in futures.items()})


def rate_bound_curve(params: BipedParams, alpha: float, bounds: Sequence[float] = RATE_BOUNDS,
                     point: tuple[float, float] = (0.45, 0.45)) -> list[tuple[float, float, float]]:
    """(bound rad/s, W N m s, largest intermediate joint rate rad/s) of the normal gait at
    ``point`` (L m, T s) and ``alpha`` (rad) as the joint-rate bound tightens (W NaN where the
    bounded problem has no solution)."""
    planner = planner_for(params)
    out = []
    for bound in bounds:
        gait = planner.plan(GaitRequest(*point, alpha, rate_bound=bound))
        rate = gait.double_support.max_intermediate_joint_rate if gait.double_support else math.nan
        out.append((bound, gait.W, rate))
    return out


def rate_bound_figure(curve: Sequence[tuple[float, float, float]], params: str) -> Figure:
    """W against the joint-rate bound (the unbounded gait's largest rate marked)."""
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    finite = [(b, w) for b, w, _ in curve if math.isfinite(b) and math.isfinite(w)]
    unbounded = next((w, r) for b, w, r in curve if not math.isfinite(b))
    ax.plot([b for b, _ in finite], [w for _, w in finite], "o-", label="W with the bound")
    ax.axhline(unbounded[0], color="grey", linestyle="--", label=f"no bound (largest rate {unbounded[1]:.1f} rad/s)")
    ax.invert_xaxis()
    ax.set_xlabel("bound on the joint rates between the sub-phases (rad/s)")
    ax.set_ylabel("W (N m s)")
    ax.set_title(f"Effort as the joint-rate bound tightens, L = T = 0.45, params {params}", fontsize="medium")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    return fig
