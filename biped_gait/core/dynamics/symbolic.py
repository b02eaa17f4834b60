"""A Pinocchio model's inverse dynamics and frame positions as CasADi expressions.

The optimal-control problems of the lasting double support (``core/gait/lasting.py``) are solved by
IPOPT, which needs exact first and second derivatives of the equations of motion. Pinocchio's PyPI
wheel has no ``pinocchio.casadi``; this module writes the recursive Newton-Euler algorithm over the
same ``pin.Model`` (its joints' placements, axes and inertias read from the model, nothing
restated) in CasADi's symbols, so that CasADi's automatic differentiation gives IPOPT the exact
sparse Jacobians and Hessians. ``tests/test_lasting.py`` holds it to Pinocchio's own ``rnea`` and
frame placements at random states.

Spatial vectors follow Pinocchio's conventions: a motion (v, w) and a force (f, n), linear part
first, each expressed in its joint's frame. Joints: revolute about x, y or z and the 3D
translation (the models of ``core/model/biped.py``); another joint type is refused.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pinocchio as pin

_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}


def _rotation(axis: int, angle) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    if axis == 0:
        return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))
    if axis == 1:
        return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


def _unit(axis: int) -> ca.DM:
    e = np.zeros(3)
    e[axis] = 1.0
    return ca.DM(e)


class SymbolicModel:
    """``rnea`` and ``frame_position`` of a Pinocchio model of revolute and translation joints, as
    CasADi SX expressions of symbolic q, v, a (the model's nq = nv coordinates)."""

    def __init__(self, model: pin.Model) -> None:
        if model.nq != model.nv:
            raise ValueError(f"{model.name}: nq {model.nq} != nv {model.nv}: only revolute and translation joints")
        self.model = model
        self.joints = []  # (parent, placement R, p, kind, axis, index in q, inertia (m, c, I))
        for i in range(1, model.njoints):
            joint = model.joints[i]
            name = joint.shortname()
            if name in _AXES:
                kind, axis = "revolute", _AXES[name]
            elif name == "JointModelTranslation":
                kind, axis = "translation", -1
            else:
                raise ValueError(f"{model.name}: joint {model.names[i]} is a {name}, not revolute or translation")
            placement = model.jointPlacements[i]
            inertia = model.inertias[i]
            self.joints.append((model.parents[i], ca.DM(placement.rotation), ca.DM(placement.translation), kind, axis,
                                joint.idx_q, (float(inertia.mass), ca.DM(inertia.lever), ca.DM(inertia.inertia))))
        self.gravity = ca.DM(model.gravity.linear)

    def _transforms(self, q):
        """Each joint's placement in its parent (R, p) at the configuration q."""
        out = []
        for _parent, rotation, position, kind, axis, iq, _inertia in self.joints:
            if kind == "revolute":
                out.append((ca.mtimes(rotation, _rotation(axis, q[iq])), position))
            else:
                out.append((rotation, position + ca.mtimes(rotation, q[iq:iq + 3])))
        return out

    def placements(self, q) -> list:
        """Each joint's placement in the world (R, p), joint 1 first."""
        world = []
        for (parent, *_rest), (rotation, position) in zip(self.joints, self._transforms(q)):
            if parent == 0:
                world.append((rotation, position))
            else:
                r0, p0 = world[parent - 1]
                world.append((ca.mtimes(r0, rotation), p0 + ca.mtimes(r0, position)))
        return world

    def frame_position(self, q, frame: str):
        """The world position (m) of a frame of the model at q."""
        f = self.model.frames[self.model.getFrameId(frame)]
        if f.parentJoint == 0:
            return ca.DM(f.placement.translation)
        rotation, position = self.placements(q)[f.parentJoint - 1]
        return position + ca.mtimes(rotation, ca.DM(f.placement.translation))

    def rnea(self, q, v, a):
        """The generalized forces (N, N m) that give the accelerations a at (q, v) under gravity."""
        transforms = self._transforms(q)
        vel, acc, force, subspace = [], [], [], []
        for joint, (rotation, position) in zip(self.joints, transforms):
            parent, _r, _p, kind, axis, iq, (mass, lever, rot_inertia) = joint
            if kind == "revolute":
                s_lin, s_ang = [ca.DM.zeros(3, 1)], [_unit(axis)]
                qd, qdd = [v[iq]], [a[iq]]
            else:
                s_lin = [_unit(k) for k in range(3)]
                s_ang = [ca.DM.zeros(3, 1)] * 3
                qd, qdd = [v[iq + k] for k in range(3)], [a[iq + k] for k in range(3)]
            j_lin = sum((s * d for s, d in zip(s_lin, qd)), ca.SX.zeros(3, 1))
            j_ang = sum((s * d for s, d in zip(s_ang, qd)), ca.SX.zeros(3, 1))
            jd_lin = sum((s * d for s, d in zip(s_lin, qdd)), ca.SX.zeros(3, 1))
            jd_ang = sum((s * d for s, d in zip(s_ang, qdd)), ca.SX.zeros(3, 1))
            if parent == 0:
                pv, pw = ca.SX.zeros(3, 1), ca.SX.zeros(3, 1)
                pa, pal = -self.gravity, ca.SX.zeros(3, 1)
            else:
                (pv, pw), (pa, pal) = vel[parent - 1], acc[parent - 1]
            rt = rotation.T
            # The parent's motion in this joint's frame (SE3 actInv), then the joint's own.
            vi_lin = ca.mtimes(rt, pv - ca.cross(position, pw)) + j_lin
            vi_ang = ca.mtimes(rt, pw) + j_ang
            ai_lin = (ca.mtimes(rt, pa - ca.cross(position, pal)) + jd_lin + ca.cross(vi_ang, j_lin)
                      + ca.cross(vi_lin, j_ang))
            ai_ang = ca.mtimes(rt, pal) + jd_ang + ca.cross(vi_ang, j_ang)
            vel.append((vi_lin, vi_ang))
            acc.append((ai_lin, ai_ang))
            # f = I a + v x* (I v), the inertia about the joint frame's origin with its CoM at lever.
            hv = mass * (vi_lin - ca.cross(lever, vi_ang))
            hw = ca.mtimes(rot_inertia, vi_ang) + ca.cross(lever, hv)
            fa = mass * (ai_lin - ca.cross(lever, ai_ang))
            na = ca.mtimes(rot_inertia, ai_ang) + ca.cross(lever, fa)
            force.append([fa + ca.cross(vi_ang, hv), na + ca.cross(vi_ang, hw) + ca.cross(vi_lin, hv)])
            subspace.append((s_lin, s_ang, iq))
        tau = [None] * self.model.nv
        for i in range(len(self.joints) - 1, -1, -1):
            f, n = force[i]
            s_lin, s_ang, iq = subspace[i]
            for k, (sl, sa) in enumerate(zip(s_lin, s_ang)):
                tau[iq + k] = ca.dot(sl, f) + ca.dot(sa, n)
            parent = self.joints[i][0]
            if parent > 0:
                rotation, position = transforms[i]
                pf = ca.mtimes(rotation, f)
                force[parent - 1][0] = force[parent - 1][0] + pf
                force[parent - 1][1] = force[parent - 1][1] + ca.mtimes(rotation, n) + ca.cross(position, pf)
        return ca.vertcat(*tau)
