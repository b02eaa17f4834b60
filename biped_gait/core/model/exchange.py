"""The leg exchange at a double support and the mirror (docs/model.md section 5), derived from the
joint table's roles.

At each touchdown the legs swap roles and the next step is described by the same model seen in
a mirror (y -> -y): the next step's frame has its origin at the new stance tip, its axes are this
step's mirrored and turned by the heading change phi about the vertical. In the next step's
coordinates:

- a leg's joint takes the value of the same joint of the other leg, negated (the chain from the
  stance foot runs through the stance leg upwards, so the stance leg's coordinates are inverse
  rotations), and negated once more if it is lateral (about x or z: the mirror turns it the other
  way); the torso's yaw changes sign, the arms swap;
- the new stance ankle's roll and pitch are the landing shin's orientation: the mirror image of
  its rotation is Rz(phi) Rx(roll) Ry(pitch), which also gives the heading change phi.

With legs of pitch joints only (the paper's model) the landing shin is Rx(q1) Ry(sum of the
pitches), so the map is linear, q' = P q, with phi = 0, and joint velocities map by the same P
(``LinearExchange``, the matrix written out in docs/model.md). With lateral hip joints the
ankle's part and its velocity are found from the kinematics (``KinematicExchange``): the landing
shin's angular velocity, mirrored and turned into the next frame, resolved on the ankle's axes.

Velocities at the double support are in the double-support model's coordinates X (``biped``),
with the new stance tip at rest: ``velocity`` maps them to the next step's joint velocity,
``next_velocity`` the next step's joint velocity back to X.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .biped import SWING_TIP, BipedModel
from .joints import Coordinate
from .rotations import euler, rotation

MIRROR = np.diag([1.0, -1.0, 1.0])  # y -> -y: the next step is the mirror image of this one


def mirror_for(stance_side: str) -> np.ndarray:
    """The map from a step's model frame (stance leg 1) to world axes: identity with the right
    foot in stance, the mirror y -> -y with the left."""
    if stance_side not in ("right", "left"):
        raise ValueError(f"stance side must be 'right' or 'left', got {stance_side!r}")
    return np.eye(3) if stance_side == "right" else MIRROR


def world_axes(stance_side: str, heading: float = 0.0) -> np.ndarray:
    """A step's model axes in the world (columns; 3 x 3, det -1 for a left stance): the world's
    turned by ``heading`` (rad) about the vertical, then mirrored for a left stance foot
    (``mirror_for``). World vectors are ``world_axes @`` model vectors (axial vectors with the
    determinant as a factor)."""
    mirror = mirror_for(stance_side)
    return mirror if heading == 0.0 else rotation("z", heading) @ mirror


def next_heading(heading: float, next_side: str, turn: float) -> float:
    """The heading (rad) of the next step's model frame after a touchdown whose landing shin
    turned the frame by ``turn`` (``heading`` of the exchange, rad) onto the ``next_side`` foot:
    the next frame is this one mirrored, then turned by ``turn``, so the world heading changes by
    +turn onto a right foot and by -turn onto a left one."""
    return heading + (turn if next_side == "right" else -turn)


def other_side(stance_side: str) -> str:
    """The stance side of the next step."""
    return "left" if stance_side == "right" else "right"


def _partner(coordinates: tuple[Coordinate, ...], i: int) -> tuple[int, float]:
    """The coordinate of this step that the next step's coordinate ``i`` (not an ankle's) takes,
    and the sign: the same joint on the other side, negated for a leg's joint, negated for a
    lateral one."""
    c = coordinates[i]
    other = {"stance": "swing", "swing": "stance", "": ""}[c.side]
    j = next(k for k, d in enumerate(coordinates) if d.role == c.role and d.side == other)
    sign = (-1.0 if c.spec.leg else 1.0) * (-1.0 if c.lateral else 1.0)
    return j, sign


def _joint_map(coordinates: tuple[Coordinate, ...]) -> list[tuple[int, int, float]]:
    """(next coordinate, this step's coordinate, sign) of every coordinate but the ankle's."""
    return [(i, *_partner(coordinates, i)) for i, c in enumerate(coordinates) if c.role not in ("ankle_roll", "ankle_pitch")]


def exchange_matrix(coordinates: tuple[Coordinate, ...]) -> np.ndarray:
    """P, the linear leg exchange of legs with pitch joints only: the joint map, the roll
    mirrored, the new ankle pitch the landing shin's absolute pitch (the sum of the pitch
    coordinates from the stance ankle to the swing knee)."""
    n = len(coordinates)
    p = np.zeros((n, n))
    for i, j, sign in _joint_map(coordinates):
        p[i, j] = sign
    for i, c in enumerate(coordinates):
        if c.role == "ankle_roll":
            p[i, i] = -1.0
        elif c.role == "ankle_pitch":
            for k, d in enumerate(coordinates):
                if d.spec.leg and d.role != "ankle_roll":
                    p[i, k] = 1.0
    return p


class LinearExchange:
    """The leg exchange of legs with pitch joints only: q' = P q, qd' = P qd, no heading change."""

    def __init__(self, bm: BipedModel) -> None:
        self.matrix = exchange_matrix(bm.coordinates)
        self.inverse = np.linalg.inv(self.matrix)

    def configuration(self, q: np.ndarray) -> np.ndarray:
        """The next step's configuration (rad) of the touchdown configuration ``q``."""
        return self.matrix @ q

    def heading(self, q: np.ndarray) -> float:
        """The heading change phi (rad): none."""
        return 0.0

    def velocity(self, q: np.ndarray, xd: np.ndarray) -> np.ndarray:
        """The next step's joint velocity (rad/s) of the double-support velocity ``xd`` (or its
        columns), the new stance tip at rest."""
        return self.matrix @ xd[3:]

    def next_velocity(self, q: np.ndarray, j2: np.ndarray, qd_next: np.ndarray) -> np.ndarray:
        """The next step's joint velocity ``qd_next`` (its own coordinates) in this step's
        double-support coordinates, the new stance tip (Jacobian ``j2``) at rest."""
        qd = self.inverse @ qd_next
        return np.concatenate([-j2[:, 3:] @ qd, qd])

    def next_velocity_gain(self, q: np.ndarray, j2: np.ndarray, row: np.ndarray) -> np.ndarray:
        """row . next_velocity(q, j2, .) as a row over the next step's joint velocity."""
        return (row[3:] - row[:3] @ j2[:, 3:]) @ self.inverse

    def spin_row(self, q: np.ndarray) -> None:
        """The new stance foot's spin rate as a row over X: none, the legs cannot spin it apart
        from the old foot's, which the model holds."""
        return None

    def derivatives(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, None]:
        """The exchange's dependence on the touchdown configuration ``q`` (``KinematicExchange``'s):
        dq'/dq = P, the velocity map's none, no spin row."""
        return self.matrix, np.zeros((len(q), len(q), len(q) + 3)), None


