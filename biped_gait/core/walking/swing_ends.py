"""What a walk needs of a cycle whose swing is actuated at its two ends (docs/model.md section
15.1; the plan: ``core/gait/actuated_swing.py``): its two actuated ends as references to track
(``tracking``: the single support with the stance tip pinned, ``PinnedTip``, driven by the plan's
torques and the LQR about the plan), its double support (``held_support``), and the orbit that
carries them.

**The feedback** acts in the actuated ends only; the flight between is ballistic and open loop,
and amplifies an error about 30-fold over its 0.25 s at the default gait. A gain frozen at each
sample (``tracking``, the double support's) ignores that: it tracks the start well and leaves the
flight off the plan (docs/model.md 15.1). The swing's gains are therefore the finite-horizon LQR
of the whole single support (``single_support_gains``): the linearized dynamics along the plan,
the start and the end driven, the flight undriven, on the 1 ms grid the walk integrates,
discretized to second order in h; the tracking's weights at every step (Bryson's: 0.01 rad,
0.1 rad/s against a tenth of each effort limit), the touchdown's state weighted by
``TOUCHDOWN_POSITION`` and ``TOUCHDOWN_RATE`` and, above them, the swing tip's height and velocity
there (``TIP_HEIGHT``, ``TIP_SPEED``: the touchdown is at the planned instant T, and the cycle is
unstable under the phases' feedback, so without them the tip drifts from the ground step after step,
docs/model.md 15.1); the Riccati recursion run backwards from the touchdown, so the
start's gains steer the flight towards the end's reference.

**The reference** (``SwingReference``): the plan's samples as ``tracking`` interpolates them, the
torques between them Hermite-Simpson's own quadratics (linear ones are no motion of the single
support at this mesh).

**Resolution.** The plan holds the single support's equations at its collocation points only
(Hermite-Simpson over each end: 10 intervals by default, 20 in ``SwingRequest.walkable``), and
Hermite-Simpson can ring between them (docs/model.md 14: the stop and the start were refused for it). Along the reference the
stance tip's reaction, from the single support's forward dynamics every millisecond, must press
within the floor's friction (``SwingEnds.reactions``); ``actuated_orbit`` refuses a plan whose
reference does not, with the figures.

Times in each end (s from its start); q, qd in the step's model coordinates. Units SI, rad.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.flow import hermite_samples
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings
from ..model.biped import SWING_TIP
from .balance import FD_STEP, TORQUE_SCALE, effort_limits, linearization
from .held_support import held_support
from .orbit import PlannedOrbit
from .phases.pulse_dynamics import PinnedTip, friction_ratio
from .tracking import POSITION_SCALE, RATE_SCALE, RESOLUTION_STEP, Tracking, riccati_gains

# The touchdown's state in the swing's LQR (its terminal weight, Bryson's). Measured on the walkable
# plan at the default gait (docs/model.md 15.1): (0.001 rad, 0.01 rad/s) walks two steps, (0.01, 0.1)
# and these three, the touchdowns 0.003 rad/s off the plan's state.
TOUCHDOWN_POSITION = 0.1  # rad
TOUCHDOWN_RATE = 1.0  # rad/s
# The swing tip at the touchdown in the same cost (Bryson's): its height and each component of its
# velocity. Measured with the reaction guard (docs/model.md 15.1): without them the walk falls in its
# fourth step (the tip 2.35 mm above the ground at T); with these it walks 32 steps; with the height
# at 0.1 mm 22, at 3 mm all 45 asked but with the tip within 0.11 mm of the walk's 1 mm at T; with
# the speed at 3 mm/s 39.
TIP_HEIGHT = 1e-3  # m
TIP_SPEED = 1e-3  # m/s


@dataclass(frozen=True, eq=False)
class SwingEnds:
    """The actuated ``start`` and ``end`` of the swing, each a ``tracking.Tracking`` of the single
    support driven (its chain a ``PinnedTip``), times from its own start."""

    start: Tracking
    end: Tracking

    @property
    def duration(self) -> float:
        """tau (s): how long each end is actuated."""
        return self.start.duration

    def reactions(self, which: str) -> tuple[np.ndarray, np.ndarray]:
        """Along the reference of the end ``which`` (``start`` or ``end``; ``Tracking.along``, every
        millisecond): the instants (s in the end) and the stance tip's reaction there (n x 3, N,
        world axes of the step's model), the single support's forward dynamics under the plan's
        torques in the plan's interpolated state."""
        rows = [(t, force) for t, _, _, _, _, force in getattr(self, which).along()]
        return np.array([t for t, _ in rows]), np.array([force for _, force in rows])


