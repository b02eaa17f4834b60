"""The re-aimed impulsive double support (docs/model.md sections 8.4, 8.5): from an actual state
with the swing foot on the ground, the next step re-aimed (``feedback``), the impulses towards it
by the effort LP, and the leg exchange. It is the reset of the paper's instantaneous double
support (``impulsive``), and what the pulsed (``pulses``) and the lasting (``lasting``) double
supports end with. Units SI, rad; times in the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ...dynamics.impulses import friction_ratios, solve_impulses
from ...model.exchange import next_heading, other_side
from ..events import Fall, Touchdown
from ..orbit import PlannedOrbit
from ..state import WalkState
from .phase import WalkContext

CLOSURE_ROUNDS = 10  # re-aims per double support at most, with legs leaning (the planner's rounds)


@dataclass(frozen=True, eq=False)
class LiftOff:
    """What a lift-off from a double support that lasts changes in the re-aimed reset: the old
    stance tip's velocity before it (``slip``, m/s, the step's model axes; None: at rest) and the
    re-aim's chord steps (``reaim_steps``)."""

    slip: np.ndarray | None
    reaim_steps: int


def impulsive_double_support(ctx: WalkContext, state: WalkState, q_td: np.ndarray, qd_td: np.ndarray,
                             t_step: float, lift_off: LiftOff | None = None) -> tuple[WalkState, Touchdown]:
    """The double support at the touchdown (``q_td``, ``qd_td``) ``t_step`` s into ``state``'s step
    (docs/model.md section 8.4): the aim moved on to the next step, the next step re-aimed (or the
    plan's velocity made reachable, without re-aiming), the impulses from the actual pre-impact
    state by the effort LP, then the leg exchange; ``lift_off``: from a double support that lasts
    (None: a touchdown). The next step's start and the touchdown report; ``Fall`` if no re-aim or
    no impulses reach it."""
    feedback, s = ctx.feedback, state
    error = s.aim.orbit.touchdown_error(q_td, qd_td)
    side = other_side(s.stance_side)
    try:
        aim, xd_a, sol, planned, miss = _double_support(ctx, s, q_td, qd_td, t_step, feedback.advanced(s.aim, side), error,
                                                        lift_off)
    except Fall:
        if s.aim.pending is None:
            raise
        # a transition step the re-aim cannot make from this touchdown: put off, the walked gait aimed at again
        aim, xd_a, sol, planned, miss = _double_support(ctx, s, q_td, qd_td, t_step,
                                                        feedback.advanced(replace(s.aim, pending=None), side), error,
                                                        lift_off)
    following = exchanged(ctx, s, q_td, xd_a, t_step, aim)
    touchdown = Touchdown(
        step=s.step, t=s.t + t_step, t_step=t_step, i_minus=sol.i_minus.copy(), i_plus=sol.i_plus.copy(),
        W=sol.W, state_error=error, velocity_miss=abs(miss),
        correction=float(np.max(np.abs(xd_a[3:] - planned.xd_a[3:]))), equation_residual=sol.equation_residual,
        next_stance_side=side,
    )
    return following, touchdown


def exchanged(ctx: WalkContext, s: WalkState, q: np.ndarray, xd: np.ndarray, t_step: float, aim) -> WalkState:
    """The next step's start after a double support that ends ``t_step`` s into ``s``'s step in
    the posture ``q`` with the double-support velocity ``xd`` (the new stance tip at rest), aiming at
    ``aim``: the new stance foot's world position, then the mirror (the next step in its model
    coordinates)."""
    side = other_side(s.stance_side)
    new_foot = s.stance_foot + s.axes @ ctx.hybrid.bm.swing_tip(q)
    new_foot[2] = 0.0
    exchange = ctx.hybrid.exchange
    return WalkState(q=exchange.configuration(q), qd=exchange.velocity(q, xd), aim=aim, step=s.step + 1,
                     t=s.t + t_step, stance_side=side, stance_foot=new_foot,
                     heading=next_heading(s.heading, side, exchange.heading(q)))


