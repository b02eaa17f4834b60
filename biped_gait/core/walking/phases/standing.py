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
from ..events import STANDING, Foot
from ..state import WalkState
from .phase import End, Guard, Phase, Transition, WalkContext

CHUNK = 0.1  # s: a standing phase ends (and begins again) this often, its samples streamed
STEP = 1e-3  # s: the closed chain's integration step (RK4; the balance's closed loop is tens of 1/s)


@dataclass(frozen=True, eq=False)
class Standing(Phase):
    """Standing held by ``balance`` (module docstring)."""

    balance: Balance
    kind = STANDING

    @property
    def friction(self) -> float:
        """The parameter set's friction coefficient: the feet's reactions must stay in its cone."""
        return self.balance.chain.bm.params.friction

    def first_state(self, aim) -> tuple[np.ndarray, np.ndarray]:
        """At rest in the standing posture."""
        return self.balance.pose.q, np.zeros_like(self.balance.pose.q)

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(STEP, held=Held(self.balance.chain, self.balance.torque))

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return Guard(at=state.t_step + CHUNK)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        return Transition(self, state.moved(end.t, end.q, end.qd))

    def push_jump(self, ctx: WalkContext, state: WalkState, q: np.ndarray, impulse: np.ndarray) -> np.ndarray:
        """The velocity jump of a trunk impulse with both feet held: the single support's jump
        projected onto the velocities the feet allow, in the kinetic-energy metric (the feet's
        impulsive reactions take the rest)."""
        jump = ctx.trunk_push.velocity_jump(q, impulse, state.axes)
        chain = self.balance.chain
        c = chain.rows_of(q)
        m = chain.mass_matrix(q)[np.ix_(chain.at, chain.at)]
        return jump - np.linalg.solve(m, c.T @ np.linalg.solve(c @ np.linalg.solve(m, c.T), c @ jump))

    def feet(self, state: WalkState) -> tuple[Foot, ...]:
        front = state.stance_foot + state.axes @ self.balance.chain.bm.swing_tip(state.q)
        front[2] = 0.0
        other = "left" if state.stance_side == "right" else "right"
        return Foot(state.stance_side, state.stance_foot), Foot(other, front)

    def evaluate(self, ctx: WalkContext, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        chain, law = self.balance.chain, self.balance.torque
        forces = np.empty((len(q), 2, 4))
        for k in range(len(q)):
            qdd, held = chain.forward(q[k], qd[k], law(q[k], qd[k]))
            forces[k] = chain.wrenches(q[k], qd[k], qdd, chain.full_force(held))
        return forces, ctx.hybrid.samples.dynamics(q, qd).lowest_link