def touchdown_tip(bm, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """The swing tip's height and velocity (m, m/s; world axes of the step's model) linearized about
    the single-support state (``q``, ``qd``): rows (4 x 2 nq) over (delta q, delta qd), the height's
    from the tip's Jacobian, the velocity's J(q) qd by central differences (``FD_STEP``)."""
    model, data = bm.single, bm.single_data
    frame = model.getFrameId(SWING_TIP)

    def jacobian(at: np.ndarray) -> np.ndarray:
        return pin.computeFrameJacobian(model, data, at, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]

    n = len(q)
    rows = np.zeros((4, 2 * n))
    j = jacobian(q)
    rows[0, :n], rows[1:, n:] = j[2], j
    for k in range(n):
        e = np.zeros(n)
        e[k] = FD_STEP
        rows[1:, k] = (jacobian(q + e) @ qd - jacobian(q - e) @ qd) / (2 * FD_STEP)
    return rows


def single_support_gains(pinned: PinnedTip, start: Tracking, end: Tracking, flight_nodes: tuple,
                         period: float) -> np.ndarray:
    """The finite-horizon LQR's gains (module docstring) at every ``RESOLUTION_STEP`` of the single
    support of ``period`` s: the actuated ``start`` and ``end`` (their references) and the flight
    between (``flight_nodes``: the walk's flow from the start's end). Rows of (nA x 2 nq), from the
    lift-off to the touchdown."""
    n, h, tau = pinned.bm.nq, RESOLUTION_STEP, start.duration
    times = np.linspace(0.0, period, round(period / h) + 1)
    limits = effort_limits(pinned)
    identity = np.eye(n)
    steps = []
    for t in times:
        if tau < t < period - tau:  # the flight: no torque, none to feed back
            q, qd = (row[0] for row in hermite_samples(flight_nodes, np.array([t - tau])))
            a = linearization(pinned, q, qd, np.zeros(len(limits)), identity)[0]
            b = np.zeros((2 * n, len(limits)))
        else:
            plan = start if t <= tau else end
            q, qd, torque = plan.reference(t if t <= tau else t - (period - tau))
            a, b = linearization(pinned, q, qd, torque, identity)
        steps.append((np.eye(2 * n) + h * a + h * h / 2 * a @ a, h * b + h * h / 2 * a @ b, h))
    weight = np.diag(np.concatenate([np.full(n, POSITION_SCALE ** -2.0), np.full(n, RATE_SCALE ** -2.0)]))
    effort = np.diag((TORQUE_SCALE * limits) ** -2.0)
    cost = np.diag(np.concatenate([np.full(n, TOUCHDOWN_POSITION ** -2.0), np.full(n, TOUCHDOWN_RATE ** -2.0)]))
    tip = touchdown_tip(pinned.bm, *end.reference(end.duration)[:2])
    cost = cost + tip.T @ np.diag(np.array([TIP_HEIGHT, TIP_SPEED, TIP_SPEED, TIP_SPEED]) ** -2.0) @ tip
    return riccati_gains(steps, weight, effort, cost)


@dataclass(frozen=True, eq=False)
class SwingReference(Tracking):
    """An actuated end's ``Tracking`` whose torques between the samples are Hermite-Simpson's own:
    quadratic through each interval's node, midpoint and node. Linear ones are no motion of the
    single support at this mesh: flown open loop from the plan's first state (SciPy's DOP853) they
    end the default gait's actuated end 0.74 rad/s off the plan's last state, where these end 0.003
    (docs/model.md 15.1)."""

    def torque(self, t: float) -> np.ndarray:
        k = min(int(np.searchsorted(self.t, t, side="right") - 1) // 2, len(self.t) // 2 - 1)
        t0, t1 = self.t[2 * k], self.t[2 * k + 2]
        s = (t - t0) / (t1 - t0)
        g0, gm, g1 = self.torques[2 * k:2 * k + 3]
        return g0 * (1 - s) * (1 - 2 * s) + gm * 4 * s * (1 - s) + g1 * s * (2 * s - 1)


def swing_tracking(pinned: PinnedTip, end) -> SwingReference:
    """The reference of an actuated end of the swing (``actuated_swing.SwingEnd``: its samples in the
    double-support coordinates, the stance tip at the origin), without feedback yet (``with_gains``)."""
    at = np.asarray(pinned.bm.ds_of_single)
    t = end.t - end.t[0]
    n, limits = pinned.bm.nq, effort_limits(pinned)
    return SwingReference(pinned, float(t[-1]), t, end.x[:, at], end.xd[:, at], end.xdd[:, at], end.torques,
                          np.zeros(1), np.eye(n)[None], np.zeros((1, len(limits), 2 * n)), limits)


def with_gains(plan: Tracking, gains: np.ndarray) -> Tracking:
    """``plan`` fed back by ``gains`` at every ``RESOLUTION_STEP`` of it (``single_support_gains``)."""
    n = plan.chain.bm.nq
    return replace(plan, gain_t=np.linspace(0.0, plan.duration, len(gains)), basis=np.array([np.eye(n)] * len(gains)),
                   gain=gains)


def actuated_orbit(orbit: PlannedOrbit, cycle, hybrid: HybridStep, settings: Settings = DEFAULTS) -> PlannedOrbit:
    """The gait of ``orbit`` walked with the swing actuated at its two ends as ``cycle`` plans it (a
    solved ``actuated_swing.ActuatedSwingCycle`` with a double support that lasts, d > 0): the step
    from the actuated start's first state (the lift-off, legs exchanged) to the actuated end's last
    (the touchdown, on q_T), its ends (their gains through the flight flown on the walk's grid,
    ``settings.walk_steps``) and its double support to track. ``ValueError`` if the cycle
    is not solved, has no double support, or its reference pulls or slips between the collocation
    points (module docstring)."""
    if not cycle.success:
        raise ValueError(f"cannot walk a cycle that was not solved: {cycle.message}")
    pinned = PinnedTip(hybrid.bm)
    n, tau, period = hybrid.bm.nq, cycle.actuated_swing, orbit.period
    flight = hybrid.flow(settings.walk_steps).propagate(cycle.flow_start[:n], cycle.flow_start[n:], period - 2 * tau,
                                                          keep_nodes=True).nodes
    start, end = swing_tracking(pinned, cycle.start), swing_tracking(pinned, cycle.end)
    gains = single_support_gains(pinned, start, end, flight, period)
    each = round(tau / RESOLUTION_STEP) + 1
    ends = SwingEnds(with_gains(start, gains[:each]), with_gains(end, gains[-each:]))
    mu = hybrid.bm.params.friction
    for which in ("start", "end"):
        t, forces = ends.reactions(which)
        least, ratio = float(forces[:, 2].min()), friction_ratio(forces)
        if not (least > 0.0 and ratio <= mu):
            raise ValueError(f"the actuated {which} of the swing cannot be tracked: between its collocation points the "
                             f"stance tip's vertical reaction falls to {least:.0f} N and its friction ratio reaches "
                             f"{ratio:.3f} (mu = {mu:g}): its mesh does not resolve the phase (docs/model.md section 15.1)")
    support = held_support(ClosedChain(hybrid.bm, hybrid.exchange), cycle.support)
    return replace(orbit, q0=ends.start.q[0], qd_a=ends.start.qd[0], q_t=ends.end.q[-1], qd_b=ends.end.qd[-1],
                   double_support=support, swing_ends=ends)
