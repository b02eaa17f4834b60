"""The turning atlas: strides on circles (``GaitPlanner.plan_stride``) of one parameter set with
lateral hip joints and one gait mode, on a grid of step length L (m), period T (s), arm
amplitude alpha (rad) and curvature kappa = 1 / R (1/m, >= 0: a right turn, kappa < 0, is the
left turn's mirror image, its steps swapped). Built by continuation in kappa from each straight
gait (``studies.turning_atlas_build``), so every node is on the branch of today's straight gait.

Each node holds the stride's warm start (qd_A(0), theta_1, qd_B(0), theta_2: step A on the right
foot, B on the left, each in its own coordinates), its status (``atlas.NodeStatus``: admissible,
inadmissible, or not reached by the continuation), the stride's effort W and each step's (N m
s), the yaw angular momentum about the new stance foot before each touchdown (kg m^2/s), and
each step's smallest swing-knee angle (rad). The kappa = 0 layer is the straight gait (both
steps the same). The file is tied to its parameters and to the model and turning code by
``turning_fingerprint``, as the straight atlas is by ``fingerprint.model_fingerprint``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .atlas import (ON_BRANCH, NodeStatus, cache_dir, check_shapes, is_shipped, read_archive, rebuild_command,
                    shipped_dir, write_archive)
from .configurations import GaitMode
from .fingerprint import ATLAS_FORMAT, code_digest, model_fingerprint
from ..model.params import BipedParams

STEP_LENGTHS = np.round(np.arange(0.35, 0.55 + 1e-9, 0.05), 6)  # m
PERIODS = np.round(np.arange(0.40, 0.50 + 1e-9, 0.05), 6)  # s
ALPHAS = np.radians(np.arange(0.0, 30.0 + 1e-9, 10.0))  # rad
CURVATURES = np.round(np.arange(0.0, 1.0 + 1e-9, 0.1), 6)  # 1/m: R down to 1 m
# The turning code beyond the model code (with every core module it imports: tests/test_fingerprint.py).
TURNING_CODE = ("gait/turning.py", "gait/stride.py")
# Arrays of a node (grid shape + the trailing shape; "nq" the model's coordinates).
NODE_ARRAYS = {
    "status": ((), np.uint8), "qd_a": ((2, "nq"), np.float64), "theta": ((2,), np.float64),
    "W": ((), np.float64), "step_W": ((2,), np.float64), "h_t_minus": ((2,), np.float64),
    "q9_min": ((2,), np.float64),
}


def turning_fingerprint(params: BipedParams) -> str:
    """SHA-256 of ``model_fingerprint(params)`` and the turning code (``TURNING_CODE``, by its
    tokens)."""
    return code_digest(model_fingerprint(params), TURNING_CODE)


@dataclass(frozen=True, eq=False)
class TurningGrid:
    """The turning atlas's axes: L (m), T (s), alpha (rad), kappa (1/m, from 0), each ascending."""

    step_lengths: np.ndarray
    periods: np.ndarray
    alphas: np.ndarray
    curvatures: np.ndarray

    @classmethod
    def default(cls) -> "TurningGrid":
        """L 0.35 to 0.55 m and T 0.40 to 0.50 s every 0.05, alpha 0 to 30 deg every 10, kappa 0
        to 1 every 0.1 1/m."""
        return cls(STEP_LENGTHS, PERIODS, ALPHAS, CURVATURES)

    @property
    def axes(self) -> tuple[np.ndarray, ...]:
        return self.step_lengths, self.periods, self.alphas, self.curvatures

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(axis) for axis in self.axes)

    def contains(self, point: tuple[float, float, float, float]) -> bool:
        """Whether (L, T, alpha, |kappa|) lies in the grid's box (to 1e-9)."""
        return all(axis[0] - 1e-9 <= x <= axis[-1] + 1e-9 for axis, x in zip(self.axes, point))


