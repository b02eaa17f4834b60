"""What a walk needs of a double support that lasts (docs/model.md section 14.1): the planned
phase (``core/gait/lasting.py``'s ``LastingSupport``) as a reference to track, and the feedback
that tracks it.

**The reference.** The plan's collocation points (nodes and midpoints of its Hermite-Simpson
intervals) carry q, qd, qdd and the torques Gamma; between them q and qd are the cubic Hermite
interpolants of (q, qd) and (qd, qdd), Gamma the linear one.

**The feedback** is the standing balance's LQR machinery (``balance``) about the reference: at
each sample the closed chain linearized there (its state and torques), in the minimal coordinates
of the held rows there, Bryson's weights; at time t the gain K and basis N of the nearest sample,
and the torques

    Gamma = Gamma*(t) - K [N'(q - q*(t)); N'(qd - qd*(t))],

each within its joint's effort limit. With point feet the rotation about the feet line has no
actuator: the feedback moves the body's shape to steer it, and what is left at the lift-off the
next step's re-aim takes (the duration, ``feedback``).

**Resolution.** The plan holds the closed chain's equations at its collocation points only. A walk
tracks the reference between them too, so the plan must resolve the phase there: the chain's
forward dynamics along the reference, every millisecond, must keep both feet pressing
(``least_normal_force``). The walked cycle of 0.1 s on 20 intervals does (44 N at its least, where
its points keep 50 N); the stop and the start on 10 intervals of 0.1 s do not (-1.4 to -2.0 kN), and
``held_support`` refuses such a plan with its reason rather than walk it into a fall
(docs/model.md section 14).

Times in the phase (s from the touchdown); q, qd in the step's model coordinates. Units SI, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings
from .balance import effort_limits, linearization, lqr_gain, minimal_basis
from .orbit import PlannedOrbit

RESOLUTION_STEP = 1e-3  # s: the reference is checked this often (``HeldSupport.least_normal_force``), the walk's step
# Bryson's weights of the tracking: the lift-off's state error is amplified about 150-fold by the
# next ballistic step, whose re-aim converges from a few mrad; standing's 0.1 rad and 1 rad/s left
# 2 mrad and 13 mrad/s at the lift-off of the default gait, too far for the re-aim's chord steps.
# These give closed-loop eigenvalues up to about 810 1/s (h lambda = 0.8 at the 1 ms step; the
# slowest, the roll over the feet line, stays near its open-loop 2.9 1/s).
POSITION_SCALE = 1e-2  # rad
RATE_SCALE = 1e-1  # rad/s


@dataclass(frozen=True, eq=False)
class HeldSupport:
    """A planned double support of ``duration`` s to track (module docstring): the closed chain,
    the samples ``t`` (s), ``q``, ``qd``, ``qdd`` (rows, the step's coordinates) and ``torques``
    (N m, actuated joints), the planned I^- (N m s) that opens it, and the feedback (at each
    sample the minimal coordinates' ``basis`` and the ``gain``; the joints' effort ``limits``)."""

    chain: ClosedChain
    duration: float
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    torques: np.ndarray
    i_minus: np.ndarray
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
        torque = np.array([np.interp(t, self.t, column) for column in self.torques.T])
        return q, qd, torque

    def least_normal_force(self) -> float:
        """The least vertical reaction (N) of either foot along the reference: the closed chain's
        forward dynamics in (q*, qd*) under Gamma* every ``RESOLUTION_STEP`` or less over the phase,
        both ends included. At the collocation points it is the plan's own; between them it says whether
        the plan's mesh resolves the phase (module docstring)."""
        chain, least = self.chain, np.inf
        for t in np.linspace(0.0, self.duration, math.ceil(self.duration / RESOLUTION_STEP) + 1):
            q, qd, torque = self.reference(float(t))
            qdd, held = chain.forward(q, qd, torque)
            least = min(least, float(chain.wrenches(q, qd, qdd, chain.full_force(held))[:, 2].min()))
        return least

    def law(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The actuated joints' torques (N m) at ``t`` (s in the phase) in (``q``, ``qd``): the
        gain and basis of the sample nearest ``t``."""
        q_ref, qd_ref, torque = self.reference(t)
        k = int(np.argmin(np.abs(self.t - t)))
        basis = self.basis[k]
        error = np.concatenate([basis.T @ (q - q_ref), basis.T @ (qd - qd_ref)])
        return np.clip(torque - self.gain[k] @ error, -self.limits, self.limits)


def held_support(chain: ClosedChain, support) -> HeldSupport:
    """The walk's ``HeldSupport`` of the planned ``support`` (a solved ``LastingSupport`` with a
    phase, d > 0)."""
    if not support.success or support.duration <= 0.0:
        raise ValueError("a double support to walk needs a solved phase of positive duration")
    at = chain.at
    q, qd, qdd = support.x[:, at], support.xd[:, at], support.xdd[:, at]
    limits = effort_limits(chain)
    bases, gains = [], []
    for k in range(len(support.t)):
        basis = minimal_basis(chain, q[k])
        a, b = linearization(chain, q[k], qd[k], support.torques[k], basis)
        bases.append(basis)
        gains.append(lqr_gain(a, b, limits, POSITION_SCALE, RATE_SCALE))
    plan = HeldSupport(chain, support.duration, support.t, q, qd, qdd, support.torques, support.i_minus,
                       np.array(bases), np.array(gains), limits)
    least = plan.least_normal_force()
    if not least > 0.0:
        raise ValueError(f"the planned double support of {support.duration:g} s cannot be tracked: its reactions "
                         f"between its collocation points reach {least:.0f} N (a foot pulls): its mesh does not "
                         "resolve the phase (docs/model.md section 14)")
    return plan


def lasting_orbit(orbit: PlannedOrbit, support, hybrid: HybridStep, settings: Settings = DEFAULTS) -> PlannedOrbit:
    """The gait of ``orbit`` (its d = 0 plan) walked with the planned double support ``support``
    (d > 0; ``lasting_support.LastingSupport``, or anything with its fields): its single support from the
    lift-off posture (the legs exchanged) with the next step's start velocity, flown on the walk's
    grid (``settings.walk_steps``) for T to the touchdown posture q_T; the double support to track
    at its end."""
    chain = ClosedChain(hybrid.bm, hybrid.exchange)
    q0 = hybrid.exchange.configuration(np.asarray(support.x)[-1, chain.at])
    qd_a = np.asarray(support.next_start_velocity)
    arrival = hybrid.flow(settings.walk_steps).propagate(q0, qd_a, orbit.period)
    return replace(orbit, q0=q0, qd_a=qd_a, qd_b=arrival.qd, double_support=held_support(chain, support))
