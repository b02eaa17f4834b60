"""The gait atlas: periodic gaits of one parameter set and gait mode on a grid of step length
L (m), period T (s) and arm amplitude alpha (rad), all on the human-like branch wherever it
exists (built by continuation from the known human-like gait, ``studies.atlas_build``).

Each node holds the gait's initial velocity qd(0) (rad/s) and trunk pitch theta (rad) (the
warm start of a solve nearby), its status (admissible; inadmissible on the branch, with the
conditions that limit it; only the backward-knee twin converges; nothing converges), and the
figures the studies and maps use: W (N m s), min vertical ground reaction (N), min swing
height (m), max friction ratio, min swing-knee angle q9 (rad), yaw angular momenta at T- and T+
(kg m^2/s), the spectral radius of the open-loop Poincare map, and the RK8 steps per T of the
grid the planner solved it on to meet the accuracy contract (docs/model.md section 4.11; 0
where nothing converged, or where the plan missed the contract: its refinement failed): a plan
near it starts on that grid. An atlas is tied to its parameters and model code by ``fingerprint.model_fingerprint``
(and recognized at once by ``fingerprint.source_fingerprint`` when the code is byte for byte the
one it was built with): a stale or unreadable file is refused with a one-line message that says how
to rebuild it.

A request's margins are answered by filtering the nodes (``Atlas.within``), not by rebuilding:
the swing clearance and the step's friction ratio are stored; the margins on the impulses (the
friction margin on them, the joint-rate bound) are the impulse problem's, solved per request.

Files are compressed NumPy archives (``.npz``, no pickles). The shipped atlases are package data
(``biped_gait/core/data/atlas/``); atlases of a user's parameter file go to the cache
(``$BIPED_GAIT_CACHE``, else ``$XDG_CACHE_HOME/biped_gait``, else ``~/.cache/biped_gait``).
"""

from __future__ import annotations

import json
import math
import os
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from enum import IntEnum
from importlib import resources
from pathlib import Path

import numpy as np

from .admissibility import Limit, describe
from .configurations import GaitMode
from .continuation import SPACING
from .fingerprint import ATLAS_FORMAT, model_fingerprint, source_fingerprint
from .margins import Margins
from ..model.params import BipedParams, load_params, shipped_param_names

STEP_LENGTHS = np.round(np.arange(0.25, 0.65 + 1e-9, 0.025), 6)  # m
PERIODS = np.round(np.arange(0.30, 0.65 + 1e-9, 0.025), 6)  # s
ALPHAS = np.radians(np.arange(0.0, 45.0 + 1e-9, 5.0))  # rad

# Arrays of a node (shape: grid shape + the trailing shape given, "nq" the model's coordinates),
# and their fill values.
NODE_ARRAYS = {
    "status": ((), np.uint8), "limits": ((), np.uint8), "qd_a": (("nq",), np.float64), "theta": ((), np.float64),
    "W": ((), np.float64), "min_grf_z": ((), np.float64), "min_swing_height": ((), np.float64),
    "max_friction_ratio": ((), np.float64), "q9_min": ((), np.float64), "h_t_minus": ((2,), np.float64),
    "h_t_plus": ((2,), np.float64), "spectral_radius": ((), np.float64),
    "min_late_swing_height": ((), np.float64), "swing_arrival_speed": ((), np.float64),
    "grid_steps": ((), np.uint16),
}


class NodeStatus(IntEnum):
    """What the build found at a node."""

    ADMISSIBLE = 0  # on the human-like branch, admissible
    INADMISSIBLE = 1  # on the human-like branch, limited by ``limits``
    TWIN_ONLY = 2  # the branch was not reached; a cold solve finds the backward-knee twin
    NO_CONVERGENCE = 3  # neither continuation nor a cold solve converges


ON_BRANCH = (NodeStatus.ADMISSIBLE, NodeStatus.INADMISSIBLE)


class AtlasError(ValueError):
    """An atlas that cannot be used (missing, unreadable, stale): the message is one line."""


def rebuild_command(params_name: str, source: str | None = None) -> str:
    """The command that rebuilds the atlas of a parameter set (its name, or its file)."""
    return f"biped-gait atlas build --params {source or params_name}"


