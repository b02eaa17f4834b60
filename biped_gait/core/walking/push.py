"""A push on the walking biped: an impulse on the trunk during a single support
(docs/model.md section 8.6).

A push is an impulse P (N s) applied at the trunk's centre of mass, world axes, at a time in
the step (s after the step's start). During the single support the stance foot is a fixed
pivot, so the push changes the generalized velocity of the 9-DOF model by

    delta_qd = D(q)^-1 J_trunk(q)^T P_model

with D the single-support inertia matrix and J_trunk the 3 x nq Jacobian of the trunk's CoM
(model frame, stance tip at the origin); the ground supplies whatever impulse at the stance
tip keeps it in place. P_model = A^T P with A the step's model axes in the world
(``exchange.world_axes``: the mirror M = diag(1, -1, 1) with the left foot in stance, turned by
the walk's heading). The configuration does not jump.

Directions in the horizontal plane are angles (rad) from +x (forward) towards +y (left):
forward 0, left pi/2, backward pi, right -pi/2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..model.biped import BipedModel

DIRECTIONS = {"forward": 0.0, "left": math.pi / 2, "backward": math.pi, "right": -math.pi / 2}
"""The named push directions: angle (rad) in the horizontal plane from +x (forward) towards +y."""


def horizontal_impulse(magnitude: float, direction: float) -> np.ndarray:
    """The impulse (N s, world axes) of ``magnitude`` (N s) in the horizontal ``direction``
    (rad from +x towards +y)."""
    return magnitude * np.array([math.cos(direction), math.sin(direction), 0.0])


@dataclass(frozen=True, eq=False)
class Push:
    """An impulse ``impulse`` (N s, world axes, at the trunk's CoM) at ``time_in_step`` (s after
    the start of the step it acts in; if the step touches down first, it acts on the pre-impact
    state at the touchdown)."""

    impulse: np.ndarray
    time_in_step: float

    def __post_init__(self) -> None:
        impulse = np.asarray(self.impulse, dtype=float)
        if impulse.shape != (3,) or not np.all(np.isfinite(impulse)):
            raise ValueError(f"a push impulse is 3 finite numbers (N s), got {self.impulse!r}")
        if not (math.isfinite(self.time_in_step) and self.time_in_step >= 0.0):
            raise ValueError(f"a push acts at a time in the step >= 0 s, got {self.time_in_step!r}")
        object.__setattr__(self, "impulse", impulse)


@dataclass(frozen=True, eq=False)
class AppliedPush:
    """A push as it acted: in ``step`` (on the ``stance_side`` foot) at ``t`` (s in the walk),
    ``time_in_step`` (s), the impulse (N s, world axes) and the velocity jump it gave (rad/s,
    model coordinates)."""

    step: int
    stance_side: str
    t: float
    time_in_step: float
    impulse: np.ndarray
    delta_qd: np.ndarray


class TrunkPush:
    """The velocity jump of a push on the trunk of ``bm`` (the single-support model)."""

    def __init__(self, bm: BipedModel) -> None:
        self.model = bm.single
        self.data = bm.single.createData()
        self.joint = bm.single.getJointId(bm.names[bm.index("torso_yaw")])  # the trunk hangs on it
        # The trunk's CoM in the torso-yaw joint's frame (m): com_offset above the pelvis centre.
        self.com = np.array([0.0, 0.0, bm.params.trunk.com_offset - bm.params.torso_joint_height])

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """J_trunk (3 x nq): d(trunk CoM position, model frame, m) / d qd."""
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        frame = pin.getJointJacobian(model, data, self.joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        offset = data.oMi[self.joint].rotation @ self.com  # from the joint to the CoM, world axes
        return frame[:3] - pin.skew(offset) @ frame[3:]

    def velocity_jump(self, q: np.ndarray, impulse: np.ndarray, axes: np.ndarray) -> np.ndarray:
        """delta_qd (rad/s, model coordinates) of ``impulse`` (N s, world axes) at configuration
        ``q`` in a step whose model axes in the world are ``axes`` (``WalkState.axes``)."""
        mass = pin.crba(self.model, self.data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        return np.linalg.solve(mass, self.jacobian(q).T @ (axes.T @ impulse))
