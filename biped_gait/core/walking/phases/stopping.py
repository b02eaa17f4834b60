"""The stop, walked (docs/model.md section 14.2): at the touchdown of a step of the gait the stop was
planned from, I^- and the held impact (``StopTouchdown``: the lasting walk's landing,
``lasting.held_landing``, both feet pressing within their pyramids, the double support started
nearest the plan's velocity); then the stop's double support (``Stopping``, d s: the closed chain
driven by the plan's torques and the feedback that tracks it, its torques kept where both feet's
reactions stay within the floor's reach, ``reaction_guard``), which ends at rest in the standing
posture; then standing, held by the balance controller (``standing.Standing``).

The step ends at the end of the stop (its ``Touchdown``, with the I^- applied and no I^+); standing
goes on in that step's frame (the old stance foot's tip at the origin, the new one in front), the
step's count past it. Units SI, rad; times in the step.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..engines.engine import Motion
from ..events import DOUBLE_SUPPORT, STOPPING, Touchdown
from ..held_support import HeldSupport
from ..state import WalkState
from .held import tracked
from .lasting import LastingDoubleSupport, held_touchdown
from .phase import End, Phase, Transition, WalkContext
from .standing import Standing


@dataclass(frozen=True, eq=False)
class StopTouchdown(Phase):
    """The touchdown onto the stop ``plan``: I^- and the held impact (module docstring); then the
    stop, and ``standing`` after it."""

    plan: HeldSupport
    standing: Standing
    kind = DOUBLE_SUPPORT

    def motion(self, ctx: WalkContext, state: WalkState) -> None:
        return None

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        report, held = held_touchdown(self.plan, state, end)
        return Transition(Stopping(self.plan, end.t, report, self.standing), state.moved(end.t, end.q, held.qd))


@dataclass(frozen=True, eq=False)
class Stopping(LastingDoubleSupport):
    """Both feet on the ground for the stop ``plan``'s duration from ``start`` (s in the step), its
    torques and the feedback tracking it, guarded to the floor's reach (the lasting walk's phase but
    for the guard and its end); then ``after``, the standing. ``report``: what its touchdown did."""

    kind = STOPPING

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return tracked(self.plan, self.start, guard=True)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        """The step ends standing: its touchdown (I^- applied, no I^+), the standing phase from the
        state at the stop's end, in the step's frame."""
        report = self.report
        touchdown = Touchdown(state.step, state.t + end.t, end.t, report.i_minus, np.zeros_like(report.i_minus),
                              float(np.abs(report.i_minus).sum()), report.state_error, 0.0, 0.0, 0.0,
                              state.stance_side, report)
        standing = replace(state, q=end.q, qd=end.qd, step=state.step + 1, t=state.t + end.t, t_step=0.0)
        return Transition(self.after, standing, (touchdown,))