def _double_support(ctx: WalkContext, s: WalkState, q_td: np.ndarray, qd_td: np.ndarray, t_step: float, aim,
                    error: float, lift_off: LiftOff | None):
    """The re-aim towards ``aim`` (the next step's) and the impulses from the touchdown (``q_td``,
    ``qd_td``) ``t_step`` s into ``s``'s step, in closure rounds with legs leaning: the aim with the
    re-aim's duration, the post-impact velocity, the impulses, the impact problem planned towards
    the plan's velocity and its velocity miss. ``Fall`` if no re-aim or no impulses reach it."""
    hybrid, feedback, bm = ctx.hybrid, ctx.feedback, ctx.hybrid.bm
    q_t, qd_b = np.asarray(s.aim.orbit.q_t), np.asarray(s.aim.orbit.qd_b)
    foot_line_moment = s.aim.orbit.foot_line_moment  # the plan's, of this double support
    impact = hybrid.impact(q_td)
    planned = impact.problem(qd_td, np.asarray(aim.orbit.qd_a))
    if lift_off is not None and lift_off.slip is not None:  # the whole robot moving with the old tip: X's first three rows
        planned = replace(planned, xd_b=planned.xd_b + np.concatenate([lift_off.slip, np.zeros(len(planned.xd_b) - 3)]))
    reaim_steps = lift_off.reaim_steps if lift_off is not None else None
    reachable, miss = planned.reachable()
    for again in range(CLOSURE_ROUNDS):  # legs leaning: the re-aim's closure matched to what the spin moments do
        if feedback.reaim:
            try:
                qd_next, next_period = feedback.reaim_velocity(aim, hybrid.exchange.configuration(q_td), impact,
                                                               planned.xd_b, foot_line_moment, again > 0, reaim_steps)
            except Fall as exc:
                momentum = float(impact.momentum_row @ planned.xd_b)
                if lift_off is not None:  # the plan's touchdown is no reference for a lift-off's state
                    raise Fall(f"{exc} (at the lift-off, t = {s.t + t_step:.4f} s, the momentum about the feet "
                               f"line, which no impulse changes, is {momentum:.2f} kg m^2/s)") from None
                planned_momentum = float(hybrid.impact(q_t).momentum_row @ bm.embed(qd_b))
                raise Fall(f"{exc} (at t = {s.t + t_step:.4f} s the momentum about the feet line, which no "
                           f"impulse changes, is {momentum:.2f} kg m^2/s where the plan's is "
                           f"{planned_momentum:.2f}, the touchdown {error:.3g} from the plan's state)") from None
            aim = replace(aim, next_period=next_period)
            problem = replace(planned, xd_a=impact.next_step_velocity(qd_next))
        else:
            problem = reachable
        xd_a = problem.xd_a
        if not np.all(np.isfinite(xd_a)):
            raise Fall(f"no reachable velocity after the touchdown at t = {s.t + t_step:.4f} s")
        sol = solve_impulses(problem, aim.orbit.effort, aim.orbit.options)
        if not sol.success:
            raise Fall(f"the double support at t = {s.t + t_step:.4f} s has no solution ({sol.message}): "
                       f"{why_no_impulses(problem, aim.orbit)}")
        done = sol.foot_line_moment(problem)
        if not feedback.reaim or abs(done - foot_line_moment) <= feedback.settings.tolerance:
            break
        foot_line_moment = done
    return aim, xd_a, sol, planned, miss


def why_no_impulses(problem, orbit: PlannedOrbit) -> str:
    """The physical reason a double support of ``orbit``'s effort and options has no impulses: the
    friction cone (the impulses exist without it, needing the friction they need: a finite
    coefficient, or none at all when a foot would need a horizontal impulse with no vertical one),
    the joint-rate bound, or none reaches the aimed velocity with the feet pushing on the ground."""
    options = orbit.options
    if math.isfinite(options.friction):
        free = solve_impulses(problem, orbit.effort, replace(options, friction=math.inf))
        if free.success:
            needed = float(friction_ratios(free).max())
            if not math.isfinite(needed):
                return (f"the impulses would need a foot to take a horizontal reaction impulse with no vertical one: "
                        f"no friction coefficient suffices (the ground's is {options.friction:g})")
            return f"the impulses would need a friction coefficient of {needed:.2f}, more than the ground's {options.friction:g}"
    if math.isfinite(options.rate_bound):
        if solve_impulses(problem, orbit.effort, replace(options, rate_bound=math.inf)).success:
            return f"the impulses would need joint rates above the bound of {options.rate_bound:g} rad/s"
    return "no impulses reach the aimed velocity with the feet pushing on the ground (unilateral contact)"