def _gimbal(roll: float, pitch: float) -> np.ndarray:
    """The angular velocity (columns, foot frame) of unit rates of a stance ankle's roll, pitch
    and spin (about the shin) at (``roll``, ``pitch``) rad."""
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    return np.array([[1.0, 0.0, sp], [0.0, cr, -sr * cp], [0.0, sr, cr * cp]])


class KinematicExchange:
    """The leg exchange of legs with lateral hip joints, from the kinematics (module docstring).
    Not thread-safe (Pinocchio data reused)."""

    def __init__(self, bm: BipedModel) -> None:
        self.bm = bm
        self.joints = _joint_map(bm.coordinates)
        self.roll, self.pitch = bm.index("ankle_roll"), bm.index("ankle_pitch")
        self.shin = bm.single.getJointId(bm.names[bm.index("knee", "swing")])  # the landing shin's frame
        self.ds_shin = bm.double_support.getJointId(bm.names[bm.index("knee", "swing")])
        self.tip = bm.single.getFrameId(SWING_TIP)
        self.single_data = bm.single.createData()
        self.ds_data = bm.double_support.createData()

    def _landing(self, q: np.ndarray) -> tuple[float, float, float]:
        """(phi, roll, pitch) of the landing shin at ``q``: M R M = Rz(phi) Rx(roll) Ry(pitch)."""
        pin.forwardKinematics(self.bm.single, self.single_data, q)
        landing = MIRROR @ self.single_data.oMi[self.shin].rotation @ MIRROR
        return euler(landing, "zxy")

    def configuration(self, q: np.ndarray) -> np.ndarray:
        """The next step's configuration (rad) of the touchdown configuration ``q``."""
        out = np.zeros_like(q)
        for i, j, sign in self.joints:
            out[i] = sign * q[j]
        _, out[self.roll], out[self.pitch] = self._landing(q)
        return out

    def heading(self, q: np.ndarray) -> float:
        """The heading change phi (rad): the next step's frame is this one's mirrored, then
        turned by phi about the vertical."""
        return self._landing(q)[0]

    def _resolution(self, q: np.ndarray) -> np.ndarray:
        """Rates (roll, pitch, spin) of the next step's ankle per angular velocity (this step's
        frame, world axes) of the landing shin (3 x 3)."""
        phi, roll, pitch = self._landing(q)
        return np.linalg.solve(_gimbal(roll, pitch), rotation("z", phi).T @ -MIRROR)

    def _shin_angular(self, q: np.ndarray) -> np.ndarray:
        """The landing shin's angular velocity (world axes) as rows over X (3 x nX)."""
        model, data = self.bm.double_support, self.ds_data
        pin.computeJointJacobians(model, data, self.bm.ds_state(q))
        return pin.getJointJacobian(model, data, self.ds_shin, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[3:]

    def velocity(self, q: np.ndarray, xd: np.ndarray) -> np.ndarray:
        """The next step's joint velocity (rad/s) of the double-support velocity ``xd`` (or its
        columns), the new stance tip at rest and its foot not spinning."""
        at = self.bm.ds_of_single
        out = np.zeros((self.bm.nq,) + xd.shape[1:])
        for i, j, sign in self.joints:
            out[i] = sign * xd[at[j]]
        rates = self._resolution(q) @ (self._shin_angular(q) @ xd)
        out[self.roll], out[self.pitch] = rates[0], rates[1]
        return out

    def spin_row(self, q: np.ndarray) -> np.ndarray:
        """The new stance foot's spin rate (rad/s, about its shin) as a row over X: zero after
        the impact, as the next step's ankle has no spin."""
        return self._resolution(q)[2] @ self._shin_angular(q)

    def derivatives(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The exchange's dependence on the touchdown configuration ``q`` (rad), exact: dq'/dq (nq x
        nq); d V / dq_k (nq x nq x nX, k first), V the matrix of ``velocity`` (qd' = V(q) Xd); and
        d ``spin_row`` / dq_k (nq x nX). The landing shin's orientation moves at the mirrored
        angular velocity -M w_k per unit rate of q_k (w_k its world angular velocity's column),
        which its Euler angles' rates resolve; the shin's angular Jacobian's derivative is its
        time variation at that unit rate."""
        bm = self.bm
        model, data = bm.double_support, self.ds_data
        x, frame = bm.ds_state(q), pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        angular = self._shin_angular(q)
        d_angular = np.empty((bm.nq, 3, model.nv))
        for k, column in enumerate(bm.ds_of_single):
            rate = np.zeros(model.nv)
            rate[column] = 1.0
            pin.computeJointJacobiansTimeVariation(model, data, x, rate)
            d_angular[k] = pin.getJointJacobianTimeVariation(model, data, self.ds_shin, frame)[3:]
        phi, roll, pitch = self._landing(q)
        turn = rotation("z", phi)
        axes = np.column_stack([[0.0, 0.0, 1.0], turn[:, 0], turn @ rotation("x", roll)[:, 1]])
        rates = np.linalg.solve(axes, -MIRROR @ angular[:, bm.ds_of_single])  # (phi, roll, pitch) per q_k
        gimbal = _gimbal(roll, pitch)
        resolution = np.linalg.solve(gimbal, turn.T @ -MIRROR)
        cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
        by_roll = np.array([[0.0, 0.0, 0.0], [0.0, -sr, -cr * cp], [0.0, cr, -sr * cp]])
        by_pitch = np.array([[0.0, 0.0, cp], [0.0, 0.0, sr * sp], [0.0, 0.0, -cr * sp]])
        by_phi = np.array([[-np.sin(phi), -np.cos(phi), 0.0], [np.cos(phi), -np.sin(phi), 0.0], [0.0, 0.0, 0.0]])
        d_gimbal = rates[1][:, None, None] * by_roll + rates[2][:, None, None] * by_pitch
        d_resolution = np.linalg.solve(gimbal, -d_gimbal @ resolution
                                       + rates[0][:, None, None] * (by_phi.T @ -MIRROR))
        d_rows = d_resolution @ angular + resolution @ d_angular  # d (resolution @ angular) / dq_k
        configuration = np.zeros((bm.nq, bm.nq))
        velocity = np.zeros((bm.nq, bm.nq, model.nv))
        for i, j, sign in self.joints:
            configuration[i, j] = sign
        configuration[self.roll], configuration[self.pitch] = rates[1], rates[2]
        velocity[self.roll], velocity[self.pitch] = d_rows[:, 0], d_rows[:, 1]
        return configuration, np.swapaxes(velocity, 0, 1), d_rows[:, 2]

    def next_velocity(self, q: np.ndarray, j2: np.ndarray, qd_next: np.ndarray) -> np.ndarray:
        """The next step's joint velocity ``qd_next`` (its own coordinates, rad/s; or its columns)
        in this step's double-support coordinates: the joints by the joint map, the old stance
        shin (the next step's swing shin) and its tip from the next step's kinematics, mirrored
        back. ``j2`` is not needed: the new stance tip is at rest in the next step's model."""
        bm = self.bm
        q_next = self.configuration(q)
        model, data = bm.single, self.single_data
        pin.computeJointJacobians(model, data, q_next)
        pin.updateFramePlacements(model, data)
        twist = pin.getFrameJacobian(model, data, self.tip, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED) @ qd_next
        back = MIRROR @ rotation("z", self.heading(q))
        out = np.zeros((bm.double_support.nv,) + np.shape(qd_next)[1:])
        out[:3] = back @ twist[:3]
        out[3:6] = np.linalg.solve(_gimbal(q[self.roll], q[self.pitch]), -back @ twist[3:])
        at = bm.ds_of_single
        for i, j, sign in self.joints:
            out[at[j]] = sign * qd_next[i]
        return out

    def next_velocity_gain(self, q: np.ndarray, j2: np.ndarray, row: np.ndarray) -> np.ndarray:
        """row . next_velocity(q, j2, .) as a row over the next step's joint velocity."""
        return row @ self.next_velocity(q, j2, np.eye(self.bm.nq))


def leg_exchange(bm: BipedModel) -> LinearExchange | KinematicExchange:
    """The leg exchange of ``bm``: linear for legs of pitch joints only."""
    return KinematicExchange(bm) if bm.params.joints.lateral_hips else LinearExchange(bm)
