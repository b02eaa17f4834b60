"""A double support that lasts, walked as torque pulses around the impact (docs/model.md sections
10 and 11.2-11.3): the phase of section 10, d / 2 of constant joint torques on each side
of a passive impact, with the walk's re-aim as the feedback. Its phases:

- ``Coast``: the ballistic single support, until the double support is planned
  ``DECISION_LEAD`` s before its pre-impact pulse is due (when, the last re-aim's duration tells;
  the planner's model again at mid-step and after a push);
- ``Approach``: the pre-impact pulse, constant torques u^- from d / 2 before the predicted
  touchdown until the swing foot's (the old stance foot on the ground); its reset the passive
  impact in the engine's own model, then the leg exchange;
- ``Departure``: the post-impact pulse, constant torques u^+ over the next step's first d / 2 s.

**The plan** (``Coast``'s reset). From the engine's state it predicts the ballistic touchdown with
the planner's flow and guard, and hands that pre-impact state to the impulsive double support's
reset (``reaim.impulsive_double_support``): the re-aim of the next step (with momentum
steering if the walk has it) and the LP's impulses I^-, I^+, exactly as the impulsive walk does at
its touchdown. The pulses u = I / (d / 2) reach that re-aimed next step only as d -> 0: the
configuration moves during them (the joints at up to 16 rad/s), and the open-loop step amplifies
the difference. So the torques are corrected, with the planner's model (``_Correction``), until
the pulsed phase lands on the re-aimed next step: unknowns the torques u^- and u^+ (2 nA) and the
next step's duration tau; equations: the swing tip on the ground at the pre-impact pulse's end
(1), and the next step's configuration at tau the re-aimed one's at its touchdown (nq);
constraints: the stance tip's reaction in the friction cone (the inscribed octagonal pyramid) with
a positive normal force at every node of both pulses, the impact's reaction likewise, the old
stance foot leaving, the swing tip coming down; Gauss-Newton (``pulse_dynamics.gauss_newton``:
least-norm steps, the constraints' least move) from the impulses spread plus the last
correction's offset from its own, to ``TOLERANCE``. The next step then starts from whatever the
engine made of the pulses.

Units SI, rad; times in the step unless said "in the walk".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ...dynamics.hybrid import passive_impact
from ...model.exchange import exchange_matrix, next_heading, other_side
from ..engines.engine import Motion, Pulse
from ..events import Fall, Touchdown
from ..state import Aim, WalkState
from .impulsive import single_support_guard
from .phase import TIME_TOLERANCE, TOUCHDOWN, End, Guard, Phase, Transition, WalkContext
from .pulse_dynamics import FD_STEP, CorrectionFailed, cone_rows, friction_ratio, gauss_newton, pulse
from .reaim import impulsive_double_support

DECISION_LEAD = 0.01  # s: the double support is planned this long before its pre-impact pulse is due
TOLERANCE = 1e-7  # m, rad: the corrected pulses land on the re-aimed next step to this (the next re-aim takes the rest)
PULSE_STEPS = 8  # RK4 steps of a pulse in the correction's model


@dataclass(frozen=True, eq=False)
class Pulses:
    """The walk's pulsed double support: its duration d (s), and what one correction leaves the
    next (its warm start): its offset from its impulses spread, and the pulsed phase's Jacobian."""

    duration: float
    offset: np.ndarray | None = None
    phase_jacobian: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not self.duration > 0:
            raise ValueError(f"the pulse duration must be positive, got {self.duration} s")

    @property
    def half(self) -> float:
        return self.duration / 2