@dataclass(frozen=True, eq=False)
class Grid:
    """The atlas's axes: L (m), T (s), alpha (rad), each ascending."""

    step_lengths: np.ndarray
    periods: np.ndarray
    alphas: np.ndarray

    @classmethod
    def default(cls) -> "Grid":
        """L 0.25 to 0.65 m and T 0.30 to 0.65 s every 0.025, alpha 0 to 45 deg every 5 deg."""
        return cls(STEP_LENGTHS, PERIODS, ALPHAS)

    @property
    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.step_lengths, self.periods, self.alphas

    @property
    def shape(self) -> tuple[int, int, int]:
        return len(self.step_lengths), len(self.periods), len(self.alphas)

    def point(self, index: tuple[int, int, int]) -> tuple[float, float, float]:
        """(L, T, alpha) of the node at ``index``."""
        return tuple(float(axis[i]) for axis, i in zip(self.axes, index))

    def contains(self, point: tuple[float, float, float]) -> bool:
        """Whether (L, T, alpha) lies in the grid's box (boundaries included, to 1e-9)."""
        return all(axis[0] - 1e-9 <= x <= axis[-1] + 1e-9 for axis, x in zip(self.axes, point))

    def distances(self, point: tuple[float, float, float]) -> np.ndarray:
        """Distance of every node to (L, T, alpha), in grid spacings."""
        grids = np.meshgrid(*self.axes, indexing="ij")
        return np.sqrt(sum(((g - x) / s) ** 2 for g, x, s in zip(grids, point, SPACING)))

    def cell(self, point: tuple[float, float, float]) -> tuple[tuple[int, int, int], np.ndarray]:
        """The lower corner of the cell holding ``point`` and its fractions along each axis."""
        lower, fractions = [], []
        for axis, x in zip(self.axes, point):
            i = int(np.clip(np.searchsorted(axis, x, side="right") - 1, 0, len(axis) - 2))
            lower.append(i)
            fractions.append(float(np.clip((x - axis[i]) / (axis[i + 1] - axis[i]), 0.0, 1.0)))
        return tuple(lower), np.array(fractions)


