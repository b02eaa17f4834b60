"""Sweeps of gaits over grids of step length L (m), period T (s), arm amplitude alpha (rad)
and gait mode, solved by continuation.

The unit of work is a chain: one (L, T, mode) over the ascending alpha grid, each gait
warm-started from its neighbour's solution; a gait that fails from the warm start is solved
again cold, and the gait after a failure starts cold. The first gait starts cold, or, given
a seed period T0, from a continuation in T from T0: Newton's method from the straight-line
start finds the human-like gait near T = 0.45 s but not at every T (at L = 0.45 m,
T = 0.50 s it finds a gait whose swing knee bends backwards). Chains run on any
``concurrent.futures.Executor`` (``biped_gait.executors``). Failed and inadmissible gaits are
results like the others (``converged``/``admissible``/``reasons``), never dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass

import numpy as np

from ..core.configurations import GaitMode
from .executors import planner_for
from ..core.planner import GaitPlanner, GaitRequest, validate_request
from ..core.params import BipedParams
from ..core.settings import DEFAULTS
from ..core.gait import Gait

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
    """One continuation chain: L (m), T (s), mode, the ascending alpha grid (rad), and the
    seed period (s) its first gait is continued from (None: that gait starts cold)."""

    params: BipedParams
    step_length: float
    period: float
    mode: str
    alphas: tuple[float, ...]
    seed_period: float | None = None


@dataclass(frozen=True)
class SweepGrid:
    """The cases of a sweep: every combination of L (m), T (s), mode and alpha (rad); each
    chain's first gait continued in T from ``seed_period`` (s) if given."""

    params: BipedParams
    step_lengths: tuple[float, ...]
    periods: tuple[float, ...]
    alphas: tuple[float, ...]
    modes: tuple[str, ...]
    seed_period: float | None = None

    @classmethod
    def build(
        cls,
        params: BipedParams,
        step_lengths: Sequence[float],
        periods: Sequence[float],
        alphas: Sequence[float],
        modes: Sequence[str],
        seed_period: float | None = None,
        confirmed: bool = False,
    ) -> "SweepGrid":
        """Check and normalize a grid: duplicates removed, alphas ascending, mode names parsed.

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
            seed_period=seed_period,
        )
        if grid.size > MAX_CASES and not confirmed:
            raise ValueError(f"the sweep has {grid.size} cases (more than {MAX_CASES}): confirm to run it (--yes)")
        for chain in grid.chains():
            for period in {chain.period} if chain.seed_period is None else {chain.period, chain.seed_period}:
                for alpha in (chain.alphas[0], chain.alphas[-1]):
                    validate_request(GaitRequest(chain.step_length, period, alpha, chain.mode), params)
        return grid

    @property
    def size(self) -> int:
        """Number of gaits in the sweep."""
        return len(self.step_lengths) * len(self.periods) * len(self.modes) * len(self.alphas)

    def chains(self) -> list[Chain]:
        """The continuation chains, in grid order (L, then T, then mode)."""
        return [
            Chain(self.params, length, period, mode, self.alphas, self.seed_period)
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
            "seed_period_s": self.seed_period,
            "cases": self.size,
        }


def solve_near(planner: GaitPlanner, request: GaitRequest, guess: tuple[np.ndarray, float] | None) -> Gait:
    """Solve from ``guess`` (a neighbour's solution); if that fails, solve again cold."""
    result = planner.plan(request, guess=guess)
    if guess is not None and not result.converged:
        result = planner.plan(request)
    return result


def continue_in_period(
    planner: GaitPlanner, step_length: float, period_from: float, period_to: float, alpha: float, mode: str
) -> tuple[np.ndarray, float] | None:
    """A warm start for the gait at ``period_to`` (s), reached by continuation in T from the
    gait at ``period_from`` (solved cold) in steps of at most ``DEFAULTS.period_step``; L in m, alpha in
    rad. None if the last gait before ``period_to`` fails."""
    count = max(1, math.ceil(abs(period_to - period_from) / DEFAULTS.period_step))
    guess = None
    for period in np.linspace(period_from, period_to, count + 1)[:-1]:
        guess = solve_near(planner, GaitRequest(step_length, float(period), alpha, mode), guess).warm_start()
    return guess


def solve_chain(
    planner: GaitPlanner,
    step_length: float,
    period: float,
    mode: str,
    alphas: Sequence[float],
    seed_period: float | None = None,
    on_result: Callable[[Gait], None] | None = None,
) -> list[Gait]:
    """The gaits at L (m), T (s), mode over ascending ``alphas`` (rad), by continuation; the
    first continued in T from ``seed_period`` (s) if given, else solved cold. ``on_result`` is
    called with each gait as it is solved (an exception it raises stops the chain)."""
    results: list[Gait] = []
    guess = None
    if seed_period is not None and seed_period != period:
        guess = continue_in_period(planner, step_length, seed_period, period, alphas[0], mode)
    for alpha in alphas:
        result = solve_near(planner, GaitRequest(step_length, period, alpha, mode), guess)
        guess = result.warm_start()
        results.append(result)
        if on_result is not None:
            on_result(result)
    return results


def run_chain(chain: Chain) -> list[Gait]:
    """Worker entry: solve one chain with this worker's planner; results without their samples."""
    results = solve_chain(
        planner_for(chain.params), chain.step_length, chain.period, chain.mode, chain.alphas, chain.seed_period
    )
    return [result.without_samples() for result in results]


def solve_grid(grid: SweepGrid, executor: Executor) -> Iterator[tuple[int, list[Gait]]]:
    """Submit every chain of ``grid``; yield (chain index in grid order, its gaits) as chains finish."""
    futures = {executor.submit(run_chain, chain): index for index, chain in enumerate(grid.chains())}
    for future in as_completed(futures):
        yield futures[future], future.result()
