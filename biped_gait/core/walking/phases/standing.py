"""Standing as a phase of the walk (docs/model.md section 13): both feet down, the closed chain
held by the balance controller (``balance``), in chunks of ``CHUNK`` s so that the runner streams
its samples; it ends only when the robot falls.

The step's model frame while standing is the back foot's (its tip at the origin, the front foot
at (stance length, width, 0)); both feet are on the ground, the back one first.

Units SI, rad; times in the step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..balance import Balance
from ..engines.engine import Held, Motion
from ..events import STANDING
from ..state import WalkState
from .held import STEP, BothFeet
from .phase import End, Guard, Transition, WalkContext

CHUNK = 0.1  # s: a standing phase ends (and begins again) this often, its samples streamed


@dataclass(frozen=True, eq=False)
class Standing(BothFeet):
    """Standing held by ``balance`` (module docstring)."""

    balance: Balance
    kind = STANDING

    @property
    def chain(self):
        return self.balance.chain

    def first_state(self, aim) -> tuple[np.ndarray, np.ndarray]:
        """At rest in the standing posture."""
        return self.balance.pose.q, np.zeros_like(self.balance.pose.q)

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(STEP, held=Held(self.balance.chain, lambda _t, q, qd: self.balance.torque(q, qd)))

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return Guard(at=state.t_step + CHUNK)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        return Transition(self, state.moved(end.t, end.q, end.qd))
