"""Building a gait atlas (``core.gait.atlas``) by continuation from the known human-like gait.

1. The spine: the human-like gait at L = T = 0.45 s (the straight-line cold start finds it
   there), continued in alpha to every alpha of the grid at that (L, T) node.
2. One task per alpha (run on any ``concurrent.futures.Executor``, local processes or Dask): a
   breadth-first walk over the (L, T) plane from the spine's node, each node solved warm from an
   already solved neighbour on the branch; where the direct warm start fails or leaves the
   branch, a continuation with step halving (``core.gait.continuation``) bridges the gap.
3. Nodes the walk does not reach are solved cold: a human-like result counts by its verdict, a
   backward-knee one marks the node TWIN_ONLY, none NO_CONVERGENCE.

L in m, T in s, alpha in rad.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, replace

import numpy as np

from ..core.gait.admissibility import KNEE_TOLERANCE, Limit
from ..core.gait.atlas import Atlas, Grid, NodeStatus
from ..core.gait.configurations import GaitMode
from ..core.gait.bvp import StepProblem
from ..core.gait.continuation import BRANCH_JUMP, continue_to
from ..core.gait.gait import Gait
from ..core.model.params import BipedParams
from ..core.gait.planner import SEED, GaitPlanner, GaitRequest
from .executors import planner_for

NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1))


@dataclass
class Slab:
    """The nodes of one alpha (index ``k``) of the grid: arrays shaped (L, T) + the node's tail."""

    k: int
    nodes: dict[str, np.ndarray]


def node_record(gait: Gait | None, on_branch: bool) -> dict[str, object]:
    """The atlas values of one node from its solved gait (None: nothing converged)."""
    if gait is None or not gait.converged:
        return {"status": NodeStatus.NO_CONVERGENCE, "limits": Limit.NO_CONVERGENCE}
    if not on_branch:
        return {"status": NodeStatus.TWIN_ONLY, "limits": gait.verdict.limits}
    record: dict[str, object] = {
        "status": NodeStatus.ADMISSIBLE if gait.admissible else NodeStatus.INADMISSIBLE,
        "limits": gait.verdict.limits, "qd_a": gait.step.qd_a, "theta": gait.theta, "W": gait.W,
        "grid_steps": gait.accuracy.steps if gait.meets_contract else 0,
    }
    if gait.figures is not None:
        f = gait.figures
        record.update(min_grf_z=f.min_grf_z, min_swing_height=f.min_swing_height,
                      max_friction_ratio=f.max_friction_ratio, q9_min=f.q9_min,
                      min_late_swing_height=f.min_late_swing_height, swing_arrival_speed=f.swing_arrival_speed)
    if gait.double_support is not None:
        record.update(h_t_minus=gait.double_support.h_t_minus, h_t_plus=gait.double_support.h_t_plus)
    if gait.stability is not None:
        record["spectral_radius"] = gait.stability.spectral_radius
    return record


def spine(planner: GaitPlanner, mode: GaitMode, grid: Grid, options: Mapping[str, object] | None = None
          ) -> tuple[tuple[int, int], list[Gait | None]]:
    """The (L, T) node nearest to ``SEED`` and the human-like gaits there at every alpha of the
    grid (None where the path fails), by continuation in alpha from the cold-started seed;
    ``options``: further ``GaitRequest`` fields of every gait."""
    options = options or {}
    i = int(np.argmin(np.abs(grid.step_lengths - SEED[0])))
    j = int(np.argmin(np.abs(grid.periods - SEED[1])))
    seed = planner.plan(GaitRequest(*SEED, mode, **options), cold=True)
    node = (float(grid.step_lengths[i]), float(grid.periods[j]))
    gaits = []
    for alpha in grid.alphas:
        guess = continue_to(planner.hybrid, planner.coarse_flow or planner.flow, planner.settings, SEED,
                            seed.warm_start(), StepProblem(*node, float(alpha), mode, seed.problem.closure)
                            ) if seed.converged else None
        gait = planner.plan(GaitRequest(*node, float(alpha), mode, **options), guess) if guess is not None else None
        gaits.append(gait if gait is not None and gait.converged else None)
    return (i, j), gaits