@dataclass(frozen=True, eq=False)
class PulsedTouchdown:
    """One double support walked as pulses (units SI, rad): the step; the engine's touchdown time
    (s in the walk); the planner's predicted ballistic touchdown from the decision's state (time in
    the walk, q, qd); the engine's pre-impact state (q, qd, after the pre-impact pulse); the torques
    u^- (this step's actuated joints) and u^+ (the next step's), N m; their effort E = (d / 2) sum |u|
    (N m s) beside the impulses' W; the correction's residual (m, rad) and Gauss-Newton steps; the
    friction the planned phase needs (the largest |F_xy| / F_z at the pulses' nodes in the planner's
    model)."""

    step: int
    t: float
    t_predicted: float
    q_predicted: np.ndarray
    qd_predicted: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    u_minus: np.ndarray
    u_plus: np.ndarray
    effort: float
    impulsive_effort: float
    residual: float
    corrections: int
    friction_planned: float

    @property
    def peak_torque(self) -> float:
        """The largest pulse torque (N m)."""
        return float(np.max(np.abs(np.concatenate([self.u_minus, self.u_plus]))))


@dataclass(frozen=True, eq=False)
class PulsePlan:
    """A planned double support: the impulsive reset's touchdown report and next step (re-aimed,
    its duration the correction's), the pre-impact pulse's start (s in the step), the predicted
    ballistic touchdown (time in the step, q, qd), the corrected torques (N m, full q vectors: this
    step's u^-, the next step's u^+), the correction's residual and steps, and the friction its
    pulses need (the largest |F_xy| / F_z at their nodes)."""

    touchdown: Touchdown
    following: WalkState
    start: float
    t_hit: float
    q_hit: np.ndarray
    qd_hit: np.ndarray
    u_minus: np.ndarray
    u_plus: np.ndarray
    residual: float
    corrections: int
    friction: float


def predict(ctx: WalkContext, aim: Aim, q: np.ndarray, qd: np.ndarray, t_step: float) -> tuple[float, np.ndarray, np.ndarray]:
    """The ballistic touchdown from (``q``, ``qd``) at ``t_step`` (s in the step) with the
    planner's flow and guard (``aim``: the current step's): its time in the step and its state."""
    flow, guard = ctx.hybrid.flow(1), ctx.hybrid.guard(0.5 * aim.period)
    h, limit = aim.period / ctx.grid, 2.0 * aim.period
    while t_step < limit:
        run = flow.propagate(q, qd, h, keep_nodes=True)
        hit = guard.touchdown((run.nodes[0] + t_step, *run.nodes[1:]))
        if hit is not None:
            end = flow.propagate(q, qd, hit - t_step)
            return hit, end.q, end.qd
        t_step, q, qd = t_step + h, run.q, run.qd
    raise Fall("the planner's model predicts no touchdown from the engine's state within 2 T")


