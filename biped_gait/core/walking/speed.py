"""Which gait walks at a given speed: the rules a speed command follows (docs/model.md section 8.8).

A gait of step length L (m) and period T (s) walks at v = L / T (m/s): over a step the pelvis
advances L in T. Two rules pick (L, T) for a speed, at the walk's arm amplitude alpha and mode:

- ``LeastEffort`` (needs the gait atlas): along the line L = v T in the (L, T) plane, the gait
  of least effort per metre W / L (W the double support's effort, N m s), W interpolated
  bilinearly between the atlas nodes (and linearly in alpha), among points whose surrounding
  nodes are all walkable; the period as a function of the speed is kept continuous, its slope
  at most ``MAX_SLOPE`` (the least total W / L over the speeds among such curves, by dynamic
  programming), so that a change of speed changes the gait gradually. Tabulated every
  ``SPEED_STEP`` over the longest range of speeds such a curve spans; between table speeds T is
  interpolated linearly and L = v T, so that L / T is the speed exactly.
- ``FixedCadence``: T fixed (the walk's plan), L = v T; the admissible step lengths are those of
  the atlas's walkable nodes at that T and alpha, or without an atlas the atlas grid's
  L range (0.25 to 0.65 m, where the default sets have admissible gaits for T >= 0.425 s).

A node is walkable (``walkable_nodes``) if the atlas calls it admissible, its open-loop
spectral radius (the Floquet multipliers, ``stability``) is at most ``MAX_RADIUS``, its swing
foot comes down onto the ground at the touchdown, vertical velocity below -``ARRIVAL_MARGIN``,
and the walker's momentum steering can steer there: its pitch authority a + b c is at least
``MIN_AUTHORITY``, at this period and every shorter one of the step length (with the hips the
authority vanishes at T = 0.55 to 0.62 s, where the least effort per metre would walk the slow
speeds: every walk that slowed down fell there).
Without the bound on the radius the least effort per metre lies at long periods (0.55 to 0.6 s),
where a gait amplifies a perturbation 1e4 to 1e6 times per step: the walker's transition and
re-aim problems there are so ill-conditioned that they fail within a few steps. And the
planner's clearance is checked on (0.05 T, 0.95 T) (docs/model.md section 4.2): around
T = 0.55 to 0.6 s at short steps, admissible gaits reach the touchdown from below the ground
(the tip dips under it just before T and comes back up), which the walker's guard catches as an
early touchdown, off the orbit.

A speed outside a rule's admissible range [low, high] is clamped to it (``clamp``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..gait.atlas import Atlas, Grid, NodeStatus
from ..gait.configurations import boundary_configurations
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS
from .steering import reference

SPEED_STEP = 0.01  # m/s: spacing of the least-effort table
PERIOD_STEP = 0.0025  # s: spacing of the periods tried along each speed line
MAX_SLOPE = 0.25  # s per m/s: the least-effort period's largest change with the speed
MAX_RADIUS = 1000.0  # the largest open-loop spectral radius of a walkable gait
ARRIVAL_MARGIN = 0.005  # m/s: a walkable gait's swing tip comes down at least this fast at the touchdown
MIN_AUTHORITY = 3.0
"""kg m^2/s per rad: a walkable gait's steering authority a + b c at least (``steering``), on the
short-period side of the line where it vanishes: there the steered re-aim is singular and the
walker falls (the hips' walk at 0.6 m/s fell at T = 0.62 s, a + b c = -1, and walked through
1.4). With the nine joints it is 14 to 15 over the walkable gaits; with the hips it falls from
7 to 11 at T = 0.3 s through 0 at T = 0.55 to 0.62 s (docs/model.md section 8.8)."""


@dataclass(frozen=True)
class SpeedGait:
    """The gait chosen for ``speed`` (m/s): step length (m), period (s), and its effort per
    metre W / L (N s, NaN if the rule does not know it)."""

    speed: float
    step_length: float
    period: float
    effort_per_metre: float = math.nan


class SpeedRule:
    """A rule speed -> gait with its admissible speed range [``low``, ``high``] (m/s)."""

    name = ""
    low: float
    high: float

    def gait(self, speed: float) -> SpeedGait:
        """The gait for ``speed`` (m/s), clamped to the admissible range first."""
        raise NotImplementedError

    def clamp(self, speed: float) -> tuple[float, bool]:
        """``speed`` (m/s) within [low, high], and whether it had to be moved there."""
        clamped = min(max(speed, self.low), self.high)
        return clamped, clamped != speed

    def describe(self) -> str:
        """One line: the rule and its range."""
        return f"{self.name}: speeds {self.low:.3f} to {self.high:.3f} m/s"


def _alpha_slices(atlas: Atlas, alpha: float) -> list[tuple[int, float]]:
    """The atlas's alpha slices around ``alpha`` (rad) with their linear weights (nonzero only;
    an atlas of one alpha has that slice only)."""
    alphas = atlas.grid.alphas
    if len(alphas) == 1:
        return [(0, 1.0)]
    k = int(np.clip(np.searchsorted(alphas, alpha, side="right") - 1, 0, len(alphas) - 2))
    t = float(np.clip((alpha - alphas[k]) / (alphas[k + 1] - alphas[k]), 0.0, 1.0))
    return [(i, w) for i, w in ((k, 1.0 - t), (k + 1, t)) if w > 0.0]


def effort_surface(atlas: Atlas, alpha: float, walkable: np.ndarray) -> np.ndarray:
    """W (N m s) on the atlas's (L, T) nodes at ``alpha`` (rad, linear between slices), NaN
    where ``walkable`` (L x T, from ``walkable_nodes``) is false."""
    effort = sum(w * atlas.nodes["W"][:, :, k] for k, w in _alpha_slices(atlas, alpha))
    return np.where(walkable, effort, np.nan)


def walkable_nodes(atlas: Atlas, alpha: float, hybrid: HybridStep, steps: int) -> np.ndarray:
    """Per (L, T) node of ``atlas``: admissible at the alpha slices around ``alpha`` (rad), with
    an open-loop spectral radius at most ``MAX_RADIUS``, at each its swing tip comes down
    faster than ``ARRIVAL_MARGIN`` at the touchdown (the step integrated from the node's qd(0)
    and theta on a grid of ``steps``), and the steering's pitch authority (on the coarse grid of
    ``DEFAULTS``) is at least
    ``MIN_AUTHORITY`` there and at every shorter period of its step length (the steerable side
    of the line where it vanishes)."""
    flow, mode, ends = hybrid.flow(steps), atlas.mode, boundary_configurations(hybrid.bm)
    coarse = hybrid.flow(min(steps, DEFAULTS.coarse_steps))  # the authority's sensitivities: half the walk's cost
    out = np.ones(atlas.grid.shape[:2], dtype=bool)
    for k, _ in _alpha_slices(atlas, alpha):
        alpha_k = float(atlas.grid.alphas[k])
        beyond = np.zeros(out.shape[0], dtype=bool)  # per step length: a shorter period lost the authority
        for i, j in np.ndindex(*out.shape):  # the periods in increasing order for each step length
            if not (out[i, j] and not beyond[i] and atlas.nodes["status"][i, j, k] == NodeStatus.ADMISSIBLE
                    and atlas.nodes["spectral_radius"][i, j, k] <= MAX_RADIUS):
                out[i, j] = False
                continue
            length, period = float(atlas.grid.step_lengths[i]), float(atlas.grid.periods[j])
            q0, q_t = ends(length, alpha_k, mode, float(atlas.nodes["theta"][i, j, k]))
            qd_a = atlas.nodes["qd_a"][i, j, k]
            end = flow.propagate(q0, qd_a, period)
            out[i, j] = hybrid.samples.swing_tip_motion(end.q, end.qd)[1][0] < -ARRIVAL_MARGIN
            if out[i, j] and reference(hybrid, coarse, q0, q_t, qd_a, end.qd, period).authority < MIN_AUTHORITY:
                out[i, j], beyond[i] = False, True
    return out


class LeastEffort(SpeedRule):
    """The gait of least W / L at each speed, from ``atlas`` at arm amplitude ``alpha`` (rad)
    among its ``walkable`` (L, T) nodes (``walkable_nodes``)."""

    name = "least effort per metre"

    def __init__(self, atlas: Atlas, alpha: float, walkable: np.ndarray) -> None:
        grid = atlas.grid
        effort = effort_surface(atlas, alpha, walkable)
        periods = np.arange(grid.periods[0], grid.periods[-1] + 1e-12, PERIOD_STEP)
        lengths = grid.step_lengths
        fastest, slowest = lengths[-1] / periods[0], lengths[0] / periods[-1]
        speeds = np.round(np.arange(math.ceil(slowest / SPEED_STEP), math.floor(fastest / SPEED_STEP) + 1) * SPEED_STEP, 9)
        costs = np.array([_per_metre(grid, effort, v * periods, periods) for v in speeds])
        first, path = _least_path(costs, max(1, round(MAX_SLOPE * SPEED_STEP / PERIOD_STEP)))
        if not path:
            raise ValueError(f"the atlas of {atlas.params} ({atlas.mode.value}) has no walkable gait at alpha = "
                             f"{math.degrees(alpha):.1f} deg")
        rows = range(first, first + len(path))
        self.speeds = speeds[first:first + len(path)]
        self.periods = periods[path]
        self.costs = costs[list(rows), path]
        self.low, self.high = float(self.speeds[0]), float(self.speeds[-1])

    def gait(self, speed: float) -> SpeedGait:
        v, _ = self.clamp(speed)
        period = float(np.interp(v, self.speeds, self.periods))
        return SpeedGait(v, v * period, period, float(np.interp(v, self.speeds, self.costs)))


def _per_metre(grid: Grid, effort: np.ndarray, lengths: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """W / L (N s) at the points (``lengths``, ``periods``) by bilinear interpolation of
    ``effort`` on the grid's (L, T) nodes; inf where a surrounding node has no effort (NaN: not
    walkable) or the point is outside the grid."""
    (i, u), (j, w) = _cells(grid.step_lengths, lengths), _cells(grid.periods, periods)
    inside = (lengths >= grid.step_lengths[0] - 1e-12) & (lengths <= grid.step_lengths[-1] + 1e-12)
    value = ((1 - u) * ((1 - w) * effort[i, j] + w * effort[i, j + 1])
             + u * ((1 - w) * effort[i + 1, j] + w * effort[i + 1, j + 1]))
    return np.where(inside & np.isfinite(value), value / lengths, np.inf)


def _cells(axis: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lower node index of the cell of ``axis`` holding each ``x``, and the fraction in it."""
    i = np.clip(np.searchsorted(axis, x, side="right") - 1, 0, len(axis) - 2)
    return i, np.clip((x - axis[i]) / (axis[i + 1] - axis[i]), 0.0, 1.0)