@dataclass(frozen=True, eq=False)
class Atlas:
    """The gaits of one parameter set (``params``, its name; ``friction`` its coefficient) and
    ``mode`` on ``grid``; ``nodes`` maps each name of ``NODE_ARRAYS`` to its array;
    ``fingerprint`` and ``source`` are the model and source fingerprints it was built with;
    ``margins``: those it is seen through (``within``; none for an atlas as built); ``options``:
    the ``GaitRequest`` fields it was built with beyond the point and mode (none for the
    planner's: a study's atlas, written elsewhere, says here what it holds)."""

    params: str
    mode: GaitMode
    fingerprint: str
    friction: float
    grid: Grid
    nodes: dict[str, np.ndarray]
    build_seconds: float = math.nan
    source: str = ""
    margins: Margins = Margins()
    options: dict = field(default_factory=dict)

    @classmethod
    def empty(cls, params: BipedParams, mode: GaitMode, grid: Grid | None = None) -> "Atlas":
        """An atlas with every node unsolved (NO_CONVERGENCE, NaN figures), on ``grid``
        (default: ``Grid.default()``)."""
        grid = grid or Grid.default()
        nodes = {}
        for name, (_, dtype) in NODE_ARRAYS.items():
            fill = {"status": NodeStatus.NO_CONVERGENCE, "limits": Limit.NO_CONVERGENCE, "grid_steps": 0}.get(name, np.nan)
            nodes[name] = np.full(grid.shape + node_tail(name, params), fill, dtype=dtype)
        return cls(params.name, mode, model_fingerprint(params), params.friction, grid, nodes,
                   source=source_fingerprint(params))

    def within(self, margins: Margins, friction: float | None = None) -> "Atlas":
        """This atlas seen through ``margins`` (nodes filtered, not rebuilt): an admissible node
        whose swing clearance is not above ``margins.clearance`` (m) or whose step friction ratio
        exceeds ``friction`` (default: the atlas's) minus ``margins.friction`` is inadmissible
        with no limit's condition (it meets the limits, not the margins)."""
        mu = self.friction if friction is None else friction
        n = self.nodes
        missed = (n["status"] == NodeStatus.ADMISSIBLE) & ~(
            (n["min_swing_height"] > margins.clearance) & (n["max_friction_ratio"] <= mu - margins.friction))
        status = np.where(missed, np.uint8(NodeStatus.INADMISSIBLE), n["status"]).astype(n["status"].dtype)
        return replace(self, nodes={**n, "status": status}, margins=margins)

    # Queries ----------------------------------------------------------------------------------
    def status(self, index: tuple[int, int, int]) -> NodeStatus:
        return NodeStatus(int(self.nodes["status"][index]))

    def guess(self, point: tuple[float, float, float]) -> tuple[np.ndarray, float] | None:
        """A warm start (qd(0), theta) at (L m, T s, alpha rad) inside the grid: Catmull-Rom
        (cubic) interpolation of the 4 x 4 x 4 nodes around it when all are on the branch (linear
        along an axis at the grid's edge), else multilinear interpolation of the cell's 8 corners
        when those are, else the nearest corner on the branch; None outside the grid or without
        such a corner."""
        if not self.grid.contains(point):
            return None
        for cubic in (True, False):
            stencil = [_weights(axis, x, cubic) for axis, x in zip(self.grid.axes, point)]
            block = np.ix_(*(indices for indices, _ in stencil))
            if np.all(np.isin(self.nodes["status"][block], ON_BRANCH)):
                w0, w1, w2 = (weights for _, weights in stencil)
                qd = np.einsum("i,j,k,ijkn->n", w0, w1, w2, self.nodes["qd_a"][block])
                return qd, float(np.einsum("i,j,k,ijk->", w0, w1, w2, self.nodes["theta"][block]))
        lower, frac = self.grid.cell(point)
        corners = [(tuple(l + o for l, o in zip(lower, offset)), offset) for offset in np.ndindex(2, 2, 2)]
        on_branch = [(idx, off) for idx, off in corners if self.status(idx) in ON_BRANCH]
        if not on_branch:
            return None
        idx = min(on_branch, key=lambda c: float(np.sum((np.array(c[1]) - frac) ** 2)))[0]
        return self.nodes["qd_a"][idx].copy(), float(self.nodes["theta"][idx])

    def grid_steps(self, point: tuple[float, float, float]) -> int:
        """The RK8 steps per T a plan at (L, T, alpha) starts on: those its grid cell's nearest
        corner met the accuracy contract on, else the most any corner did (0 outside the grid, or
        where none did). The grid a gait needs grows with T (section 4.11 of docs/model.md): at
        T = 0.625 s, 64 steps, where the cell's corners at 0.65 s need 128; a plan that needs more
        than its corner's refines."""
        if not self.grid.contains(point):
            return 0
        lower, fractions = self.grid.cell(point)
        steps = self.nodes["grid_steps"]
        nearest = int(steps[tuple(i + int(f > 0.5) for i, f in zip(lower, fractions))])
        return nearest or int(np.max(steps[tuple(slice(i, i + 2) for i in lower)]))

    def admissible_near(self, point: tuple[float, float, float]) -> bool:
        """Whether a corner of the grid cell holding (L, T, alpha) is admissible (False
        outside the grid)."""
        if not self.grid.contains(point):
            return False
        lower, _ = self.grid.cell(point)
        cell = self.nodes["status"][tuple(slice(i, i + 2) for i in lower)]
        return bool(np.any(cell == NodeStatus.ADMISSIBLE))

    def nearest(self, point: tuple[float, float, float], statuses=(NodeStatus.ADMISSIBLE,)) -> tuple[int, int, int] | None:
        """The index of the node nearest to (L, T, alpha) (in grid spacings) among those of
        ``statuses``; None if there is none."""
        distances = np.where(np.isin(self.nodes["status"], [int(s) for s in statuses]), self.grid.distances(point), np.inf)
        if not np.isfinite(distances).any():
            return None
        return tuple(int(i) for i in np.unravel_index(int(np.argmin(distances)), distances.shape))

    def reasons(self, index: tuple[int, int, int]) -> list[str]:
        """Why the node is not admissible, one line per condition (empty if it is)."""
        status = self.status(index)
        if status == NodeStatus.TWIN_ONLY:
            return ["only the backward-knee twin converges"]
        if status == NodeStatus.NO_CONVERGENCE:
            return ["no gait converges"]
        n = self.nodes
        return describe(Limit(int(n["limits"][index])), float(n["min_grf_z"][index]), float(n["min_swing_height"][index]),
                        float(n["q9_min"][index]), float(n["max_friction_ratio"][index]), self.friction,
                        float(n["min_late_swing_height"][index]), float(n["swing_arrival_speed"][index]))

    def hint(self, point: tuple[float, float, float]) -> str:
        """Where the nearest admissible gaits are, for a refusal at (L m, T s, alpha rad) of a
        request this atlas describes (its other fields the atlas's): the admissible periods at the
        nearest grid L and alpha, without the refused T (``period_runs``), else the nearest
        admissible node."""
        L, period, alpha = point
        i = int(np.argmin(np.abs(self.grid.step_lengths - L)))
        k = int(np.argmin(np.abs(self.grid.alphas - alpha)))
        runs = period_runs(self.grid.periods, self.nodes["status"][i, :, k] == NodeStatus.ADMISSIBLE, period)
        where = f"L = {self.grid.step_lengths[i]:.3f} m, alpha = {math.degrees(self.grid.alphas[k]):.0f} deg"
        what = "within the margins" if self.margins else "admissible"
        if runs:
            return f"nearest {what} (atlas grid): {runs} at {where}"
        index = self.nearest(point)
        if index is None:
            return f"no {what} gait in the atlas of {self.params} ({self.mode.value})"
        nl, nt, na = self.grid.point(index)
        return f"nearest {what} (atlas grid): L = {nl:.3f} m, T = {nt:.3f} s, alpha = {math.degrees(na):.0f} deg"

    def counts(self) -> dict[str, int]:
        """Nodes per status."""
        return {s.name.lower(): int(np.sum(self.nodes["status"] == s)) for s in NodeStatus}

    # Files ------------------------------------------------------------------------------------
    def save(self, path: Path) -> Path:
        """Write the atlas as a compressed ``.npz`` (atomically: a temporary file, then renamed)."""
        meta = {"format": ATLAS_FORMAT, "params": self.params, "mode": self.mode.value, "fingerprint": self.fingerprint,
                "friction": self.friction, "build_seconds": self.build_seconds, "source": self.source}
        if self.options:
            meta["options"] = {k: v if not isinstance(v, float) or math.isfinite(v) else str(v)
                               for k, v in self.options.items()}
        return write_archive(path, meta, {"step_lengths": self.grid.step_lengths, "periods": self.grid.periods,
                                          "alphas": self.grid.alphas, **self.nodes})

    @classmethod
    def load(cls, path: Path, params: BipedParams, source: str | None = None) -> "Atlas":
        """Read an atlas for ``params`` (``source``: the name or file the user gave); ``AtlasError``
        with the rebuild command if the file is unreadable, of another mode format, or stale."""
        rebuild = rebuild_command(params.name, source)
        meta, data = read_archive(path, "gait atlas", rebuild, lambda meta: (
            meta.get("source") == source_fingerprint(params) or meta.get("fingerprint") == model_fingerprint(params)),
            ("step_lengths", "periods", "alphas", *NODE_ARRAYS))
        grid = Grid(data["step_lengths"], data["periods"], data["alphas"])
        nodes = {name: data[name] for name in NODE_ARRAYS}
        check_shapes(path, "gait atlas", rebuild, {name: grid.shape + node_tail(name, params) for name in NODE_ARRAYS},
                     nodes)
        return cls(meta["params"], GaitMode.parse(meta["mode"]), meta["fingerprint"], float(meta["friction"]), grid, nodes,
                   float(meta.get("build_seconds", math.nan)), meta.get("source", ""),
                   options=meta.get("options", {}))