@dataclass(frozen=True, eq=False)
class Coast(Phase):
    """The ballistic single support until the double support is planned (module docstring), at
    ``decide_at`` (s in the step; None: the last re-aim's duration less d / 2 and the lead), once
    the touchdown has been predicted at mid-step (``predicted``)."""

    pulses: Pulses
    decide_at: float | None = None
    predicted: bool = False

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(state.aim.period / ctx.grid)

    def _decide_at(self, state: WalkState) -> float:
        if self.decide_at is not None:
            return self.decide_at
        return state.aim.next_period - self.pulses.half - DECISION_LEAD

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        mid = 0.5 * state.aim.period
        return replace(single_support_guard(state),
                       after=self._decide_at(state) if self.predicted else min(mid, self._decide_at(state)))

    def _predicted(self, ctx: WalkContext, state: WalkState, q: np.ndarray, qd: np.ndarray, t: float) -> "Coast":
        """This phase with the decision when the planner's model, from (``q``, ``qd``) at ``t``,
        says the pre-impact pulse is due."""
        t_hit = predict(ctx, state.aim, q, qd, t)[0]
        return replace(self, decide_at=t_hit - self.pulses.half - DECISION_LEAD)

    def pushed(self, ctx: WalkContext, state: WalkState, t: float, q: np.ndarray, qd: np.ndarray) -> "Coast":
        return self._predicted(ctx, state, q, qd, t)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        moved = state.moved(end.t, end.q, end.qd)
        if end.event == TOUCHDOWN:
            raise Fall(f"the swing foot landed at t = {state.t + end.t:.4f} s, before its double support was planned")
        if not self.predicted and end.t >= 0.5 * state.aim.period - TIME_TOLERANCE:
            return Transition(replace(self._predicted(ctx, state, end.q, end.qd, end.t), predicted=True), moved)
        plan, pulses = self._plan(ctx, state, end)
        return Transition(Approach(pulses, plan), moved)

    def _plan(self, ctx: WalkContext, s: WalkState, end: End) -> tuple[PulsePlan, Pulses]:
        """The double support planned from the engine's state at ``end`` (module docstring, the
        plan), and the pulses' settings with this correction's warm start for the next."""
        pulses, half = self.pulses, self.pulses.half
        q, qd, t_step = end.q, end.qd, end.t
        t_hit, q_hit, qd_hit = predict(ctx, s.aim, q, qd, t_step)
        following, touchdown = impulsive_double_support(ctx, s, q_hit, qd_hit, t_hit)
        flow = ctx.feedback.step_flow
        target = flow.propagate(following.q, following.qd, following.aim.next_period).q
        start = max(t_step, t_hit - half)
        q_s, qd_s = q, qd
        if start > t_step:  # the planner's state where the pre-impact pulse starts
            run = ctx.hybrid.flow(1).propagate(q, qd, start - t_step)
            q_s, qd_s = run.q, run.qd
        correction = _Correction(ctx, pulses.duration, q_s, qd_s, target, pulses.phase_jacobian)
        joints = _exchange_joints(ctx)
        spread = np.concatenate([[following.aim.next_period], joints @ touchdown.i_plus / half,
                                 touchdown.i_minus / half])
        z, steps = correction.solve(spread, pulses.offset)
        residual, _, forces = correction.evaluate(z)
        following = replace(following, aim=replace(following.aim, next_period=float(z[0])))
        na = correction.na
        plan = PulsePlan(touchdown, following, start, t_hit, q_hit, qd_hit, correction.torque(z[1 + na:]),
                         correction.torque(z[1:1 + na]), float(np.max(np.abs(residual))), steps, friction_ratio(forces))
        return plan, replace(pulses, offset=z - spread, phase_jacobian=correction.phase_jacobian)


def _exchange_joints(ctx: WalkContext) -> np.ndarray:
    """u^+ in the next step's joints from I^+ in this step's (section 10: a signed
    permutation of the actuated joints, its own inverse transpose)."""
    bm = ctx.hybrid.bm
    return exchange_matrix(bm.coordinates)[np.ix_(bm.actuated, bm.actuated)]


@dataclass(frozen=True, eq=False)
class Approach(Phase):
    """The pre-impact pulse of ``plan`` until the swing foot's touchdown (module docstring); its
    reset the passive impact in the engine's model and the leg exchange, then the post-impact
    pulse."""

    pulses: Pulses
    plan: PulsePlan

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(state.aim.period / ctx.grid, (Pulse(self.plan.u_minus, self.plan.start, math.inf),))

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return single_support_guard(state)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        """The engine's touchdown (the pushes still due acting on it): the passive impact in the
        engine's model and the leg exchange; the touchdown report with the engine's time and what
        the pulses applied (their integrals (d / 2) u as I^-, I^+, I^+ in this step's joints, their
        effort E as W; its state error the predicted ballistic touchdown's, as the impulsive
        walk's)."""
        s, plan, half = state, self.plan, self.pulses.half
        bm, exchange = ctx.hybrid.bm, ctx.hybrid.exchange
        q_c, qd_c, t_c = end.q, end.qd, state.t + end.t
        tip = s.stance_foot + s.axes @ bm.swing_tip(q_c)
        tip[2] = 0.0
        following = replace(plan.following, q=exchange.configuration(q_c), qd=ctx.engine.passive_impact(q_c, qd_c),
                             t=t_c, stance_foot=tip,
                             heading=next_heading(s.heading, other_side(s.stance_side), exchange.heading(q_c)))
        actuated, td = bm.actuated, plan.touchdown
        record = PulsedTouchdown(
            step=s.step, t=t_c, t_predicted=s.t + plan.t_hit, q_predicted=plan.q_hit, qd_predicted=plan.qd_hit, q=q_c,
            qd=qd_c, u_minus=plan.u_minus[actuated], u_plus=plan.u_plus[actuated],
            effort=float(half * (np.abs(plan.u_minus).sum() + np.abs(plan.u_plus).sum())), impulsive_effort=td.W,
            residual=plan.residual, corrections=plan.corrections, friction_planned=plan.friction)
        touchdown = replace(td, t=t_c, t_step=end.t, i_minus=half * plan.u_minus[actuated],
                            i_plus=half * _exchange_joints(ctx).T @ plan.u_plus[actuated], W=record.effort,
                            double_support=record)
        return Transition(Departure(self.pulses, plan.u_plus), following, (touchdown,))


