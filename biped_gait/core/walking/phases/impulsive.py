"""The paper's walk as phases (docs/model.md sections 8.2-8.5): the ballistic single support,
ended by the swing foot's touchdown, and the instantaneous double support, whose reset re-aims
the next step from the actual pre-impact state (``feedback``), re-solves the impulses by the
effort LP towards it and exchanges the legs (``reaim``). A step whose plan has a double support
that lasts goes on to it instead (``lasting``). Units SI, rad; times in the step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..engines.engine import Motion
from ..events import DOUBLE_SUPPORT
from ..state import WalkState
from .lasting import HeldTouchdown
from .phase import End, Guard, Phase, Transition, WalkContext
from .reaim import impulsive_double_support


def single_support_guard(state: WalkState) -> Guard:
    """The swing foot's touchdown, armed at mid-step (the aimed T / 2); no touchdown within 2 T is
    a fall."""
    period = state.aim.period
    return Guard(touchdown_after=0.5 * period, deadline=2.0 * period,
                 overdue=f"the swing foot did not land within 2 T = {2.0 * period:.3f} s")


@dataclass(frozen=True, eq=False)
class ImpulsiveDoubleSupport(Phase):
    """The paper's instantaneous double support (eqs. 6-10) at the touchdown the state is in: its
    reset re-aims the next step, finds the impulses and exchanges the legs; then the next step's
    single support."""

    kind = DOUBLE_SUPPORT

    def motion(self, ctx: WalkContext, state: WalkState) -> None:
        return None

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        following, touchdown = impulsive_double_support(ctx, state, end.q, end.qd, end.t)
        return Transition(SingleSupport(self), following, (touchdown,))


@dataclass(frozen=True, eq=False)
class SingleSupport(Phase):
    """The ballistic single support (the planner's model: no joint torque), until the swing foot's
    touchdown; then the double support that lasts if the step's plan has one
    (``lasting.HeldTouchdown``), else ``next``, the double support of the walk (by default the
    impulsive one)."""

    next: Phase = field(default_factory=ImpulsiveDoubleSupport)

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(state.aim.period / ctx.grid)

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return single_support_guard(state)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        following = self.next if state.aim.orbit.double_support is None else HeldTouchdown(self)
        return Transition(following, state.moved(end.t, end.q, end.qd))


