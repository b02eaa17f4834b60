"""The robot on MuJoCo's floor, its feet held by MuJoCo's own contacts (docs/model.md section 13.2):
the ``floating`` export (core/model/mjcf.py: a free pelvis, the URDF's joints with a motor each,
a point foot, a 1 mm sphere with the parameter set's friction, at each shin's tip, the floor); the
model's state placed on it, and measured back; the feet's contact forces.

**Frames.** MuJoCo's world is the step's model frame: the stance tip placed at the origin, the
model's stance leg MuJoCo's right leg (a left stance is the robot's mirror image, docs/model.md
section 5, the same motion: the robot is symmetric).

**The state measured** (``measure``): the model's coordinates are the joints' angles (each the
URDF joint's, ``urdf.UrdfJoints``, its sign) and the stance ankle's roll and pitch: the stance
shin's orientation in the world as intrinsic yaw, roll, pitch (z, x, y: the stance tree's ankle is
a roll, then a pitch; in closed form, a fiftieth of SciPy's ``Rotation`` call), its yaw dropped
(the model's pivot holds the foot's spin; MuJoCo's torsional friction holds it); their rates
likewise, from the shin's angular velocity on those three axes. Where the tips are (a contact's
penetration, a foot's creep) is not a coordinate: it shows as the measured state leaving the held
rows, which the balance's minimal coordinates (their null space) do not see.

Units SI, rad; forces N, moments N m.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ...dynamics.samples import SampleEvaluator
from ...model.mjcf import make_mjcf
from ...model.urdf import UrdfJoints

STANCE, SWING = "right", "left"  # MuJoCo's legs of the model's stance and swing legs
NOSLIP_ITERATIONS = 20
"""MuJoCo's no-slip post-processing of the friction forces (``opt.noslip_iterations``): without it
a soft contact's friction lets a loaded foot creep (the feet 1.1 mm further apart after 5 s of standing)."""
TOUCH_MARGIN = 1e-9
"""m: the feet's contact margin: a foot placed touching the floor (at distance 0) is in contact from
the start (MuJoCo makes a contact active below its margin, strictly; the floor moves by this much)."""


