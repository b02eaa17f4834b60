"""Chains of gaits: one (L m, T s, mode) over ascending arm amplitudes alpha (rad), each gait
warm-started from its neighbours' solutions (the secant through the last two), the first one,
one whose warm start fails and the one after a failure found by the planner on the human-like
branch (gait atlas, then continuation: ``GaitPlanner.plan``); and the checked inclusive ranges
their axes (and a sweep's) are made of. Failed and inadmissible gaits are results like the
others (``converged``/``admissible``/``reasons``), never dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from .gait import Gait
from .planner import GaitPlanner, GaitRequest

MAX_AXIS_VALUES = 100_000  # values one range may produce


def inclusive_range(start: float, stop: float, step: float, what: str) -> tuple[float, ...]:
    """start, start + step, ... up to stop inclusive (within 1e-9 of a step), in any unit.

    Raises ``ValueError`` for a step that is not positive, an inverted range (stop < start)
    or one of more than ``MAX_AXIS_VALUES`` values; ``what`` names the range in the message.
    """
    values = [start, stop, step]
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"{what} range must be finite numbers, got {start:g} {stop:g} {step:g}")
    if step <= 0:
        raise ValueError(f"{what} range step must be positive, got {step:g}")
    if stop < start:
        raise ValueError(f"{what} range is inverted: stop {stop:g} is below start {start:g}")
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count > MAX_AXIS_VALUES:
        raise ValueError(f"{what} range has {count} values (more than {MAX_AXIS_VALUES})")
    return tuple(float(v) for v in np.round(start + step * np.arange(count), 12))


def solve_near(planner: GaitPlanner, request: GaitRequest, guess: tuple[np.ndarray, float] | None) -> Gait:
    """Solve from ``guess`` (a neighbour's solution); without one, or if that fails, let the
    planner find the gait on the human-like branch."""
    if guess is not None:
        result = planner.plan(request, guess=guess)
        if result.converged:
            return result
    return planner.plan(request)


def solve_chain(
    planner: GaitPlanner,
    step_length: float,
    period: float,
    mode: str,
    alphas: Sequence[float],
    on_result: Callable[[Gait], None] | None = None,
    options: Mapping[str, object] | None = None,
) -> list[Gait]:
    """The gaits at L (m), T (s), mode over ascending ``alphas`` (rad), by continuation from the
    first, which the planner finds; each warm start extrapolated (secant) from the two gaits
    before it. ``on_result`` is called with each gait as it is solved (an exception it raises
    stops the chain); ``options`` are further fields of each ``GaitRequest`` (friction,
    rate_bound, effort_coordinates)."""
    results: list[Gait] = []
    for k, alpha in enumerate(alphas):
        request = GaitRequest(step_length, period, alpha, mode, **(options or {}))
        result = solve_near(planner, request, _secant_start(results, alphas[:k], alpha))
        results.append(result)
        if on_result is not None:
            on_result(result)
    return results


def _secant_start(results: Sequence[Gait], alphas: Sequence[float], alpha: float) -> tuple[np.ndarray, float] | None:
    """The warm start at ``alpha`` from the chain's gaits so far (at ``alphas``, rad): the secant
    through the last two if both converged, else the last one's solution, else None."""
    if not results or not results[-1].converged:
        return None
    last = results[-1].warm_start()
    if len(results) < 2 or not results[-2].converged:
        return last
    before = results[-2].warm_start()
    ratio = (alpha - alphas[-1]) / (alphas[-1] - alphas[-2])
    return last[0] + ratio * (last[0] - before[0]), last[1] + ratio * (last[1] - before[1])