def period_runs(periods: np.ndarray, admissible: np.ndarray, refused: float) -> str:
    """The runs of consecutive ``periods`` (s, ascending) that are ``admissible`` (a mask), as
    "T in [a, b] s" (runs joined by "or"), each cut where the ``refused`` period (s) lies in it, so
    that none holds it; '' if there are none."""
    admissible = np.asarray(admissible, dtype=bool) & ~np.isclose(periods, refused, rtol=0.0, atol=1e-9)
    runs, start = [], None
    for j, ok in enumerate(admissible):
        if start is not None and (not ok or periods[j - 1] < refused < periods[j]):
            runs.append((periods[start], periods[j - 1]))
            start = None
        if ok and start is None:
            start = j
    if start is not None:
        runs.append((periods[start], periods[-1]))
    if not runs:
        return ""
    return "T in " + " or ".join(f"[{a:.3f}, {b:.3f}]" for a, b in runs) + " s"


def write_archive(path: Path, meta: dict, arrays: dict[str, np.ndarray]) -> Path:
    """Write ``arrays`` and the JSON ``meta`` as a compressed ``.npz`` (no pickles), atomically
    (a temporary file, then renamed)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as f:
        np.savez_compressed(f, meta=np.array(json.dumps(meta)), **arrays)
    os.replace(tmp, path)
    return path


def read_archive(path: Path, what: str, rebuild: str, current: Callable[[dict], bool],
                 names: tuple[str, ...]) -> tuple[dict, dict[str, np.ndarray]]:
    """The JSON meta and the arrays ``names`` of the archive of ``what`` (e.g. "gait atlas") at
    ``path``; ``AtlasError`` (one line, with the ``rebuild`` command) if it is missing,
    unreadable, of another format or not ``current`` (its meta tells: the fingerprints)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta.get("format") != ATLAS_FORMAT or not current(meta):
                raise AtlasError(f"the {what} {path} is stale (built for other parameters or model code): "
                                 f"rebuild it with `{rebuild}`")
            return meta, {name: data[name] for name in names}
    except FileNotFoundError:
        raise AtlasError(f"no {what} at {path}: build it with `{rebuild}`") from None
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        if isinstance(exc, AtlasError):
            raise
        raise AtlasError(f"the {what} {path} is unreadable: rebuild it with `{rebuild}`") from None