class FloatingRobot:
    """The floating export of ``samples``'s model (module docstring) and the maps between its state
    and the model's; ``timestep``: MuJoCo's step (s)."""

    def __init__(self, samples: SampleEvaluator, timestep: float) -> None:
        bm = samples.bm
        self.samples, self.nq = samples, bm.nq
        self.model = model = mujoco.MjModel.from_xml_string(make_mjcf(bm.params, "floating"))
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)  # as the planner: none enforced
        model.opt.timestep = timestep
        model.opt.noslip_iterations = NOSLIP_ITERATIONS
        joints = UrdfJoints(bm.params.joints, bm.coordinates)
        roles = joints.roles(STANCE)
        self._index = np.array([bm.names.index(name) for name, _ in roles])  # each joint's coordinate
        self._sign = np.array([sign for _, sign in roles])
        self._qpos = np.array([model.joint(name).qposadr[0] for name in joints.names])
        self._dof = np.array([model.joint(name).dofadr[0] for name in joints.names])
        self._ctrl = np.array([model.actuator(name).id for name in joints.names])
        self._ankle = np.setdiff1d(np.arange(bm.nq), self._index)  # the stance ankle's roll and pitch
        self._shin = model.body(f"{STANCE}_shin").id
        self.feet = tuple(model.geom(f"{side}_foot").id for side in (STANCE, SWING))
        model.geom_margin[list(self.feet)] = TOUCH_MARGIN
        self._tips = tuple(model.site(f"{side}_foot").id for side in (STANCE, SWING))
        self.actuated = np.asarray(bm.actuated)

    def data(self) -> mujoco.MjData:
        return mujoco.MjData(self.model)

    def place(self, data: mujoco.MjData, q: np.ndarray, qd: np.ndarray) -> None:
        """MuJoCo's state (qpos, qvel): the model's (``q``, ``qd``), the stance tip at the origin."""
        poses = self.samples.poses(q[None], qd[None])
        x, y, z, w = poses.pelvis_quaternion[0]
        data.qpos[:3], data.qpos[3:7] = poses.pelvis_position[0], (w, x, y, z)
        data.qpos[self._qpos] = q[self._index] * self._sign
        self.set_velocity(data, q, qd)

    def set_velocity(self, data: mujoco.MjData, q: np.ndarray, qd: np.ndarray) -> None:
        """MuJoCo's velocity (qvel): the model's ``qd`` at ``q``, MuJoCo's configuration kept (the
        pelvis's twist in its own frame is the model's)."""
        poses = self.samples.poses(q[None], qd[None])
        rotation = np.empty(9)
        mujoco.mju_quat2Mat(rotation, data.qpos[3:7])
        data.qvel[:3] = rotation.reshape(3, 3) @ poses.pelvis_linear_velocity[0]  # the free joint's: world axes
        data.qvel[3:6] = poses.pelvis_angular_velocity[0]  # and the body's
        data.qvel[self._dof] = qd[self._index] * self._sign

    def measure(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """The model's state (q, qd) measured from MuJoCo's qpos and qvel (module docstring)."""
        for stage in (mujoco.mj_kinematics, mujoco.mj_comPos, mujoco.mj_comVel):  # the shin's pose and velocity
            stage(self.model, data)
        q, qd = np.empty(self.nq), np.empty(self.nq)
        q[self._index], qd[self._index] = data.qpos[self._qpos] * self._sign, data.qvel[self._dof] * self._sign
        rotation = data.xmat[self._shin].reshape(3, 3)  # Rz(yaw) Rx(roll) Ry(pitch)
        yaw = math.atan2(-rotation[0, 1], rotation[1, 1])
        q[self._ankle] = math.asin(rotation[2, 1]), math.atan2(-rotation[2, 0], rotation[2, 2])
        spin = np.empty(6)
        mujoco.mj_objectVelocity(self.model, data, mujoco.mjtObj.mjOBJ_BODY, self._shin, spin, 0)
        axes = np.column_stack([(0.0, 0.0, 1.0), (np.cos(yaw), np.sin(yaw), 0.0), rotation[:, 1]])
        qd[self._ankle] = np.linalg.solve(axes, spin[:3])[1:]
        return q, qd

    def apply(self, data: mujoco.MjData, torque: np.ndarray) -> None:
        """The actuated joints' torques (N m, the model's actuated order) on MuJoCo's motors."""
        full = np.zeros(self.nq)
        full[self.actuated] = torque
        data.ctrl[self._ctrl] = full[self._index] * self._sign

    def tips(self, data: mujoco.MjData) -> np.ndarray:
        """Where the stance and the swing tip are (2 x 3, m)."""
        return np.array([data.site_xpos[site] for site in self._tips])

    def contact_forces(self, data: mujoco.MjData) -> np.ndarray:
        """[Fx, Fy, Fz, Mz] the floor exerts on the stance and on the swing foot (2 x 4: N; N m about
        the vertical through the tip): MuJoCo's contact forces (``mj_contactForce``; ``mj_forward``
        done), summed."""
        out = np.zeros((2, 4))
        tips = self.tips(data)
        wrench = np.empty(6)
        for k in range(data.ncon):
            contact = data.contact[k]
            for foot, geom in enumerate(self.feet):
                if geom not in (contact.geom1, contact.geom2):
                    continue
                mujoco.mj_contactForce(self.model, data, k, wrench)
                frame = contact.frame.reshape(3, 3)  # rows: the normal (from geom1 to geom2), two tangents
                sign = 1.0 if contact.geom2 == geom else -1.0  # on geom2; on geom1 the opposite
                force = sign * frame.T @ wrench[:3]
                arm = contact.pos - tips[foot]
                out[foot, :3] += force
                out[foot, 3] += sign * wrench[3] * frame[0, 2] + arm[0] * force[1] - arm[1] * force[0]
        return out
