"""Pinocchio models of the biped (docs/model.md sections 1-2), built from one ``BipedParams`` and
its joint table (``joints``).

Three models share one kinematic tree rooted at the stance-foot tip:

- ``single``: the single support, q = the table's coordinates (``JointTable.coordinates``), the
  stance tip fixed at the world origin;
- ``extended``: X = [x0, y0, z0, q], a translation joint at the root carrying the stance tip to
  (x0, y0, z0) in the world frame (the paper's D_e, J1, J2; ground reactions by inverse
  dynamics);
- ``double_support``: the model the instantaneous double support is written in. With legs of
  pitch joints only it is ``extended`` itself; with lateral hip joints it has one more, passive
  coordinate, the old stance foot's spin about its shin (``STANCE_SPIN``, after the ankle's
  pitch): once that foot lifts off at the impact nothing keeps its shin from spinning, which the
  legs of pitch joints cannot do (docs/model.md section 5.2).

The stance leg is always the model's leg 1 on the right (-y); the swing leg is leg 2 (+y).
World frame: x forward, y left, z up; every link frame has z along the link, up at q = 0. A hip's
joints turn about axes through the hip centre; the pelvis frame (``PELVIS``) is at the pelvis
centre, with the pelvis's axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from .joints import Coordinate
from .params import BipedParams, Link

SWING_TIP = "swing_tip"
STANCE_TIP = "stance_tip"
PELVIS = "pelvis"
STANCE_SPIN = "stance_ankle_spin"
ROOT_TRANSLATION = ("stance_tip_x", "stance_tip_y", "stance_tip_z")
_JOINT_MODELS = {"x": pin.JointModelRX, "y": pin.JointModelRY, "z": pin.JointModelRZ}


def _inertia(link: Link, com_z: float) -> pin.Inertia:
    """Spatial inertia of ``link`` with its CoM at (0, 0, com_z) in its joint frame."""
    return pin.Inertia(link.mass, np.array([0.0, 0.0, com_z]), np.diag(link.inertia))


def _at(x: float, y: float, z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([x, y, z]))


def _build(p: BipedParams, coordinates: tuple[Coordinate, ...], root: bool, spin: bool) -> pin.Model:
    """The tree: with ``root`` the translation joint at the stance tip, with ``spin`` the old
    stance foot's spin after the ankle's pitch."""
    model = pin.Model()
    model.name = "biped_double_support" if spin else ("biped_extended" if root else "biped_single_support")
    model.gravity = pin.Motion(np.array([0.0, 0.0, -p.gravity]), np.zeros(3))
    eye = pin.SE3.Identity()
    by = {(c.side, c.role): c for c in coordinates}

    def add(parent: int, c: Coordinate, placement: pin.SE3) -> int:
        return model.addJoint(parent, _JOINT_MODELS[c.axis](), placement, c.name)

    parent = model.addJoint(0, pin.JointModelTranslation(), eye, "stance_tip_translation") if root else 0
    roll = add(parent, by["stance", "ankle_roll"], eye)
    shin = add(roll, by["stance", "ankle_pitch"], eye)
    if spin:
        shin = model.addJoint(shin, pin.JointModelRZ(), eye, STANCE_SPIN)
    model.appendBodyToJoint(shin, _inertia(p.shin, p.shin.length - p.shin.com_offset), eye)
    knee = add(shin, by["stance", "knee"], _at(0, 0, p.shin.length))
    model.appendBodyToJoint(knee, _inertia(p.thigh, p.thigh.length - p.thigh.com_offset), eye)
    # The stance hip's joints from the thigh up; the first sits at the hip centre. The last (the
    # pelvis's) is put at the pelvis centre when it is the pitch, whose axis runs through both;
    # otherwise the pelvis centre lies hip_half_width along its y axis.
    hips = p.joints.hip_roles
    joint, offset = knee, (0.0, 0.0, p.thigh.length)
    for role in reversed(hips):
        last = role == hips[0]
        shift = p.hip_half_width if last and role == "hip_pitch" else 0.0
        joint = add(joint, by["stance", role], _at(offset[0], offset[1] + shift, offset[2]))
        offset = (0.0, 0.0, 0.0)
    pelvis = (0.0, 0.0 if hips[0] == "hip_pitch" else p.hip_half_width, 0.0)
    model.addFrame(pin.Frame(PELVIS, joint, _at(*pelvis), pin.FrameType.OP_FRAME))
    yaw = add(joint, by["", "torso_yaw"], _at(pelvis[0], pelvis[1], pelvis[2] + p.torso_joint_height))
    # The trunk's CoM is com_offset above the pelvis centre (docs/model.md section 1), not above the yaw joint.
    model.appendBodyToJoint(yaw, _inertia(p.trunk, p.trunk.com_offset - p.torso_joint_height), eye)
    for side, sign in (("stance", -1.0), ("swing", 1.0)):
        shoulder = add(yaw, by[side, "shoulder"], _at(0, sign * p.shoulder_half_width, p.shoulder_height))
        model.appendBodyToJoint(shoulder, _inertia(p.arm, -p.arm.com_offset), eye)
    swing, placement = joint, _at(pelvis[0], pelvis[1] + p.hip_half_width, pelvis[2])
    for role in hips:
        swing = add(swing, by["swing", role], placement)
        placement = eye
    model.appendBodyToJoint(swing, _inertia(p.thigh, -p.thigh.com_offset), eye)
    swing_knee = add(swing, by["swing", "knee"], _at(0, 0, -p.thigh.length))
    model.appendBodyToJoint(swing_knee, _inertia(p.shin, -p.shin.com_offset), eye)
    model.addFrame(pin.Frame(SWING_TIP, swing_knee, _at(0, 0, -p.shin.length), pin.FrameType.OP_FRAME))
    model.addFrame(pin.Frame(STANCE_TIP, roll, eye, pin.FrameType.OP_FRAME))
    return model


@dataclass(frozen=True)
class CoordinateNames:
    """What a model's vectors are: the single-support coordinates q, the actuated joints (the
    impulses' order) and the double-support coordinates X."""

    joints: tuple[str, ...]
    actuated: tuple[str, ...]
    double_support: tuple[str, ...]


