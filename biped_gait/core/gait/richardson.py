"""A plan's estimate of its own integration error (``accuracy.IntegrationError``), by Richardson's
extrapolation over the two grids it has (docs/model.md section 4.11).

The plan is solved on its grid of N RK8 steps per T; the same step is solved again on the coarse
grid of N / r steps (Newton's, r = 2), from the plan's own solution (one Newton iteration), with
its double support and figures (a plan refined from one on that grid is compared with it; a plan
whose end point already misses the contract is refined without its figures' estimate). A figure whose error is C h^p on a grid of step h errs by r^p
times more on the coarse grid, so the plan's own error is about (coarse - plan) / (r^p - 1):
p = 8 for the RK8 grid's end state and what the BVP's solution and the double support make of it,
p = 5 for what is read from the quintic Hermite samples between the nodes (``accuracy.FIGURES``).
The end point: the flow from the plan's start on both grids, its exact end extrapolated the same
way and measured from q_T. Measured against grids of 256 steps on five gaits of the default
parameter set (docs/model.md section 4.11), that extrapolation is within a factor 3 of the true
error from 16 steps on (7 at 8 steps, whose coarse grid of 4 is not yet in the asymptotic range):
the estimate takes it ``SAFETY`` times over, a bound.
"""

from __future__ import annotations

import numpy as np

from .accuracy import FIGURES, GRID_ORDER, SAMPLE_ORDER, SAMPLED, IntegrationError, relative_error
from .gait import Gait
from .views import FIELD_BY_KEY

SAFETY = 4.0  # the estimate over the extrapolated error


def _shrink(ratio: float, order: int) -> float:
    """What of two grids' difference is the finer one's error, ``SAFETY`` times over."""
    return SAFETY / (ratio ** order - 1.0)


def end_point(plan: Gait, coarse_end: np.ndarray, ratio: float) -> float:
    """How far the exact flow from ``plan``'s start ends from its q_T (rad), from ``coarse_end``,
    q(T) of the flow from there on a grid ``ratio`` times coarser."""
    end = plan.step.nodes[1][-1]
    return float(np.max(np.abs(end - plan.step.q_target) + np.abs(end - coarse_end) * _shrink(ratio, GRID_ORDER)))


def estimate(plan: Gait, coarse: Gait | None, coarse_end: np.ndarray, ratio: float) -> IntegrationError:
    """The integration error of ``plan`` (solved on a grid of ``plan.step.nodes``' steps) from
    ``coarse``, the same step solved on a grid ``ratio`` times coarser, and ``coarse_end``, q(T)
    (rad) of the coarse grid's flow from the plan's start; ``coarse`` None: the end point's alone,
    the figures not estimated (NaN)."""
    steps = len(plan.step.nodes[0]) - 1
    if coarse is None:
        return IntegrationError(end_point(plan, coarse_end, ratio), np.nan, np.nan, np.nan, steps)
    figures = max(relative_error(FIELD_BY_KEY[key].read(plan), FIELD_BY_KEY[key].read(coarse)) * _shrink(ratio, order)
                  for key, order in FIGURES.items())
    drawn, coarse_drawn = FIELD_BY_KEY["trajectory"].read(plan), FIELD_BY_KEY["trajectory"].read(coarse)
    sampled = max(relative_error(drawn[key], coarse_drawn.get(key, np.nan)) for key in SAMPLED)
    return IntegrationError(
        end_point=end_point(plan, coarse_end, ratio),
        W=relative_error(plan.W, coarse.W) * _shrink(ratio, GRID_ORDER),
        figures=figures,
        samples=sampled * _shrink(ratio, SAMPLE_ORDER),
        steps=steps,
    )