def _solve_from(planner: GaitPlanner, grid: Grid, k: int, mode: GaitMode, source: tuple[int, int], gait: Gait,
                target: tuple[int, int], options: Mapping[str, object]) -> Gait | None:
    """The gait at node ``target`` (of alpha index ``k``) from the solved ``gait`` at ``source``,
    on its branch: warm start, else continuation; None if neither stays on the branch;
    ``options``: further ``GaitRequest`` fields."""
    alpha = float(grid.alphas[k])
    point = (float(grid.step_lengths[target[0]]), float(grid.periods[target[1]]), alpha)
    request = GaitRequest(point[0], point[1], alpha, mode, **options)
    result = planner.plan(request, gait.warm_start())
    if _stays(result, gait):
        return result
    start = (float(grid.step_lengths[source[0]]), float(grid.periods[source[1]]), alpha)
    guess = continue_to(planner.hybrid, planner.coarse_flow or planner.flow, planner.settings, start,
                        gait.warm_start(), StepProblem(*point, mode, gait.problem.closure))
    if guess is None:
        return None
    result = planner.plan(request, guess)
    return result if result.converged else None


def _stays(result: Gait, origin: Gait) -> bool:
    """Whether ``result`` is on ``origin``'s branch (qd(0) within the continuation's jump bound)."""
    return result.converged and float(np.max(np.abs(result.step.qd_a - origin.step.qd_a))) <= BRANCH_JUMP


def build_slab(params: BipedParams, mode: GaitMode, grid: Grid, k: int, start: tuple[int, int], seed_guess,
               options: Mapping[str, object] | None = None) -> Slab:
    """Worker entry: every (L, T) node at alpha index ``k``, walked breadth-first from ``start``
    whose gait is solved from ``seed_guess`` (qd(0), theta); ``options``: further ``GaitRequest``
    fields of every gait."""
    options = options or {}
    planner = planner_for(params)
    shape = grid.shape[:2]
    empty = Atlas.empty(params, mode, Grid(grid.step_lengths, grid.periods, grid.alphas[k:k + 1]))
    nodes = {name: array[:, :, 0] for name, array in empty.nodes.items()}
    alpha = float(grid.alphas[k])
    first = planner.plan(GaitRequest(float(grid.step_lengths[start[0]]), float(grid.periods[start[1]]), alpha, mode,
                                     **options), seed_guess)
    solved: dict[tuple[int, int], Gait] = {}
    queue: deque[tuple[int, int]] = deque()
    if first.converged:
        solved[start] = first
        queue.append(start)
    while queue:
        source = queue.popleft()
        for di, dj in NEIGHBOURS:
            target = (source[0] + di, source[1] + dj)
            if not (0 <= target[0] < shape[0] and 0 <= target[1] < shape[1]) or target in solved:
                continue
            gait = _solve_from(planner, grid, k, mode, source, solved[source], target, options)
            if gait is not None:
                solved[target] = gait
                queue.append(target)
    for index in np.ndindex(*shape):
        if index in solved:
            record = node_record(solved[index], True)
        else:  # not reached on the branch: what a cold solve finds there
            cold = planner.plan(GaitRequest(float(grid.step_lengths[index[0]]), float(grid.periods[index[1]]), alpha, mode,
                                            **options), cold=True)
            knee_lower = params.joints.role("knee").limits.lower
            human = cold.converged and cold.figures is not None and cold.figures.q9_min >= knee_lower - KNEE_TOLERANCE
            record = node_record(cold, human)
        for name, value in record.items():
            nodes[name][index] = value
    return Slab(k, nodes)


def build_atlas(params: BipedParams, mode: GaitMode, executor: Executor, grid: Grid | None = None,
                on_slab: Callable[[int], None] | None = None, options: Mapping[str, object] | None = None) -> Atlas:
    """The atlas of ``params`` and ``mode`` on ``grid`` (default ``Grid.default()``), one task a
    grid alpha on ``executor``; ``on_slab`` is told the node count of each finished task;
    ``options``: further ``GaitRequest`` fields of every gait (the planner's atlas has none)."""
    grid = grid or Grid.default()
    start_time = time.perf_counter()
    atlas = Atlas.empty(params, mode, grid)
    start, gaits = spine(planner_for(params), mode, grid, options)
    futures = {executor.submit(build_slab, params, mode, grid, k, start, gait.warm_start(), options): k
               for k, gait in enumerate(gaits) if gait is not None}
    for slab in _completed(futures):
        for name, array in slab.nodes.items():
            atlas.nodes[name][:, :, slab.k] = array
        if on_slab is not None:
            on_slab(grid.shape[0] * grid.shape[1])
    return replace(atlas, build_seconds=time.perf_counter() - start_time, options=dict(options or {}))


def _completed(futures) -> Iterator[Slab]:
    for future in as_completed(futures):
        yield future.result()
