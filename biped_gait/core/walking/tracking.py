"""A planned motion the walk tracks (docs/model.md sections 14.1, 15.1): the plan's collocation
samples as a reference, and the LQR about it.

**The reference.** The plan's collocation points (nodes and midpoints of its Hermite-Simpson
intervals) carry q, qd, qdd and the torques Gamma; between them q and qd are the cubic Hermite
interpolants of (q, qd) and (qd, qdd), Gamma the linear one (``HeldSupport``'s, with which the
lasting walk was measured) or the quadratic through each interval's node, midpoint and node, the
rule's own (``swing_ends.SwingReference``: docs/model.md 15.1 says why).

**The feedback** is the standing balance's LQR machinery (``balance``) about the reference: at
each sample the dynamics linearized there (its state and torques), in the minimal coordinates
of the held rows there, Bryson's weights; at time t the gain K and basis N of the nearest sample,
and the torques

    Gamma = Gamma*(t) - K [N'(q - q*(t)); N'(qd - qd*(t))],

each within its joint's effort limit. The gains are the LQR's of the dynamics frozen at each sample
(the lasting walk's, d up to a few tenths of a second), or, for a phase of seconds
(``tracking_with_horizon``: the stop and the start, 2 s), the finite-horizon LQR of the linearized time-varying system: the
samples' bases aligned to their predecessors' (orthogonal Procrustes, so that the minimal
coordinates change smoothly), each interval's dynamics discretized exactly (zero-order hold of
the torques), the discrete Riccati recursion run backwards from the frozen LQR's cost at the last
sample (at rest). Frozen gains along the stop let its error grow about sevenfold a second (7.1
mrad at its end from the touchdown's 1e-9; a touchdown 1e-3 rad/s off the plan fell in two of
three trials); the horizon's end it at 0.7 mrad and keep such a touchdown (docs/model.md 14.2).

**What holds the tips** (``chain``): the closed chain of a double support (both tips held,
core/dynamics/closed_chain.py) or the single support driven by joint torques (the stance tip
pinned, ``phases.pulse_dynamics.PinnedTip``); of it the reference needs its model ``bm``, its
``actuated`` joints, its forward dynamics ``forward(q, qd, torque)`` (qdd and the held tips'
reaction) and its held rows ``rows_of(q)`` (none for the pinned tip: its minimal coordinates are q).

Times in the tracked phase (s from its start); q, qd in the step's model coordinates. Units SI, rad.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import CubicHermiteSpline
from scipy.linalg import expm, solve_continuous_are

from .balance import TORQUE_SCALE, effort_limits, linearization, lqr_gain, minimal_basis

RESOLUTION_STEP = 1e-3  # s: the reference is checked this often (``Tracking.along``), the walk's step
# Bryson's weights of the tracking: the lift-off's state error is amplified about 150-fold by the
# next ballistic step, whose re-aim converges from a few mrad; standing's 0.1 rad and 1 rad/s left
# 2 mrad and 13 mrad/s at the lift-off of the default gait, too far for the re-aim's chord steps.
# In the double support these give closed-loop eigenvalues up to about 810 1/s (h lambda = 0.8 at
# the 1 ms step; the slowest, the roll over the feet line, stays near its open-loop 2.9 1/s).
POSITION_SCALE = 1e-2  # rad
RATE_SCALE = 1e-1  # rad/s


@dataclass(frozen=True, eq=False)
class Tracking:
    """A planned phase of ``duration`` s to track (module docstring): what holds the tips
    (``chain``), the samples ``t`` (s in the phase), ``q``, ``qd``, ``qdd`` (rows, the step's
    coordinates) and ``torques`` (N m, actuated joints), and the feedback (at the instants
    ``gain_t``, s in the phase, the minimal coordinates' ``basis`` and the ``gain``; the joints'
    effort ``limits``)."""

    chain: object
    duration: float
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    torques: np.ndarray
    gain_t: np.ndarray
    basis: np.ndarray
    gain: np.ndarray
    limits: np.ndarray

    @cached_property
    def _splines(self) -> tuple[CubicHermiteSpline, CubicHermiteSpline]:
        return CubicHermiteSpline(self.t, self.q, self.qd), CubicHermiteSpline(self.t, self.qd, self.qdd)

    def reference(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q*, qd* and Gamma* at ``t`` (s in the phase, clamped to it)."""
        t = min(max(t, 0.0), self.duration)
        q, qd = (spline(t) for spline in self._splines)
        return q, qd, self.torque(t)

    def torque(self, t: float) -> np.ndarray:
        """Gamma*(t) (N m; ``t`` s in the phase, within it): linear between the samples."""
        return np.array([np.interp(t, self.t, column) for column in self.torques.T])

    def along(self) -> Iterator[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """The reference every ``RESOLUTION_STEP`` or less over the phase, both ends included: t, q*,
        qd*, Gamma* and the chain's forward dynamics there (qdd and the held reaction). At the
        collocation points they are the plan's own; between them they say whether the plan's mesh
        resolves the phase (Hermite-Simpson can ring between its points, docs/model.md 14)."""
        for t in np.linspace(0.0, self.duration, math.ceil(self.duration / RESOLUTION_STEP) + 1):
            q, qd, torque = self.reference(float(t))
            qdd, held = self.chain.forward(q, qd, torque)
            yield float(t), q, qd, torque, qdd, held

    def law(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The actuated joints' torques (N m) at ``t`` (s in the phase) in (``q``, ``qd``): the
        gain and basis of the instant nearest ``t``."""
        q_ref, qd_ref, torque = self.reference(t)
        k = int(np.argmin(np.abs(self.gain_t - t)))
        basis = self.basis[k]
        error = np.concatenate([basis.T @ (q - q_ref), basis.T @ (qd - qd_ref)])
        return np.clip(torque - self.gain[k] @ error, -self.limits, self.limits)


def tracking(chain, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, torques: np.ndarray,
             cls: type = Tracking, **extra) -> Tracking:
    """The ``Tracking`` (or its subclass ``cls``, its further fields ``extra``) of the samples ``t``
    (s, from 0), ``q``, ``qd``, ``qdd`` and ``torques`` of a phase held by ``chain``: at each sample
    the minimal basis and the LQR gain of the dynamics frozen there (module docstring)."""
    limits = effort_limits(chain)
    bases, systems = _linearized(chain, q, qd, torques, aligned=False)
    gains = np.array([lqr_gain(a, b, limits, POSITION_SCALE, RATE_SCALE) for a, b in systems])
    t = np.asarray(t)
    return cls(chain, float(t[-1]), t, q, qd, qdd, torques, t, np.array(bases), gains, limits, **extra)


def tracking_with_horizon(chain, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                          torques: np.ndarray, cls: type = Tracking, **extra) -> Tracking:
    """As ``tracking``, for a phase of a second or more (the stop's and the start's): the gains the
    finite-horizon LQR's, the samples' bases aligned (module docstring)."""
    limits = effort_limits(chain)
    bases, systems = _linearized(chain, q, qd, torques, aligned=True)
    t = np.asarray(t)
    gains = _horizon_gains(t, bases, systems, limits)
    return cls(chain, float(t[-1]), t, q, qd, qdd, torques, t, np.array(bases), gains, limits, **extra)


def _linearized(chain, q: np.ndarray, qd: np.ndarray, torques: np.ndarray, aligned: bool) -> tuple[list, list]:
    """At each sample the minimal basis (``aligned``: the nearest to the last one that spans the same
    space, orthogonal Procrustes) and the dynamics (A, B) linearized there in it."""
    bases, systems = [], []
    for k in range(len(q)):
        basis = minimal_basis(chain, q[k])
        if aligned and bases:
            u, _, vt = np.linalg.svd(basis.T @ bases[-1])
            basis = basis @ (u @ vt)
        bases.append(basis)
        systems.append(linearization(chain, q[k], qd[k], torques[k], basis))
    return bases, systems


def _horizon_gains(t: np.ndarray, bases: list[np.ndarray], systems: list[tuple[np.ndarray, np.ndarray]],
                   limits: np.ndarray) -> np.ndarray:
    """The finite-horizon LQR's gains at the samples ``t`` (s) of the dynamics ``systems`` (A, B)
    linearized in the aligned ``bases`` (module docstring): each interval discretized exactly, the
    discrete Riccati recursion run backwards from the frozen LQR's cost at the last sample."""
    a, b = systems[-1]
    m, na = a.shape[0] // 2, b.shape[1]
    q_weight = np.diag(np.concatenate([np.full(m, 1 / POSITION_SCALE ** 2), np.full(m, 1 / RATE_SCALE ** 2)]))
    r_weight = np.diag(1.0 / (TORQUE_SCALE * limits) ** 2)
    cost = solve_continuous_are(a, b, q_weight, r_weight)
    steps = []
    for k in range(len(t) - 1):
        h = t[k + 1] - t[k]
        a_k, b_k = systems[k]
        block = np.zeros((2 * m + na, 2 * m + na))
        block[:2 * m, :2 * m], block[:2 * m, 2 * m:] = a_k, b_k
        held = expm(block * h)  # x(t + h) from x(t) and the torques held over h
        change = np.kron(np.eye(2), bases[k + 1].T @ bases[k])  # into the next sample's coordinates
        steps.append((change @ held[:2 * m, :2 * m], change @ held[:2 * m, 2 * m:], h))
    return np.concatenate([riccati_gains(steps, q_weight, r_weight, cost), [np.linalg.solve(r_weight, b.T @ cost)]])


def riccati_gains(steps: list[tuple[np.ndarray, np.ndarray, float]], weight: np.ndarray, effort: np.ndarray,
                  cost: np.ndarray) -> np.ndarray:
    """The finite-horizon LQR's gains of the discrete steps x+ = A x + B u (each (A, B, h), h the
    step's duration, s): the state's ``weight`` and the torques' ``effort`` per second, the Riccati
    recursion run backwards from the last state's ``cost``. Rows (nA x n), one a step, in order."""
    gains = []
    for a, b, h in reversed(steps):
        gain = np.linalg.solve(effort * h + b.T @ cost @ b, b.T @ cost @ a)
        cost = weight * h + a.T @ cost @ (a - b @ gain)
        cost = (cost + cost.T) / 2
        gains.append(gain)
    return np.array(gains[::-1])
