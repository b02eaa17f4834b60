"""The start, walked (docs/model.md section 14.3): from standing at rest in the start's posture, the
start's double support (``Starting``, d s: the closed chain driven by the plan's torques and the
feedback that tracks it, its torques kept where both feet's reactions stay within the floor's
reach, as the stop's), which ends in the gait's touchdown posture, moving; then at the lift-off I^+
re-aimed onto the gait's next step from the actual state and the leg exchange (the lasting walk's,
``LastingDoubleSupport.reset``), and the gait's single support.

The lift-off ends the standing's step (its ``Touchdown``, with no I^-); the gait's steps follow.
Units SI, rad; times in the step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..engines.engine import Motion
from ..events import STARTING
from ..held_support import HeldSupport
from ..state import WalkState
from .held import tracked
from .impulsive import SingleSupport
from .lasting import LastingDoubleSupport, LastingTouchdown
from .phase import WalkContext


@dataclass(frozen=True, eq=False)
class Starting(LastingDoubleSupport):
    """Both feet on the ground for the start ``plan``'s duration from ``start`` (s in the step), its
    torques and the feedback tracking it, guarded to the floor's reach; then I^+ and the leg
    exchange (``LastingDoubleSupport``'s), and ``after``, the gait's single support. ``report``: where
    it began (``starting``)."""

    kind = STARTING

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return tracked(self.plan, self.start, guard=True)


def starting(plan: HeldSupport, state: WalkState) -> Starting:
    """The start ``plan`` from ``state`` (standing, at the plan's posture at rest): its report the
    state's distance from the plan's start (max |(q, qd) - (q*(0), 0)|, rad, rad/s), no I^- and no
    held impact."""
    none, still = np.zeros(len(plan.i_minus)), np.zeros(3)
    error = max(float(np.max(np.abs(state.q - plan.q[0]))), float(np.max(np.abs(state.qd - plan.qd[0]))))
    report = LastingTouchdown(state.t + state.t_step, error, plan.duration, none, none, still, still)
    return Starting(plan, state.t_step, report, SingleSupport())
