"""The swing actuated at its two ends, walked (docs/model.md section 15.1; the plan:
``core/gait/actuated_swing.py``, what the walk needs of it: ``swing_ends``). One step:

1. **the actuated start** (``ActuatedStart``, tau s from the lift-off): the single support, the
   stance tip pinned (``PinnedTip``), driven by the plan's torques Gamma*(t) and the LQR that tracks
   the plan's state (``tracking``'s law, as the double support's; its gains the swing's LQR through
   the flight, ``swing_ends``);
2. **the flight** (``Flight``, to T - tau): ballistic, the planner's own flow; the swing foot
   landing in it is a fall;
3. **the actuated end** (``ActuatedEnd``, tau s, to the plan's touchdown at T): as the start;
4. **the held touchdown** at T, instantaneous: the swing tip must be within ``TOUCHDOWN_HEIGHT``
   of the ground then. The plan's landing is soft (its held impact's impulses are zero, and it has
   no I^-); off the plan the passive impact would leave a held impulse pulling (docs/model.md
   15.1), so the walk takes the I^- that the lasting walk's touchdown takes (``lasting.held_landing``:
   both tips pressing within the pyramid, the phase started nearest the plan's velocity), reported
   as the step's I^- (here the plan's is zero: what it applies is the landing's correction);
5. **the double support** (``lasting.LastingDoubleSupport``'s phase, d s, the closed chain tracked);
6. **the lift-off** (``ContinuousLiftOff``), the state continuous (no I^+: the old foot leaves from
   rest, the next actuated start accelerates it), the legs exchanged; then the next step's 1.

No re-aim: the feedback acts through the tracked phases only (1, 3 and 5); the flight between is
open loop. Units SI, rad; times in the step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...model.exchange import other_side
from ..engines.engine import Motion
from ..events import DOUBLE_SUPPORT, Fall, Touchdown
from ..state import WalkState
from ..tracking import Tracking
from .held import tracked
from .lasting import LastingDoubleSupport, held_touchdown
from .phase import TOUCHDOWN, End, Guard, Phase, Transition, WalkContext
from .pulse_dynamics import ground_reaction
from .reaim import exchanged

TOUCHDOWN_HEIGHT = 1e-3  # m: the swing tip this close to the ground at the planned touchdown is on it (the runner's LIFT_LIMIT)


@dataclass(frozen=True, eq=False)
class ActuatedSwing(Phase):
    """An actuated end of the swing: the single support driven by ``plan``'s torques and the
    feedback tracking it (``plan``: a ``tracking.Tracking`` whose chain is the ``PinnedTip``), from
    ``start`` (s in the step) for the plan's duration (module docstring)."""

    plan: Tracking
    start: float

    @property
    def friction(self) -> float:
        """The parameter set's: the stance tip's reaction, which the torques change, is checked."""
        return self.plan.chain.bm.params.friction

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return tracked(self.plan, self.start, guard=True)

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return Guard(at=self.start + self.plan.duration)

    def evaluate(self, ctx: WalkContext, q: np.ndarray, qd: np.ndarray,
                 torques: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The stance tip's reaction under the torques that act (``pulse_dynamics.ground_reaction``)."""
        forces = np.zeros((len(q), 1, 4))
        for k in range(len(q)):
            forces[k, 0, :3] = ground_reaction(ctx.hybrid, q[k], qd[k], torques[k])
        return forces, ctx.hybrid.samples.dynamics(q, qd).lowest_link


@dataclass(frozen=True, eq=False)
class ActuatedStart(ActuatedSwing):
    """The actuated start of the swing; then the flight."""

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        return Transition(Flight(self.start + self.plan.duration), state.moved(end.t, end.q, end.qd))


@dataclass(frozen=True, eq=False)
class Flight(Phase):
    """The ballistic single support from ``start`` (s in the step) to the actuated end (T - tau);
    the swing foot landing in it is a fall."""

    start: float

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(state.aim.period / ctx.grid)

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        ends = state.aim.orbit.swing_ends
        return Guard(touchdown_after=self.start, at=state.aim.period - ends.duration)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        if end.event == TOUCHDOWN:
            raise Fall(f"the swing foot landed at t = {state.t + end.t:.4f} s, before its actuated end")
        ends = state.aim.orbit.swing_ends
        return Transition(ActuatedEnd(ends.end, end.t), state.moved(end.t, end.q, end.qd))


@dataclass(frozen=True, eq=False)
class ActuatedEnd(ActuatedSwing):
    """The actuated end of the swing; then the held touchdown (module docstring) and the double
    support, which lifts off into the next step's actuated start."""

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        plan = state.aim.orbit.double_support
        chain = plan.chain
        when = f"at the planned touchdown, t = {state.t + end.t:.4f} s"
        height = float(chain.bm.swing_tip(end.q)[2])
        if abs(height) > TOUCHDOWN_HEIGHT:
            raise Fall(f"{when}, the swing tip is {abs(height) * 1e3:.2f} mm {'above' if height > 0 else 'below'} "
                       "the ground")
        report, held = held_touchdown(plan, state, end)
        aim = ctx.feedback.advanced(state.aim, other_side(state.stance_side))
        after = ActuatedStart(aim.orbit.swing_ends.start, 0.0)
        return Transition(ContinuousLiftOff(plan, end.t, report, after), state.moved(end.t, end.q, held.qd))


@dataclass(frozen=True, eq=False)
class ContinuousLiftOff(LastingDoubleSupport):
    """The double support of a cycle with an actuated swing (``LastingDoubleSupport``'s motion),
    whose lift-off keeps the state: no I^+, the legs exchanged, then ``after`` (the next step's
    actuated start)."""

    kind = DOUBLE_SUPPORT

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        """The lasting double support's, its torques guarded (``reaction_guard``)."""
        return tracked(self.plan, self.start, guard=True)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        """The lift-off: the next step starts in the phase's end state mirrored (the new stance tip
        at rest, as the chain holds it; with legs of pitch joints only its sideways drift, second
        order in the roll over the feet line, ``ClosedChain.lateral_drift``, is dropped). The
        step's ``W``: the touchdown's sum |I^-| (N m s)."""
        aim = ctx.feedback.advanced(state.aim, other_side(state.stance_side))
        following = exchanged(ctx, state, end.q, self.chain.bm.embed(end.qd), end.t, aim)
        report = self.report
        touchdown = Touchdown(step=state.step, t=state.t + end.t, t_step=end.t, i_minus=report.i_minus,
                              i_plus=np.zeros_like(report.i_minus), W=float(np.abs(report.i_minus).sum()),
                              state_error=report.state_error, velocity_miss=0.0,
                              correction=0.0, equation_residual=0.0, next_stance_side=following.stance_side,
                              double_support=report)
        return Transition(self.after, following, (touchdown,))
