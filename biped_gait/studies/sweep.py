"""Sweeps of gaits over grids of step length L (m), period T (s), arm amplitude alpha (rad)
and gait mode, solved by continuation.

The unit of work is a chain: one (L, T, mode) over the ascending alpha grid, each gait
warm-started from its neighbour's solution. The first gait, a gait whose warm start fails, and
the gait after a failure are found by the planner on the human-like branch (gait atlas, then
continuation: ``GaitPlanner.plan``). Chains run on any ``concurrent.futures.Executor``
(``studies.executors``). Failed and inadmissible gaits are results like the others
(``converged``/``admissible``/``reasons``), never dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field

import numpy as np

from ..core.gait.configurations import GaitMode
from .executors import planner_for
from ..core.gait.planner import GaitPlanner, GaitRequest, validate_request
from ..core.model.params import BipedParams
from ..core.gait.gait import Gait

MAX_CASES = 2000  # a larger sweep must be confirmed (CLI: --yes)
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


@dataclass(frozen=True)
class Chain:
    """One continuation chain: L (m), T (s), mode and the ascending alpha grid (rad), with the
    further ``GaitRequest`` fields of every gait (``options``: friction, margins, ...)."""

    params: BipedParams
    step_length: float
    period: float
    mode: str
    alphas: tuple[float, ...]
    options: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class SweepGrid:
    """The cases of a sweep: every combination of L (m), T (s), mode and alpha (rad), each gait
    with the further ``GaitRequest`` fields ``options``."""

    params: BipedParams
    step_lengths: tuple[float, ...]
    periods: tuple[float, ...]
    alphas: tuple[float, ...]
    modes: tuple[str, ...]
    options: Mapping[str, object] = field(default_factory=dict)

    @classmethod
    def build(
        cls,
        params: BipedParams,
        step_lengths: Sequence[float],
        periods: Sequence[float],
        alphas: Sequence[float],
        modes: Sequence[str],
        confirmed: bool = False,
        options: Mapping[str, object] | None = None,
    ) -> "SweepGrid":
        """Check and normalize a grid: duplicates removed, alphas ascending, mode names parsed;
        ``options``: further ``GaitRequest`` fields of every gait.

        Raises ``ValueError`` (one line) for an empty axis, an unknown mode, a value the gait
        problem refuses, or more than ``MAX_CASES`` cases unless ``confirmed``.
        """
        axes = {"step length": step_lengths, "period": periods, "arm amplitude": alphas, "gait mode": modes}
        for name, values in axes.items():
            if len(values) == 0:
                raise ValueError(f"no {name} given: the sweep would be empty")
        grid = cls(
            params=params,
            step_lengths=tuple(dict.fromkeys(float(v) for v in step_lengths)),
            periods=tuple(dict.fromkeys(float(v) for v in periods)),
            alphas=tuple(sorted(set(float(v) for v in alphas))),
            modes=tuple(dict.fromkeys(GaitMode.parse(m).value for m in modes)),
            options=dict(options or {}),
        )
        if grid.size > MAX_CASES and not confirmed:
            raise ValueError(f"the sweep has {grid.size} cases (more than {MAX_CASES}): confirm to run it (--yes)")
        for chain in grid.chains():
            for alpha in (chain.alphas[0], chain.alphas[-1]):
                validate_request(GaitRequest(chain.step_length, chain.period, alpha, chain.mode, **chain.options), params)
        return grid

    @property
    def size(self) -> int:
        """Number of gaits in the sweep."""
        return len(self.step_lengths) * len(self.periods) * len(self.modes) * len(self.alphas)

    def chains(self) -> list[Chain]:
        """The continuation chains, in grid order (L, then T, then mode)."""
        return [
            Chain(self.params, length, period, mode, self.alphas, self.options)
            for length in self.step_lengths
            for period in self.periods
            for mode in self.modes
        ]

    def describe(self) -> dict:
        """The grid as JSON-ready values (alpha in degrees, as users give it)."""
        return {
            "params": self.params.name,
            "step_length_m": list(self.step_lengths),
            "period_s": list(self.periods),
            "arm_amplitude_deg": [round(math.degrees(a), 9) for a in self.alphas],
            "modes": list(self.modes),
            "options": dict(self.options),
            "cases": self.size,
        }


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
        result = solve_near(planner, request, predict(results, alphas[:k], alpha))
        results.append(result)
        if on_result is not None:
            on_result(result)
    return results


def predict(results: Sequence[Gait], alphas: Sequence[float], alpha: float) -> tuple[np.ndarray, float] | None:
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


def run_chain(chain: Chain) -> list[Gait]:
    """Worker entry: solve one chain with this worker's planner; results without their samples."""
    results = solve_chain(planner_for(chain.params), chain.step_length, chain.period, chain.mode, chain.alphas,
                          options=chain.options)
    return [result.without_samples() for result in results]


def solve_grid(grid: SweepGrid, executor: Executor) -> Iterator[tuple[int, list[Gait]]]:
    """Submit every chain of ``grid``; yield (chain index in grid order, its gaits) as chains finish."""
    futures = {executor.submit(run_chain, chain): index for index, chain in enumerate(grid.chains())}
    for future in as_completed(futures):
        yield futures[future], future.result()