@dataclass(eq=False)
class BipedModel:
    """The single-support, extended and double-support Pinocchio models with their data, from one
    parameter set; ``coordinates`` names q (single support). Compared and hashed by identity."""

    params: BipedParams
    coordinates: tuple[Coordinate, ...]
    single: pin.Model
    single_data: pin.Data
    extended: pin.Model
    extended_data: pin.Data
    double_support: pin.Model
    double_support_data: pin.Data

    @classmethod
    def from_params(cls, params: BipedParams) -> "BipedModel":
        """Build the models; their masses and inertias come from ``params`` only."""
        coordinates = params.joints.coordinates()
        single = _build(params, coordinates, root=False, spin=False)
        extended = _build(params, coordinates, root=True, spin=False)
        extended_data = extended.createData()
        if params.joints.lateral_hips:
            ds = _build(params, coordinates, root=True, spin=True)
            ds_data = ds.createData()
        else:
            ds, ds_data = extended, extended_data
        return cls(params, coordinates, single, single.createData(), extended, extended_data, ds, ds_data)

    # The coordinates ----------------------------------------------------------------------------
    @property
    def nq(self) -> int:
        """Number of single-support coordinates."""
        return len(self.coordinates)

    @cached_property
    def names(self) -> tuple[str, ...]:
        """The single-support coordinates' names, in q order."""
        return tuple(c.name for c in self.coordinates)

    def index(self, role: str, side: str = "stance") -> int:
        """Index in q of the coordinate of ``role`` on the model's ``side`` (``stance``,
        ``swing``; ``""`` for the torso)."""
        for k, c in enumerate(self.coordinates):
            if c.role == role and c.side == (side if role != "torso_yaw" else ""):
                return k
        raise KeyError(f"the model has no {side} {role} coordinate")

    @property
    def spin(self) -> bool:
        """Whether the double-support model has the old stance foot's spin."""
        return self.double_support is not self.extended

    @property
    def ds_names(self) -> tuple[str, ...]:
        """The double-support model's coordinates X, in order."""
        names = list(self.names)
        if self.spin:
            names.insert(2, STANCE_SPIN)
        return (*ROOT_TRANSLATION, *names)

    @property
    def coordinate_names(self) -> CoordinateNames:
        return CoordinateNames(self.names, self.actuated_names, self.ds_names)

    @cached_property
    def ds_of_single(self) -> np.ndarray:
        """Indices in X of the single-support coordinates (a single-support velocity qd is the
        double-support velocity with qd there and zero elsewhere); read-only, made once."""
        rest = np.arange(2, self.nq) + (4 if self.spin else 3)
        return _frozen(np.concatenate([[3, 4], rest]))

    @cached_property
    def actuated(self) -> np.ndarray:
        """Indices in q of the actuated coordinates (the joint impulses' order); read-only, made once."""
        return _frozen(np.array([k for k, c in enumerate(self.coordinates) if c.actuated]))

    @property
    def actuated_names(self) -> tuple[str, ...]:
        return tuple(self.names[k] for k in self.actuated)

    @cached_property
    def ds_actuated(self) -> np.ndarray:
        """Indices in X of the actuated coordinates; read-only, made once."""
        return _frozen(self.ds_of_single[self.actuated])

    def embed(self, qd: np.ndarray) -> np.ndarray:
        """The double-support velocity (m/s, rad/s) of a single-support velocity ``qd`` (rad/s): the
        stance tip at rest, the old stance foot not spinning."""
        if not self.spin:
            return np.concatenate([np.zeros(3), qd])
        xd = np.zeros(self.double_support.nv)
        xd[self.ds_of_single] = qd
        return xd

    # Kinematics and dynamics ---------------------------------------------------------------------
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

    def ds_state(self, q: np.ndarray) -> np.ndarray:
        """The double-support model's configuration at the single-support configuration ``q``
        (stance tip at the origin, no spin)."""
        return self.embed(q) if self.spin else self.extended_state(q)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """D_e(q), the symmetric inertia matrix of the double-support model (kg, kg m, kg m^2)."""
        m = pin.crba(self.double_support, self.double_support_data, self.ds_state(q)).copy()
        lower = self._lower_triangle
        m[lower] = m.T[lower]  # CRBA fills the upper triangle
        m += 0.0  # a signed zero reads +0, as the sum of the two triangles gave it
        return m

    @cached_property
    def _lower_triangle(self) -> tuple[np.ndarray, np.ndarray]:
        return np.tril_indices(self.double_support.nv, -1)

    def tip_jacobians(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """J1, J2: 3 x nX Jacobians of the stance and swing tips' world positions w.r.t. X (the
        double-support model's coordinates)."""
        model, data = self.double_support, self.double_support_data
        x = self.ds_state(q)
        pin.computeJointJacobians(model, data, x)
        pin.updateFramePlacements(model, data)
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        j1 = pin.getFrameJacobian(model, data, model.getFrameId(STANCE_TIP), frame)[:3]
        j2 = pin.getFrameJacobian(model, data, model.getFrameId(SWING_TIP), frame)[:3]
        return j1, j2

    def derivatives(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """dD_e/dq_k, dJ1/dq_k, dJ2/dq_k for each single-support coordinate q_k (k first: nq x nX
        x nX, nq x 3 x nX twice), exact: dD_e/dX_k = C(X, e_k) + C(X, e_k)^T (Pinocchio's Coriolis
        matrix, whose C + C^T is dD_e/dt), and the tips' Jacobians' time variation at the unit
        rate of X_k (the tips' positions' second derivatives)."""
        model, data = self.double_support, self.double_support_data
        x = self.ds_state(q)
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        tips = model.getFrameId(STANCE_TIP), model.getFrameId(SWING_TIP)
        d_mass = np.empty((self.nq, model.nv, model.nv))
        d_tips = np.empty((2, self.nq, 3, model.nv))
        for k, column in enumerate(self.ds_of_single):
            rate = np.zeros(model.nv)
            rate[column] = 1.0
            coriolis = pin.computeCoriolisMatrix(model, data, x, rate)
            d_mass[k] = coriolis + coriolis.T
            pin.computeJointJacobiansTimeVariation(model, data, x, rate)
            pin.updateFramePlacements(model, data)
            for tip, frame_id in enumerate(tips):
                d_tips[tip, k] = pin.getFrameJacobianTimeVariation(model, data, frame_id, frame)[:3]
        return d_mass, d_tips[0], d_tips[1]

    def momentum(self, q: np.ndarray, xd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Linear momentum p (kg m/s), angular momentum about the world origin (kg m^2/s), CoM (m).

        ``xd`` is a double-support velocity (``embed`` of a single-support one); the configuration
        has the stance tip at the origin. Vectors are in the world frame.
        """
        model, data = self.double_support, self.double_support_data
        pin.computeCentroidalMomentum(model, data, self.ds_state(q), xd)
        p = data.hg.linear.copy()
        com = data.com[0].copy()
        h_origin = data.hg.angular + cross(com, p)
        return p, h_origin, com

    def vertical_momentum_about(self, q: np.ndarray, xd: np.ndarray, point: np.ndarray) -> float:
        """Angular momentum (kg m^2/s) about the vertical axis through ``point`` (world, m)."""
        p, h_origin, _ = self.momentum(q, xd)
        return float(h_origin[2] - (point[0] * p[1] - point[1] * p[0]))


def _frozen(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only (a model's index arrays are shared by every caller)."""
    a.flags.writeable = False
    return a


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors (np.cross costs ~20 us a call on small arrays)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
