"""The gait modes and the double-support configurations of a gait (docs/model.md section 3).

Angles in radians, lengths in metres. q in the single-support coordinates of the model
(``model.biped``, stance leg 1 on the right), built from the joint table's roles.
"""

from __future__ import annotations

import math
from enum import Enum
from functools import lru_cache

import numpy as np

from ..model.biped import BipedModel
from ..model.rotations import euler, rotation


class GaitMode(str, Enum):
    """Arm swing relative to the legs: ``normal`` (opposite phase, as people walk) or ``anti-normal``."""

    NORMAL = "normal"
    ANTI_NORMAL = "anti-normal"

    @classmethod
    def parse(cls, value: "str | GaitMode") -> "GaitMode":
        """Accept a mode or its name (``normal``, ``anti-normal``, also ``anti_normal``)."""
        if isinstance(value, cls):
            return value
        text = str(value).strip().lower().replace("_", "-")
        for mode in cls:
            if mode.value == text:
                return mode
        raise ValueError(f"unknown gait mode {value!r}: use 'normal' or 'anti-normal'")

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)


def half_step_angle(step_length: float, leg_length: float) -> float:
    """beta = asin(L / (2 l)) (rad): each straight leg's pitch at double support."""
    return math.asin(step_length / (2.0 * leg_length))


def arm_angles(arm_amplitude: float, mode: GaitMode) -> tuple[float, float]:
    """Shoulder angles (a6, a7) at t = 0 (rad); normal: the stance-side arm is back (+alpha)."""
    sign = 1.0 if mode is GaitMode.NORMAL else -1.0
    return sign * arm_amplitude, -sign * arm_amplitude


class BoundaryConfigurations:
    """q(0) (stance leg in front) and q(T) (swing leg in front, its tip at (L, w, 0)) of the straight
    gaits of ``bm`` at step length L (m), arm amplitude alpha (rad), mode, trunk pitch theta
    (rad) and step width w (m, between the feet; None: the hips' spacing).

    Both feet on the ground, the legs straight, the torso not yawed, the pelvis level and facing
    forward, pitched by theta, midway between the feet. At the hips' spacing the legs lie in
    sagittal planes: the ankle roll and the hips' lateral joints are zero, the pitches those of
    docs/model.md section 3. At another width (lateral hip joints needed) each leg leans in the
    frontal plane by the ankle roll that puts its hip above the line to the other foot's, and each
    hip's joints are the rotation from the pelvis to its thigh resolved on their axes."""

    def __init__(self, bm: BipedModel) -> None:
        self.bm = bm
        p = bm.params
        self.leg_length, self.hip_spacing = p.leg_length, p.hip_spacing
        index = bm.index
        self._stance = {role: index(role, "stance") for role in p.joints.hip_roles}
        self._swing = {role: index(role, "swing") for role in p.joints.hip_roles}
        self._roll, self._pitch = index("ankle_roll"), index("ankle_pitch")
        self._arms = (index("shoulder", "stance"), index("shoulder", "swing"))
        self._sequence = "".join(p.joints.role(role).axis for role in p.joints.hip_roles)
        self.theta_direction = np.zeros(bm.nq)
        """d q / d theta at the hips' spacing, the same at both ends: +1 on the stance hip's pitch,
        -1 on the swing hip's (the pelvis and trunk pitch, the legs stay)."""
        self.theta_direction[self._stance["hip_pitch"]] = 1.0
        self.theta_direction[self._swing["hip_pitch"]] = -1.0

    def width(self, step_width: float | None) -> float:
        """The step width (m) a request means: its own, or the hips' spacing."""
        return self.hip_spacing if step_width is None else step_width

    def sagittal(self, step_width: float | None) -> bool:
        """Whether the legs lie in sagittal planes at this width (the hips' spacing)."""
        return step_width is None or step_width == self.hip_spacing

    def __call__(self, step_length: float, arm_amplitude: float, mode: GaitMode, theta: float,
                 step_width: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        beta = half_step_angle(step_length, self.leg_length)
        a6, a7 = arm_angles(arm_amplitude, mode)
        q0, q_t = np.zeros(self.bm.nq), np.zeros(self.bm.nq)
        (s6, s7) = self._arms
        q0[s6], q0[s7], q_t[s6], q_t[s7] = a6, a7, -a6, -a7
        if self.sagittal(step_width):
            q0[self._pitch], q0[self._stance["hip_pitch"]], q0[self._swing["hip_pitch"]] = -beta, beta + theta, beta - theta
            q_t[self._pitch], q_t[self._stance["hip_pitch"]], q_t[self._swing["hip_pitch"]] = beta, theta - beta, -beta - theta
            return q0, q_t
        if len(self._sequence) != 3:
            raise ValueError(f"a step width other than the hips' spacing ({self.hip_spacing:g} m) needs hips with "
                             "roll and yaw joints")
        for q, forward in ((q0, -1.0), (q_t, 1.0)):
            self._lean(q, forward * step_length, step_width, theta)
        return q0, q_t

    def _lean(self, q: np.ndarray, reach: float, step_width: float, theta: float) -> None:
        """The legs of ``q`` at width ``step_width`` with the stance hip ``reach``/2 ahead of the
        stance foot (reach = L at T, -L at 0)."""
        lateral = step_width / 2 - self.bm.params.hip_half_width  # the stance hip beside its foot (m, +y)
        height = math.sqrt(self.leg_length ** 2 - reach ** 2 / 4 - lateral ** 2)
        pelvis = rotation("y", theta)

        def shin(dx: float, dy: float) -> tuple[float, float, np.ndarray]:
            pitch = math.asin(dx / self.leg_length)
            roll = math.atan2(-dy, height)
            return roll, pitch, rotation("x", roll) @ rotation("y", pitch)

        roll, pitch, stance = shin(reach / 2, lateral)
        q[self._roll], q[self._pitch] = roll, pitch
        for angle, role in zip(euler(pelvis.T @ stance, self._sequence), self.bm.params.joints.hip_roles):
            q[self._stance[role]] = -angle  # the stance leg's coordinates are its joints' inverse rotations
        _, _, swing = shin(-reach / 2, -lateral)  # the other foot, from its own tip to its hip
        for angle, role in zip(euler(pelvis.T @ swing, self._sequence), self.bm.params.joints.hip_roles):
            q[self._swing[role]] = angle

    def theta_derivatives(self, step_length: float, arm_amplitude: float, mode: GaitMode, theta: float,
                          step_width: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """d q(0) / d theta and d q(T) / d theta: ``theta_direction`` at the hips' spacing, else
        by central differences (1e-6 rad)."""
        if self.sagittal(step_width):
            return self.theta_direction, self.theta_direction
        h = 1e-6
        plus = self(step_length, arm_amplitude, mode, theta + h, step_width)
        minus = self(step_length, arm_amplitude, mode, theta - h, step_width)
        return (plus[0] - minus[0]) / (2 * h), (plus[1] - minus[1]) / (2 * h)


@lru_cache(maxsize=32)
def boundary_configurations(bm: BipedModel) -> BoundaryConfigurations:
    """The double-support configurations of ``bm`` (built once per model)."""
    return BoundaryConfigurations(bm)
