"""What the phases with both feet on the ground share (standing, the double support that lasts):
the closed chain holds both tips (core/dynamics/closed_chain.py), the feet's reactions (the lateral
force between the feet shared so that the friction each needs is least) are checked against the
parameter set's friction cone, a push's velocity jump is projected onto the velocities
the feet allow, and the contact forces at the samples follow from the torques that act there.

The step's model frame: the old stance foot's (its tip at the origin), the other foot at the swing
tip's position. Units SI, rad.
"""

from __future__ import annotations

import numpy as np

from ...dynamics.closed_chain import ClosedChain
from ..engines.engine import Held, Motion
from ..events import Foot
from ..reaction_guard import guarded_torque
from ..state import WalkState
from ..tracking import Tracking
from .phase import Phase, WalkContext

STEP = 1e-3  # s: the integration step (RK4) of a phase whose tips are held (standing's, whose balance's
# closed loop is tens of 1/s; the tracked phases', up to about 1,350 1/s: h lambda = 1.35 within RK4's 2.78)


def tracked(plan: Tracking, start: float, guard: bool = False) -> Motion:
    """The motion of a phase that tracks ``plan`` from ``start`` (s in the step): its chain holds the
    tips, its law drives the joints (with ``guard``, its torques kept where the held tips' reactions
    stay within the floor's reach, ``reaction_guard``), in RK4 steps of ``STEP``."""
    chain, law, limits = plan.chain, plan.law, plan.limits
    if guard:
        return Motion(STEP, held=Held(chain, lambda t, q, qd: guarded_torque(chain, q, qd, law(t - start, q, qd), limits)))
    return Motion(STEP, held=Held(chain, lambda t, q, qd: law(t - start, q, qd)))


class BothFeet(Phase):
    """A phase with both feet held by ``chain`` (a property of the subclass)."""

    chain: ClosedChain

    @property
    def friction(self) -> float:
        """The parameter set's friction coefficient: the feet's reactions must stay in its cone."""
        return self.chain.bm.params.friction

    def push_jump(self, ctx: WalkContext, state: WalkState, q: np.ndarray, impulse: np.ndarray) -> np.ndarray:
        """The velocity jump of a trunk impulse with both feet held: the single support's jump
        projected onto the velocities the feet allow, in the kinetic-energy metric (the feet's
        impulsive reactions take the rest)."""
        jump = ctx.trunk_push.velocity_jump(q, impulse, state.axes)
        chain = self.chain
        c = chain.rows_of(q)
        m = chain.mass_matrix(q)[np.ix_(chain.at, chain.at)]
        return jump - np.linalg.solve(m, c.T @ np.linalg.solve(c @ np.linalg.solve(m, c.T), c @ jump))

    def feet(self, state: WalkState) -> tuple[Foot, ...]:
        front = state.stance_foot + state.axes @ self.chain.bm.swing_tip(state.q)
        front[2] = 0.0
        other = "left" if state.stance_side == "right" else "right"
        return Foot(state.stance_side, state.stance_foot), Foot(other, front)

    def evaluate(self, ctx: WalkContext, q: np.ndarray, qd: np.ndarray,
                 torques: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        chain = self.chain
        forces = np.empty((len(q), 2, 4))
        for k in range(len(q)):
            qdd, held = chain.forward(q[k], qd[k], torques[k, chain.actuated])
            forces[k] = chain.shared_wrenches(q[k], qd[k], qdd, held)
        return forces, ctx.hybrid.samples.dynamics(q, qd).lowest_link
