"""Sweeps of gaits over grids of step length L (m), period T (s), arm amplitude alpha (rad)
and gait mode, solved by continuation.

The unit of work is a chain (``core.gait.chains``): one (L, T, mode) over the ascending alpha
grid, each gait warm-started from its neighbour's solution. Chains run on any
``concurrent.futures.Executor`` (``studies.executors``). Failed and inadmissible gaits are
results like the others (``converged``/``admissible``/``reasons``), never dropped.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field

from ..core.gait.configurations import GaitMode
from ..core.gait.chains import solve_chain
from .executors import planner_for
from ..core.gait.planner import GaitRequest, validate_request
from ..core.model.params import BipedParams
from ..core.gait.gait import Gait

MAX_CASES = 2000  # a larger sweep must be confirmed (CLI: --yes)


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