def _least_path(costs: np.ndarray, reach: int) -> tuple[int, list[int]]:
    """The least-cost path through ``costs`` (speeds x periods, inf where not walkable) that
    moves at most ``reach`` periods from one speed to the next, over the longest run of speeds
    such paths span: (its first speed's index, the period index at each of its speeds)."""
    total = np.full(costs.shape, np.inf)
    came = np.zeros(costs.shape, dtype=int)
    starts = np.zeros(len(costs), dtype=int)  # where the run of connected speeds through each began
    for i, row in enumerate(costs):
        if i and np.isfinite(total[i - 1]).any():
            previous = np.stack([np.roll(total[i - 1], shift) for shift in range(-reach, reach + 1)])
            for shift in range(-reach, reach + 1):  # no wrap-around: np.roll brings the far end in
                previous[shift + reach, :max(shift, 0)] = np.inf
                previous[shift + reach, len(row) + min(shift, 0):] = np.inf
            best = np.argmin(previous, axis=0)
            total[i] = row + previous[best, np.arange(len(row))]
            came[i] = np.arange(len(row)) - (best - reach)
            starts[i] = starts[i - 1]
        if not np.isfinite(total[i]).any():
            total[i], starts[i] = row, i
    runs = [(i - starts[i], i) for i in range(len(costs)) if np.isfinite(total[i]).any()]
    if not runs:
        return 0, []
    _, last = max(runs)
    path = [int(np.argmin(total[last]))]
    for i in range(last, starts[last], -1):
        path.append(int(came[i, path[-1]]))
    return int(starts[last]), path[::-1]


class FixedCadence(SpeedRule):
    """L = v T at the fixed period ``period`` (s); the step lengths from the ``atlas``'s
    ``walkable`` nodes (``walkable_nodes``) around that period, or the atlas grid's L range
    without them."""

    name = "fixed cadence"

    def __init__(self, period: float, atlas: Atlas | None = None, walkable: np.ndarray | None = None) -> None:
        self.period = period
        lengths = Grid.default().step_lengths
        if atlas is not None and walkable is not None:
            j = int(np.clip(np.searchsorted(atlas.grid.periods, period, side="right") - 1, 0, len(atlas.grid.periods) - 2))
            rows = walkable[:, j] & walkable[:, j + 1]
            if not rows.any():
                raise ValueError(f"no walkable gait of the atlas of {atlas.params} around T = {period:g} s")
            lengths = atlas.grid.step_lengths[rows]
        self.low, self.high = float(lengths.min() / period), float(lengths.max() / period)

    def gait(self, speed: float) -> SpeedGait:
        v, _ = self.clamp(speed)
        return SpeedGait(v, v * self.period, self.period)

    def describe(self) -> str:
        return f"{self.name} (T = {self.period:g} s): speeds {self.low:.3f} to {self.high:.3f} m/s"
