"""Many states of the biped evaluated in one call: what the figures of a step, the walker and
the world view need of each sample (docs/model.md sections 6 and 8).

A sample is a state (q, qd) of the single-support model (rad, rad/s) with the stance tip at
the world origin; a batch is n of them, the rows of two n x nq arrays. ``SampleEvaluator`` gives,
for each row:

- ``dynamics``: the ballistic acceleration qdd (ABA, rad/s^2), the ground reaction [Fx, Fy, Fz,
  Mz] at the stance tip (paper eq. 1, by RNEA of the extended model with the root at rest; N,
  N m), the swing-tip height (m), the yaw angular momentum about the vertical through the
  stance tip (kg m^2/s), and the height of the lowest knee, hip, shoulder or hand (m);
- ``swing_tip_motion``: the swing-tip height (m) and vertical velocity (m/s), the touchdown
  guard's witness and its rate;
- ``poses``: the pelvis placement and velocity, the CoM, the linear momentum and the angular
  momentum about the stance tip;
- ``energy``: kinetic plus gravitational potential energy (J).

``JointPlacements`` gives the placements of every joint of a Pinocchio model in its parent's
frame (the URDF's link transforms) for many configurations.

Vectors are in world axes, model frame (stance leg 1 on the right), unless said otherwise. Each
runs in the compiled twin (core/dynamics/native/samples.cpp, built by tools/build_native.sh) when it is
built (``native=None``) or in the Python loops below (``native=False``): the same Pinocchio
algorithms, the same results to rounding (tests/test_samples.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..model.biped import PELVIS, SWING_TIP, BipedModel

try:
    from ._samples_native import NativePlacements, NativeSamples
except ImportError:  # not built (no compiler): the Python loops serve
    NativePlacements = NativeSamples = None



@dataclass(frozen=True, eq=False)
class SampleDynamics:
    """Per sample (row): qdd (rad/s^2); the ground reaction [Fx, Fy, Fz, Mz] at the stance tip (N,
    N m); the swing-tip height (m); the yaw angular momentum about the vertical through the stance
    tip (kg m^2/s); the height of the lowest knee, hip, shoulder or hand (m)."""

    qdd: np.ndarray
    grf: np.ndarray
    swing_height: np.ndarray
    yaw_momentum: np.ndarray
    lowest_link: np.ndarray


@dataclass(frozen=True, eq=False)
class SamplePoses:
    """Per sample (row): the pelvis position (m) and orientation (quaternion x, y, z, w; of the
    mirror image M R M, M = diag(1, -1, 1), when asked for mirrored); the pelvis velocity in the
    pelvis frame, linear (m/s) and angular (rad/s); the CoM (m); the linear momentum (kg m/s);
    the angular momentum about the stance tip (kg m^2/s)."""

    pelvis_position: np.ndarray
    pelvis_quaternion: np.ndarray
    pelvis_linear_velocity: np.ndarray
    pelvis_angular_velocity: np.ndarray
    com: np.ndarray
    momentum: np.ndarray
    angular_momentum: np.ndarray


def ground_reaction_inverse_dynamics(bm: BipedModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """[Fx, Fy, Fz, Mz] at the stance tip by RNEA of the extended model with the root at rest.

    The generalized force of the root translation joint is the ground force; the spatial force
    that joint transmits, taken at the tip with world axes, gives the vertical moment.
    """
    model, data = bm.extended, bm.extended_data
    x = bm.extended_state(q)
    xd = np.concatenate([np.zeros(3), qd])
    xdd = np.concatenate([np.zeros(3), qdd])  # the extended model: the root translation, then q
    tau = pin.rnea(model, data, x, xd, xdd)
    return np.array([tau[0], tau[1], tau[2], data.f[1].angular[2]])


def _compiled(native: bool | None) -> bool:
    """Whether to evaluate in the compiled twin: ``native``, or None for "when it is built"."""
    if native is None:
        return NativeSamples is not None
    if native and NativeSamples is None:
        raise ValueError("the compiled sample evaluation is not built: run tools/build_native.sh")
    return native


def _rows(a: np.ndarray, width: int) -> np.ndarray:
    """``a`` as a C-ordered float array of rows (a single state becomes one row) of ``width``."""
    rows = np.ascontiguousarray(np.atleast_2d(a), dtype=float)
    if rows.ndim != 2 or rows.shape[1] != width:
        raise ValueError(f"expected an n x {width} array, got shape {np.shape(a)}")
    return rows


class SampleEvaluator:
    """Evaluates batches of single-support states of ``bm``; ``native``: in the compiled twin
    (None: when it is built; False: the Python loops). Not thread-safe (Pinocchio data reused)."""

    def __init__(self, bm: BipedModel, native: bool | None = None) -> None:
        self.bm = bm
        model = bm.single
        self._swing_tip = model.getFrameId(SWING_TIP)
        pelvis = model.frames[model.getFrameId(PELVIS)]
        self._pelvis, self._pelvis_offset = pelvis.parentJoint, pelvis.placement.translation.copy()
        # The stance knee and every joint after it must stay above the ground.
        self._links = list(range(model.getJointId(bm.names[bm.index("knee")]), model.njoints))
        self._arms = [model.getJointId(bm.names[bm.index("shoulder", side)]) for side in ("stance", "swing")]
        self._hand = np.array([0.0, 0.0, -bm.params.arm.length])  # in the shoulder joint's frame
        self._tau = np.zeros(model.nv)
        self.native = (
            NativeSamples(model.saveToString(), bm.extended.saveToString(), self._swing_tip, self._pelvis,
                          self._pelvis_offset, self._links, self._arms, bm.params.arm.length)
            if _compiled(native) else None
        )

    def _states(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q, qd) as two n x nq arrays of the same n; ``ValueError`` if they are not."""
        q, qd = _rows(q, self.bm.single.nq), _rows(qd, self.bm.single.nv)
        if len(q) != len(qd):
            raise ValueError(f"q and qd must have as many rows, got {len(q)} and {len(qd)} (n x {self.bm.nq} arrays)")
        return q, qd

    def dynamics(self, q: np.ndarray, qd: np.ndarray) -> SampleDynamics:
        """qdd, ground reaction, swing-tip height, yaw momentum and lowest link of each (q, qd) row."""
        q, qd = self._states(q, qd)
        if self.native is not None:
            return SampleDynamics(*self.native.dynamics(q, qd))
        bm, model, data = self.bm, self.bm.single, self.bm.single_data
        n = len(q)
        qdd, grf = np.empty((n, model.nv)), np.empty((n, 4))
        height, yaw, lowest = np.empty(n), np.empty(n), np.empty(n)
        origin = np.zeros(3)
        for i in range(n):
            qdd[i] = pin.aba(model, data, q[i], qd[i], self._tau)
            grf[i] = ground_reaction_inverse_dynamics(bm, q[i], qd[i], qdd[i])
            yaw[i] = bm.vertical_momentum_about(q[i], bm.embed(qd[i]), origin)
            pin.forwardKinematics(model, data, q[i])
            height[i] = pin.updateFramePlacement(model, data, self._swing_tip).translation[2]
            lowest[i] = min([data.oMi[j].translation[2] for j in self._links]
                            + [data.oMi[j].act(self._hand)[2] for j in self._arms])
        return SampleDynamics(qdd, grf, height, yaw, lowest)

    def swing_tip_motion(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Swing-tip height (m) and vertical velocity (m/s) of each (q, qd) row."""
        q, qd = self._states(q, qd)
        if self.native is not None:
            return self.native.swing_tip_motion(q, qd)
        model, data = self.bm.single, self.bm.single_data
        height, vz = np.empty(len(q)), np.empty(len(q))
        for i in range(len(q)):
            pin.forwardKinematics(model, data, q[i], qd[i])
            height[i] = pin.updateFramePlacement(model, data, self._swing_tip).translation[2]
            vz[i] = pin.getFrameVelocity(model, data, self._swing_tip, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).linear[2]
        return height, vz

    def poses(self, q: np.ndarray, qd: np.ndarray, mirrored: bool = False) -> SamplePoses:
        """Pelvis placement and velocity, CoM and momenta of each (q, qd) row; the pelvis
        orientation of the mirror image (y -> -y) when ``mirrored``."""
        q, qd = self._states(q, qd)
        if self.native is not None:
            position, quaternion, velocity, com, p, h = self.native.poses(q, qd, mirrored)
            return SamplePoses(position, quaternion, velocity[:, :3], velocity[:, 3:], com, p, h)
        bm, model, data = self.bm, self.bm.single, self.bm.single_data
        m = np.diag([1.0, -1.0 if mirrored else 1.0, 1.0])
        n = len(q)
        position, quaternion, velocity = np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 6))
        com, p, h = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        offset = self._pelvis_offset  # the pelvis centre in its joint's frame
        for i in range(n):
            pin.forwardKinematics(model, data, q[i], qd[i])
            pelvis = data.oMi[self._pelvis]
            position[i] = pelvis.translation + pelvis.rotation @ offset
            quaternion[i] = pin.Quaternion(m @ pelvis.rotation @ m).coeffs()
            twist = data.v[self._pelvis]
            velocity[i] = np.concatenate([twist.linear + np.cross(twist.angular, offset), twist.angular])
            p[i], h[i], com[i] = bm.momentum(q[i], bm.embed(qd[i]))
        return SamplePoses(position, quaternion, velocity[:, :3], velocity[:, 3:], com, p, h)

    def energy(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Kinetic plus gravitational potential energy (J) of each (q, qd) row, zero height at the
        stance tip."""
        q, qd = self._states(q, qd)
        if self.native is not None:
            return self.native.energy(q, qd)
        model, data = self.bm.single, self.bm.single_data
        return np.array([pin.computeKineticEnergy(model, data, a, b) + pin.computePotentialEnergy(model, data, a)
                         for a, b in zip(q, qd)])


class JointPlacements:
    """The placement of every joint of ``model`` in its parent joint's frame (Pinocchio's liMi)
    for many configurations; ``native`` as for ``SampleEvaluator``."""

    def __init__(self, model: pin.Model, native: bool | None = None) -> None:
        self.model = model
        self.data = model.createData()
        self.native = NativePlacements(model.saveToString()) if _compiled(native) else None

    def local(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Translations (n x joints x 3, m) and quaternions (n x joints x 4, x, y, z, w) of joints
        1, 2, ... in their parents' frames, for each configuration row of ``q``."""
        q = _rows(q, self.model.nq)
        joints = self.model.njoints - 1
        if self.native is not None:
            translation, quaternion = self.native.local(q)
            return translation.reshape(len(q), joints, 3), quaternion.reshape(len(q), joints, 4)
        translation, quaternion = np.empty((len(q), joints, 3)), np.empty((len(q), joints, 4))
        for i, row in enumerate(q):
            pin.forwardKinematics(self.model, self.data, row)
            for j in range(joints):
                placement = self.data.liMi[j + 1]
                translation[i, j] = placement.translation
                quaternion[i, j] = pin.Quaternion(placement.rotation).coeffs()
        return translation, quaternion
