"""The double-support configuration of a step on a circle (docs/model.md section 3.1): the pelvis
on a circle of radius R (m, signed: positive turns left, the circle's centre on the +y side),
advancing the arc L per step, its heading changing by L / R; each leg in the vertical plane of
its foot (both ankle rolls zero, so that the momentum about the feet line is conserved exactly,
docs/model.md section 5.2). Angles in rad, lengths in m, the stance foot at the origin facing +x,
stance leg 1 on the right.

Geometry, about the circle's centre C: the pelvis centre at radius |R| midway (in angle) between
the feet, facing the circle's tangent, pitched by theta and rolled by phi (one hip lower); each
hip in its foot's tangent plane, so a foot is at radius rho cos(L / 2R), rho its hip's radius;
the stance foot half a step behind the pelvis, the landing foot half a step ahead. phi and the
pelvis height follow from both legs being straight (length l), by Newton's method. As R grows
the configuration tends to the straight gait's q(T) at the hips' spacing.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.biped import BipedModel
from ..model.rotations import euler, rotation as _rot
from .configurations import GaitMode, arm_angles

TOLERANCE = 1e-14  # m: the legs' lengths
ITERATIONS = 30


class TurningConfiguration:
    """The touchdown configuration q(T) of a step on a circle, for the model ``bm`` (hip roll and
    yaw joints needed: the legs leave the pelvis's sagittal plane)."""

    def __init__(self, bm: BipedModel) -> None:
        p = bm.params
        if not p.joints.lateral_hips:
            raise ValueError(f"parameter set {p.name} walks straight only: walking on a circle needs hip roll and "
                             "yaw joints (e.g. aoustin2013-hips)")
        self.bm = bm
        self.leg_length, self.half_width = p.leg_length, p.hip_half_width
        self.roles = p.joints.hip_roles
        self.sequence = "".join(p.joints.role(role).axis for role in self.roles)
        self.index = {(side, role): bm.index(role, side) for side in ("stance", "swing") for role in self.roles}
        self.roll, self.pitch = bm.index("ankle_roll"), bm.index("ankle_pitch")
        self.arms = (bm.index("shoulder", "stance"), bm.index("shoulder", "swing"))

    def __call__(self, step_length: float, arm_amplitude: float, mode: GaitMode, theta: float, radius: float,
                 lean: float = 0.0) -> np.ndarray:
        """q(T) at the end of a step of arc ``step_length`` (m) on the circle of signed ``radius``
        (m) with the pelvis pitched by ``theta`` (rad), the body leaning by ``lean`` (rad) into the
        turn (the pelvis moved towards the circle's centre by its height times tan(lean), the
        feet where they are without it; the legs then roll); the landing foot's heading is L / R."""
        if not math.isfinite(radius) or abs(radius) <= self.half_width:
            raise ValueError(f"turn radius must be finite and more than the hips' half spacing "
                             f"({self.half_width:g} m), got {radius:g} m")
        half = step_length / (2 * radius)  # half the heading change per step (rad), signed
        x = self._straighten(radius, half, np.array([0.0, math.sqrt(self.leg_length ** 2 - step_length ** 2 / 4)]))
        feet = self._legs(radius, half, *x)[2]
        if lean:
            x = self._straighten(radius, half, x, math.copysign(x[1] * math.tan(lean), radius), feet)
        _, shins, _ = self._legs(radius, half, *x, math.copysign(x[1] * math.tan(lean), radius), feet)
        pelvis = _rot("z", half) @ _rot("x", x[0]) @ _rot("y", theta)  # in the stance foot's frame
        q = np.zeros(self.bm.nq)
        q[self.roll], q[self.pitch] = shins[0][0], shins[0][1]
        for (_, _, shin), side, sign in zip(shins, ("stance", "swing"), (-1.0, 1.0)):
            angles = euler(pelvis.T @ shin, self.sequence)
            for angle, role in zip(angles, self.roles):
                q[self.index[side, role]] = sign * angle  # the stance leg's coordinates are inverse rotations
        a6, a7 = arm_angles(arm_amplitude, mode)
        q[self.arms[0]], q[self.arms[1]] = -a6, -a7
        return q

    def _straighten(self, radius: float, half: float, x: np.ndarray, shift: float = 0.0,
                    feet: list[np.ndarray] | None = None) -> np.ndarray:
        """The pelvis roll (rad) and height (m) at which both legs are straight, by Newton's
        method from ``x``."""
        for _ in range(ITERATIONS):
            errors = self._legs(radius, half, *x, shift, feet)[0]
            if np.max(np.abs(errors)) < TOLERANCE:
                return x
            jac = np.column_stack([(self._legs(radius, half, *(x + step), shift, feet)[0] - errors) / 1e-7
                                   for step in (np.array([1e-7, 0.0]), np.array([0.0, 1e-7]))])
            x = x - np.linalg.solve(jac, errors)
        raise ValueError(f"no straight-legged double support on a circle of radius {radius:g} m")

    def _legs(self, radius: float, half: float, roll: float, height: float, shift: float = 0.0,
              feet: list[np.ndarray] | None = None) -> tuple[np.ndarray, list, list[np.ndarray]]:
        """Both legs' length errors (m) with the pelvis rolled by ``roll`` (rad) at ``height`` (m)
        and moved ``shift`` (m) towards the circle's centre, each shin's (roll rad, pitch rad,
        orientation in the stance foot's frame), and the feet: ``feet``, or each below its hip in
        its tangent plane. The stance (right) hip half a step behind, the swing (left) hip half a
        step ahead; worked in the frame of the pelvis's heading, on the ground below it, the
        circle's centre at (0, R)."""
        h, centre = self.half_width, np.array([0.0, radius, 0.0])
        errors, shins, placed = [], [], []
        for k, (lateral, angle) in enumerate(((-1.0, -half), (1.0, half))):
            hip = np.array([0.0, shift + lateral * h * math.cos(roll), height + lateral * h * math.sin(roll)])
            heading = _rot("z", angle)  # the foot's: the circle's tangent there
            if feet is None:
                ray = heading @ np.array([0.0, -math.copysign(1.0, radius), 0.0])  # from the centre to the foot
                foot = centre + float((hip - centre) @ ray) * ray  # the hip in the foot's tangent plane
                foot[2] = 0.0
            else:
                foot = feet[k]
            leg = heading.T @ (hip - foot)  # (forward, lateral, up) in the foot's frame
            errors.append(float(np.linalg.norm(leg)) - self.leg_length)
            shin_roll = math.atan2(-leg[1], leg[2])
            pitch = math.asin(max(-1.0, min(1.0, leg[0] / np.linalg.norm(leg))))
            shins.append((shin_roll, pitch, _rot("z", half) @ heading @ _rot("x", shin_roll) @ _rot("y", pitch)))
            placed.append(foot)
        return np.array(errors), shins, placed
