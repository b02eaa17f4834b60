"""Pinocchio models of the biped (docs/model.md sections 1-2), built from one ``BipedParams``.

Two models share one kinematic tree rooted at the stance-foot tip:

- ``single``: 9 DOF, q = [q1..q9], the stance tip fixed at the world origin (single support);
- ``extended``: 12 DOF, X = [x0, y0, z0, q1..q9], a translation joint at the root carrying the
  stance tip to (x0, y0, z0) in the world frame (double support, paper's D_e, J1, J2).

The stance leg is always the model's leg 1 on the right (-y); the swing leg is leg 2 (+y).
World frame: x forward, y left, z up; every link frame has z along the link, up at q = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .params import BipedParams, Link

# Names of the model's joints in q order (model-side names: "stance"/"swing", not left/right).
JOINT_NAMES = (
    "stance_ankle_roll",
    "stance_ankle_pitch",
    "stance_knee",
    "stance_hip",
    "torso_yaw",
    "stance_side_shoulder",
    "swing_side_shoulder",
    "swing_hip",
    "swing_knee",
)
NQ = 9
NX = 12
SWING_TIP = "swing_tip"
STANCE_TIP = "stance_tip"


def _inertia(link: Link, com_z: float) -> pin.Inertia:
    """Spatial inertia of ``link`` with its CoM at (0, 0, com_z) in its joint frame."""
    return pin.Inertia(link.mass, np.array([0.0, 0.0, com_z]), np.diag(link.inertia))


def _build(p: BipedParams, extended: bool) -> pin.Model:
    model = pin.Model()
    model.name = "biped_extended" if extended else "biped_single_support"
    model.gravity = pin.Motion(np.array([0.0, 0.0, -p.gravity]), np.zeros(3))
    eye = pin.SE3.Identity()

    def at(x: float, y: float, z: float) -> pin.SE3:
        return pin.SE3(np.eye(3), np.array([x, y, z]))

    parent = 0
    if extended:
        parent = model.addJoint(0, pin.JointModelTranslation(), eye, "stance_tip_translation")
    roll = model.addJoint(parent, pin.JointModelRX(), eye, JOINT_NAMES[0])
    pitch = model.addJoint(roll, pin.JointModelRY(), eye, JOINT_NAMES[1])
    model.appendBodyToJoint(pitch, _inertia(p.shin, p.shin.length - p.shin.com_offset), eye)
    knee = model.addJoint(pitch, pin.JointModelRY(), at(0, 0, p.shin.length), JOINT_NAMES[2])
    model.appendBodyToJoint(knee, _inertia(p.thigh, p.thigh.length - p.thigh.com_offset), eye)
    # The stance hip's axis is parallel to y and passes through the pelvis centre, which lies
    # hip_half_width to the left of the stance hip: the joint frame is put at the pelvis centre.
    hip = model.addJoint(knee, pin.JointModelRY(), at(0, p.hip_half_width, p.thigh.length), JOINT_NAMES[3])
    yaw = model.addJoint(hip, pin.JointModelRZ(), at(0, 0, p.torso_joint_height), JOINT_NAMES[4])
    # The trunk's CoM is com_offset above the pelvis centre (docs/model.md section 1), not above the yaw joint.
    model.appendBodyToJoint(yaw, _inertia(p.trunk, p.trunk.com_offset - p.torso_joint_height), eye)
    for i, side in ((5, -1.0), (6, 1.0)):
        shoulder = model.addJoint(
            yaw, pin.JointModelRY(), at(0, side * p.shoulder_half_width, p.shoulder_height), JOINT_NAMES[i]
        )
        model.appendBodyToJoint(shoulder, _inertia(p.arm, -p.arm.com_offset), eye)
    swing_hip = model.addJoint(hip, pin.JointModelRY(), at(0, p.hip_half_width, 0), JOINT_NAMES[7])
    model.appendBodyToJoint(swing_hip, _inertia(p.thigh, -p.thigh.com_offset), eye)
    swing_knee = model.addJoint(swing_hip, pin.JointModelRY(), at(0, 0, -p.thigh.length), JOINT_NAMES[8])
    model.appendBodyToJoint(swing_knee, _inertia(p.shin, -p.shin.com_offset), eye)
    model.addFrame(pin.Frame(SWING_TIP, swing_knee, at(0, 0, -p.shin.length), pin.FrameType.OP_FRAME))
    model.addFrame(pin.Frame(STANCE_TIP, roll, eye, pin.FrameType.OP_FRAME))
    return model


@dataclass
class BipedModel:
    """The single-support and extended Pinocchio models with their data, from one parameter set."""

    params: BipedParams
    single: pin.Model
    single_data: pin.Data
    extended: pin.Model
    extended_data: pin.Data

    @classmethod
    def from_params(cls, params: BipedParams) -> "BipedModel":
        """Build both models; their masses and inertias come from ``params`` only."""
        single = _build(params, extended=False)
        extended = _build(params, extended=True)
        return cls(params, single, single.createData(), extended, extended.createData())

    @property
    def total_mass(self) -> float:
        """Mass of the model (kg), as Pinocchio sums it."""
        return float(pin.computeTotalMass(self.single))

    def swing_tip(self, q: np.ndarray) -> np.ndarray:
        """World position (m) of the swing-foot tip, stance tip at the origin."""
        pin.framesForwardKinematics(self.single, self.single_data, q)
        return self.single_data.oMf[self.single.getFrameId(SWING_TIP)].translation.copy()

    def extended_state(self, q: np.ndarray) -> np.ndarray:
        """Extended configuration X = [0, 0, 0, q] (stance tip at the world origin)."""
        return np.concatenate([np.zeros(3), q])

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """D_e(q), the 12 x 12 symmetric inertia matrix of the extended model (kg, kg m, kg m^2)."""
        m = pin.crba(self.extended, self.extended_data, self.extended_state(q))
        return np.triu(m) + np.triu(m, 1).T

    def tip_jacobians(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """J1, J2: 3 x 12 Jacobians of the stance and swing tips' world positions w.r.t. X."""
        model, data = self.extended, self.extended_data
        x = self.extended_state(q)
        pin.computeJointJacobians(model, data, x)
        pin.updateFramePlacements(model, data)
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        j1 = pin.getFrameJacobian(model, data, model.getFrameId(STANCE_TIP), frame)[:3]
        j2 = pin.getFrameJacobian(model, data, model.getFrameId(SWING_TIP), frame)[:3]
        return j1, j2

    def momentum(self, q: np.ndarray, xd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Linear momentum p (kg m/s), angular momentum about the world origin (kg m^2/s), CoM (m).

        ``xd`` is the extended velocity [x0d, y0d, z0d, qd]; the configuration has the stance
        tip at the origin. Vectors are in the world frame.
        """
        model, data = self.extended, self.extended_data
        pin.computeCentroidalMomentum(model, data, self.extended_state(q), xd)
        p = data.hg.linear.copy()
        com = data.com[0].copy()
        h_origin = data.hg.angular + cross(com, p)
        return p, h_origin, com

    def vertical_momentum_about(self, q: np.ndarray, xd: np.ndarray, point: np.ndarray) -> float:
        """Angular momentum (kg m^2/s) about the vertical axis through ``point`` (world, m)."""
        p, h_origin, _ = self.momentum(q, xd)
        return float(h_origin[2] - (point[0] * p[1] - point[1] * p[0]))


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors (np.cross costs ~20 us a call on small arrays)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