@dataclass(frozen=True, eq=False)
class TurningAtlas:
    """The strides of ``params`` (its name) and ``mode`` on ``grid``; ``nodes`` maps each name
    of ``NODE_ARRAYS`` to its array."""

    params: str
    mode: GaitMode
    fingerprint: str
    grid: TurningGrid
    nodes: dict[str, np.ndarray]
    build_seconds: float = math.nan

    @classmethod
    def empty(cls, params: BipedParams, mode: GaitMode, grid: TurningGrid | None = None) -> "TurningAtlas":
        """Every node not reached (NO_CONVERGENCE, NaN figures), on ``grid`` (default the default)."""
        grid = grid or TurningGrid.default()
        nodes = {name: np.full(grid.shape + _tail(name, params), NodeStatus.NO_CONVERGENCE if name == "status" else np.nan,
                               dtype=dtype) for name, (_, dtype) in NODE_ARRAYS.items()}
        return cls(params.name, mode, turning_fingerprint(params), grid, nodes)

    def guess(self, point: tuple[float, float, float, float]) -> tuple[np.ndarray, float, np.ndarray, float] | None:
        """A warm start (qd_A(0), theta_1, qd_B(0), theta_2) of the stride at (L m, T s, alpha
        rad, kappa 1/m, signed): multilinear interpolation of the 16 corners of its cell when all
        were reached, else the nearest reached corner; a negative kappa gets the mirror image's
        (its steps swapped). None outside the grid or without a reached corner."""
        length, period, alpha, curvature = point
        where = (length, period, alpha, abs(curvature))
        if not self.grid.contains(where):
            return None
        lower, fractions = [], []
        for axis, x in zip(self.grid.axes, where):
            i = int(np.clip(np.searchsorted(axis, x, side="right") - 1, 0, len(axis) - 2))
            lower.append(i)
            fractions.append(float(np.clip((x - axis[i]) / (axis[i + 1] - axis[i]), 0.0, 1.0)))
        block = tuple(slice(i, i + 2) for i in lower)
        status = self.nodes["status"][block]
        weights = np.ones((2,) * 4)
        for axis, t in enumerate(fractions):
            shape = [1] * 4
            shape[axis] = 2
            weights = weights * np.array([1.0 - t, t]).reshape(shape)
        if np.all(np.isin(status, ON_BRANCH)):
            qd = np.einsum("ijkl,ijklsn->sn", weights, self.nodes["qd_a"][block])
            theta = np.einsum("ijkl,ijkls->s", weights, self.nodes["theta"][block])
        else:
            reached = [o for o in np.ndindex(*status.shape) if status[o] in ON_BRANCH]
            if not reached:
                return None
            corner = max(reached, key=lambda o: weights[o])
            index = tuple(i + o for i, o in zip(lower, corner))
            qd, theta = self.nodes["qd_a"][index], self.nodes["theta"][index]
        a, b = (1, 0) if curvature < 0 else (0, 1)
        return qd[a].copy(), float(theta[a]), qd[b].copy(), float(theta[b])

    def smallest_radius(self, point: tuple[float, float, float]) -> tuple[float, tuple[float, float, float]] | None:
        """The smallest admissible turn radius (m) of the grid at the node nearest to (L m, T s,
        alpha rad) (the largest curvature up to which every node is admissible), and that node;
        None if even the straight gait is not admissible there."""
        index = tuple(int(np.argmin(np.abs(axis - x))) for axis, x in zip(self.grid.axes[:3], point))
        column = self.nodes["status"][index] == NodeStatus.ADMISSIBLE
        if not column[0]:
            return None
        last = int(np.argmin(column)) - 1 if not column.all() else len(column) - 1
        node = tuple(float(axis[i]) for axis, i in zip(self.grid.axes[:3], index))
        curvature = float(self.grid.curvatures[last])
        return (math.inf if curvature == 0 else 1.0 / curvature), node

    def counts(self) -> dict[str, int]:
        """Nodes per status."""
        return {s.name.lower(): int(np.sum(self.nodes["status"] == s)) for s in NodeStatus}

    def save(self, path: Path) -> Path:
        """Write the atlas as a compressed ``.npz`` (atomically)."""
        meta = {"format": ATLAS_FORMAT, "params": self.params, "mode": self.mode.value, "fingerprint": self.fingerprint,
                "build_seconds": self.build_seconds}
        return write_archive(path, meta, {"step_lengths": self.grid.step_lengths, "periods": self.grid.periods,
                                          "alphas": self.grid.alphas, "curvatures": self.grid.curvatures, **self.nodes})

    @classmethod
    def load(cls, path: Path, params: BipedParams, source: str | None = None) -> "TurningAtlas":
        """Read the turning atlas of ``params``; ``AtlasError`` (one line, with the rebuild
        command) if it is missing, unreadable or stale."""
        rebuild = rebuild_command(params.name, source) + " --turning"
        meta, data = read_archive(path, "turning atlas", rebuild,
                                  lambda meta: meta.get("fingerprint") == turning_fingerprint(params),
                                  ("step_lengths", "periods", "alphas", "curvatures", *NODE_ARRAYS))
        grid = TurningGrid(data["step_lengths"], data["periods"], data["alphas"], data["curvatures"])
        nodes = {name: data[name] for name in NODE_ARRAYS}
        check_shapes(path, "turning atlas", rebuild, {name: grid.shape + _tail(name, params) for name in NODE_ARRAYS},
                     nodes)
        return cls(meta["params"], GaitMode.parse(meta["mode"]), meta["fingerprint"], grid, nodes,
                   float(meta.get("build_seconds", math.nan)))


def _tail(name: str, params: BipedParams) -> tuple[int, ...]:
    return tuple(len(params.joints.coordinates()) if d == "nq" else d for d in NODE_ARRAYS[name][0])


def turning_atlas_path(params: BipedParams, mode: GaitMode) -> Path:
    """Where the turning atlas of ``params`` and ``mode`` lives (package data for a shipped set,
    the cache for any other)."""
    if is_shipped(params):
        return shipped_dir() / f"{params.name}-{mode.value}-turning.npz"
    return cache_dir() / f"{params.name}-{model_fingerprint(params)[:12]}-{mode.value}-turning.npz"