@dataclass(frozen=True, eq=False)
class Departure(Phase):
    """The post-impact pulse, constant torques ``u_plus`` (N m, q order) over the step's first
    d / 2 s; then the ballistic single support."""

    pulses: Pulses
    u_plus: np.ndarray

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(state.aim.period / ctx.grid, (Pulse(self.u_plus, 0.0, self.pulses.half),))

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return Guard(at=self.pulses.half)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        return Transition(Coast(self.pulses), state.moved(end.t, end.q, end.qd))


class _Correction:
    """The pulses' correction (module docstring) for pulses of ``duration`` d (s): z = (tau, u^+,
    u^-), tau the next step's duration (s), u^+ (the next step's actuated joints) and u^- (this
    step's), N m; from the pre-impact pulse's start (``q_s``, ``qd_s``: rad, rad/s) to the next
    step's configuration at tau, ``target`` (rad)."""

    def __init__(self, ctx: WalkContext, duration: float, q_s: np.ndarray, qd_s: np.ndarray, target: np.ndarray,
                 phase_jacobian: np.ndarray | None = None) -> None:
        self.hybrid, self.flow = ctx.hybrid, ctx.feedback.step_flow
        self.coarse = ctx.hybrid.flow(ctx.feedback.settings.coarse_steps)  # the sensitivities' grid
        self.q_s, self.qd_s, self.target = q_s, qd_s, target
        self.duration, self.friction = duration, ctx.hybrid.bm.params.friction
        self.actuated, self.na = ctx.hybrid.bm.actuated, len(ctx.hybrid.bm.actuated)
        # d(next state, tip height, constraints) / d torques: given (the last double support's), or by differences
        self.phase_jacobian = phase_jacobian

    def torque(self, u: np.ndarray) -> np.ndarray:
        """The joint torques (nq, q order, N m) of the actuated joints' ``u``."""
        out = np.zeros(self.hybrid.bm.nq)
        out[self.actuated] = u
        return out

    def phase(self, u_plus: np.ndarray, u_minus: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
        """The pulsed phase of the torques ``u_plus``, ``u_minus`` (N m): the next step's state at
        the post-impact pulse's end (q, qd stacked, rad, rad/s), the swing tip's height at the
        pre-impact pulse's end (m), the constraints of ``evaluate`` and the stance tips' reactions
        at the pulses' nodes (N)."""
        hybrid, bm, half = self.hybrid, self.hybrid.bm, self.duration / 2
        q_e, qd_e, before = pulse(hybrid, self.q_s, self.qd_s, self.torque(u_minus), half, PULSE_STEPS)
        impact = hybrid.impact(q_e)
        landing = passive_impact(impact, qd_e)
        exchange = hybrid.exchange
        q_p, qd_p, after = pulse(hybrid, exchange.configuration(q_e), exchange.velocity(q_e, landing.xd_plus),
                                 self.torque(u_plus), half, PULSE_STEPS)
        forces = np.vstack([before, after])
        arrival = float(impact.j2[2] @ bm.embed(qd_e))
        constraints = np.concatenate([cone_rows(forces * half, self.friction).ravel(),
                                      cone_rows(landing.reaction, self.friction), [-landing.old_foot_vz, arrival]])
        return np.concatenate([q_p, qd_p]), float(bm.swing_tip(q_e)[2]), constraints, forces

    def evaluate(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The equations' residual (the next configuration at tau less the target, rad; the swing
        tip's height at the pulse's end, m), the constraints (<= 0: the stance tip's reaction at
        every node of both pulses in the friction cone with a positive normal force, as impulses
        over d / 2 (N s), the passive impact's reaction likewise, the old stance foot leaving, the
        swing tip coming down), and the stance tips' reactions at the pulses' nodes (N)."""
        na, n = self.na, self.hybrid.bm.nq
        state, height, constraints, forces = self.phase(z[1:1 + na], z[1 + na:])
        with np.errstate(over="ignore", invalid="ignore"):
            run = self.flow.propagate(state[:n], state[n:], z[0] - self.duration / 2)
        return np.append(run.q - self.target, height), constraints, forces

    def solve(self, z: np.ndarray, guess: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """z with the equations met to ``TOLERANCE`` and the constraints, from ``z`` (or
        ``z + guess`` if its residual is smaller), and the Gauss-Newton steps taken
        (``pulse_dynamics.gauss_newton``; the torques scaled by their largest, tau in s; the
        Jacobian ``differences``: the flow's at each step, the pulsed phase's given
        (``phase_jacobian``) or at the first step, and again when a step cannot lower the merit).
        ``Fall`` if it does not converge."""
        if guess is not None:  # the last double support's correction, if it does better
            if np.max(np.abs(self.evaluate(z + guess)[0])) < np.max(np.abs(self.evaluate(z)[0])):
                z = z + guess
        try:
            return gauss_newton(self.evaluate, lambda x, r, c, fresh: self.differences(x, r, c, phase=fresh), z,
                                self.scale, TOLERANCE, fresh=self.phase_jacobian is None)
        except CorrectionFailed as exc:
            raise Fall(f"the double support's pulses of {self.duration * 1e3:g} ms cannot reach the re-aimed next "
                       f"step within the friction cone: {exc}") from None

    def scale(self, z: np.ndarray) -> np.ndarray:
        """The unknowns' units: tau in s, the torques in their largest (N m)."""
        return np.append(1.0, np.full(2 * self.na, max(1.0, float(np.max(np.abs(z[1:]))))))

    def differences(self, z: np.ndarray, residual: np.ndarray, constraints: np.ndarray,
                    phase: bool = True) -> np.ndarray:
        """d(residual, constraints) / dz: the flow after the pulsed phase by its sensitivities at z
        (on the planner's coarse grid), the phase by forward differences (``phase``), or as the
        last differences found (short pulses: the phase is nearly linear in the torques)."""
        na, n, half = self.na, self.hybrid.bm.nq, self.duration / 2
        scale = self.scale(z)
        state, height, _, _ = self.phase(z[1:1 + na], z[1 + na:])
        run = self.coarse.propagate(state[:n], state[n:], z[0] - half, np.eye(2 * n))
        if phase or self.phase_jacobian is None:
            columns = []
            for k in range(1, len(z)):
                dz = np.zeros(len(z))
                dz[k] = FD_STEP * scale[k]
                moved, h, c, _ = self.phase(z[1:1 + na] + dz[1:1 + na], z[1 + na:] + dz[1 + na:])
                columns.append(np.concatenate([moved - state, [h - height], c - constraints]) / dz[k])
            self.phase_jacobian = np.array(columns).T
        d_state, d_rest = self.phase_jacobian[:2 * n], self.phase_jacobian[2 * n:]
        jac = np.zeros((len(residual) + len(constraints), len(z)))
        jac[:n, 0] = run.qd
        jac[:n, 1:] = run.sens[:n] @ d_state
        jac[n:, 1:] = d_rest
        return jac


