"""What a walk needs of a double support that lasts (docs/model.md section 14.1): the planned
phase (``core/gait/lasting.py``'s ``LastingSupport``) as a reference to track, and the feedback
that tracks it (``tracking``: the plan's samples interpolated, the standing balance's LQR about
them). With point feet the rotation about the feet line has no actuator: the feedback moves the
body's shape to steer it, and what is left at the lift-off the next step's re-aim takes (the
duration, ``feedback``).

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

from dataclasses import dataclass, replace

import numpy as np

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings
from .orbit import PlannedOrbit
from .tracking import Tracking, tracking, tracking_with_horizon


@dataclass(frozen=True, eq=False)
class HeldSupport(Tracking):
    """A planned double support to track (``tracking.Tracking``, its ``chain`` the closed chain)
    and the planned I^- (N m s) that opens it."""

    i_minus: np.ndarray

    def least_normal_force(self) -> float:
        """The least vertical reaction (N) of either foot along the reference (``Tracking.along``:
        the closed chain's forward dynamics in (q*, qd*) under Gamma* every millisecond or less over
        the phase). At the collocation points it is the plan's own; between them it says whether
        the plan's mesh resolves the phase (module docstring)."""
        chain = self.chain
        return min(float(chain.wrenches(q, qd, qdd, chain.full_force(held))[:, 2].min())
                   for _, q, qd, _, qdd, held in self.along())


def held_support(chain: ClosedChain, support, horizon: bool = False) -> HeldSupport:
    """The walk's ``HeldSupport`` of the planned ``support`` (a solved ``LastingSupport`` with a
    phase, d > 0); ``horizon``: its feedback the finite-horizon LQR's (``tracking_with_horizon``)."""
    if not support.success or support.duration <= 0.0:
        raise ValueError("a double support to walk needs a solved phase of positive duration")
    at = chain.at
    track = tracking_with_horizon if horizon else tracking
    plan = track(chain, support.t, support.x[:, at], support.xd[:, at], support.xdd[:, at], support.torques,
                 HeldSupport, i_minus=support.i_minus)
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