def check_shapes(path: Path, what: str, rebuild: str, shapes: dict[str, tuple[int, ...]],
                 arrays: dict[str, np.ndarray]) -> None:
    """``AtlasError`` (unreadable) unless each array has its expected shape."""
    if any(arrays[name].shape != shape for name, shape in shapes.items()):
        raise AtlasError(f"the {what} {path} is unreadable: rebuild it with `{rebuild}`")


def node_tail(name: str, params: BipedParams) -> tuple[int, ...]:
    """The trailing shape of the node array ``name`` for the model of ``params``."""
    return tuple(len(params.joints.coordinates()) if d == "nq" else d for d in NODE_ARRAYS[name][0])


def _weights(axis: np.ndarray, x: float, cubic: bool) -> tuple[np.ndarray, np.ndarray]:
    """Node indices along ``axis`` and their interpolation weights at ``x``: Catmull-Rom over
    four nodes (``cubic``, where the axis has a node on each side of the cell), else linear."""
    i = int(np.clip(np.searchsorted(axis, x, side="right") - 1, 0, len(axis) - 2))
    t = float(np.clip((x - axis[i]) / (axis[i + 1] - axis[i]), 0.0, 1.0))
    if cubic and 0 < i < len(axis) - 2:
        t2, t3 = t * t, t * t * t
        weights = np.array([-t3 + 2 * t2 - t, 3 * t3 - 5 * t2 + 2, -3 * t3 + 4 * t2 + t, t3 - t2]) / 2
        return np.arange(i - 1, i + 3), weights
    return np.array([i, i + 1]), np.array([1.0 - t, t])


def cache_dir() -> Path:
    """Where atlases of user parameter files are kept: ``$BIPED_GAIT_CACHE``, else
    ``$XDG_CACHE_HOME/biped_gait``, else ``~/.cache/biped_gait`` (an ``atlas/`` folder in it)."""
    root = os.environ.get("BIPED_GAIT_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "biped_gait")
    return Path(root) / "atlas"


def shipped_dir() -> Path:
    """The package's folder of shipped atlases."""
    return Path(str(resources.files("biped_gait.core.data"))) / "atlas"


def is_shipped(params: BipedParams) -> bool:
    """Whether ``params`` is one of the shipped parameter sets, values included."""
    return params.name in shipped_param_names() and load_params(params.name) == params


def atlas_path(params: BipedParams, mode: GaitMode) -> Path:
    """Where the atlas of ``params`` and ``mode`` lives: package data for a shipped parameter
    set, the cache (keyed by the fingerprint) for any other."""
    if is_shipped(params):
        return shipped_dir() / f"{params.name}-{mode.value}.npz"
    return cache_dir() / f"{params.name}-{model_fingerprint(params)[:12]}-{mode.value}.npz"
