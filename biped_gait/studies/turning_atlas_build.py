"""Building a turning atlas (``core.gait.turning_atlas``) by continuation in the curvature.

One task per arm amplitude of the grid (on any ``concurrent.futures.Executor``): at each (L, T)
node the straight gait (the planner's, from its atlas), then the strides at each curvature of the
grid in turn, each warm-started from the last (``GaitPlanner.plan_stride`` with a guess and its
curvature: a solve that leaves the branch is done again along a finer continuation, so that a
node does not land on the twin branch of the swing knee bent backwards); a stride that does not
converge ends its line (the larger curvatures stay NO_CONVERGENCE).
L in m, T in s, alpha in rad, kappa in 1/m.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, as_completed

import numpy as np

from ..core.gait.atlas import NodeStatus
from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Gait, Stride
from ..core.gait.planner import GaitRequest
from ..core.gait.turning_atlas import TurningAtlas, TurningGrid
from ..core.model.params import BipedParams
from .executors import planner_for


def stride_record(steps: tuple[Gait, Gait], admissible: bool) -> dict[str, object]:
    """The turning atlas's values of one node from its two solved steps (a straight gait: the
    same step twice)."""
    return {
        "status": NodeStatus.ADMISSIBLE if admissible else NodeStatus.INADMISSIBLE,
        "qd_a": np.stack([g.step.qd_a for g in steps]), "theta": np.array([g.theta for g in steps]),
        "W": float(sum(g.W for g in steps)), "step_W": np.array([g.W for g in steps]),
        "h_t_minus": np.array([g.double_support.h_t_minus[1] for g in steps]),
        "q9_min": np.array([g.figures.q9_min for g in steps]),
    }


def build_turning_slab(params: BipedParams, mode: GaitMode, grid: TurningGrid, k: int) -> tuple[int, dict[str, np.ndarray]]:
    """Worker entry: every (L, T, kappa) node at alpha index ``k``."""
    planner = planner_for(params)
    alpha = float(grid.alphas[k])
    slab = TurningAtlas.empty(params, mode, TurningGrid(grid.step_lengths, grid.periods, grid.alphas[k:k + 1],
                                                        grid.curvatures))
    nodes = {name: array[:, :, 0] for name, array in slab.nodes.items()}
    for i, j in np.ndindex(len(grid.step_lengths), len(grid.periods)):
        length, period = float(grid.step_lengths[i]), float(grid.periods[j])
        straight = planner.plan(GaitRequest(length, period, alpha, mode))
        if not straight.converged or straight.double_support is None:
            continue
        _store(nodes, (i, j, 0), stride_record((straight, straight), straight.admissible))
        guess, reached = (straight.qd_a, straight.theta, straight.qd_a, straight.theta), 0.0
        for m, curvature in enumerate(grid.curvatures[1:], start=1):
            stride = planner.plan_stride(GaitRequest(length, period, alpha, mode, turn_radius=1.0 / float(curvature)),
                                         guess, stability=False, guess_curvature=reached)
            if not _solved(stride):
                break
            _store(nodes, (i, j, m), stride_record(stride.steps, stride.admissible))
            a, b = stride.steps
            guess, reached = (a.qd_a, a.theta, b.qd_a, b.theta), float(curvature)
    return k, nodes


def _solved(stride: Stride) -> bool:
    return stride.converged and all(g.double_support is not None and g.figures is not None and
                                    g.double_support.impulses.success for g in stride.steps)


def _store(nodes: dict[str, np.ndarray], index: tuple[int, int, int], record: dict[str, object]) -> None:
    for name, value in record.items():
        nodes[name][index] = value


def build_turning_atlas(params: BipedParams, mode: GaitMode, executor: Executor, grid: TurningGrid | None = None,
                        on_slab: Callable[[int], None] | None = None) -> TurningAtlas:
    """The turning atlas of ``params`` (lateral hip joints needed) and ``mode`` on ``grid``
    (default ``TurningGrid.default()``), one task an arm amplitude on ``executor``; ``on_slab``
    is told the node count of each finished task."""
    if not params.joints.lateral_hips:
        raise ValueError(f"parameter set {params.name} walks straight only: a turning atlas needs hip roll and yaw "
                         "joints (e.g. aoustin2013-hips)")
    grid = grid or TurningGrid.default()
    start = time.perf_counter()
    atlas = TurningAtlas.empty(params, mode, grid)
    futures = [executor.submit(build_turning_slab, params, mode, grid, k) for k in range(len(grid.alphas))]
    for k, nodes in _completed(futures):
        for name, array in nodes.items():
            atlas.nodes[name][:, :, k] = array
        if on_slab is not None:
            on_slab(grid.shape[0] * grid.shape[1] * grid.shape[3])
    return TurningAtlas(atlas.params, atlas.mode, atlas.fingerprint, grid, atlas.nodes, time.perf_counter() - start)


def _completed(futures) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
    for future in as_completed(futures):
        yield future.result()
