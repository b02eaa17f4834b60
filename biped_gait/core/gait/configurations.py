"""The gait modes and the double-support configurations of a gait (docs/model.md section 3).

Angles in radians, lengths in metres. q = [q1..q9] in the single-support coordinates of
``biped_gait.model`` (stance leg 1 on the right).
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np


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


# d q(0) / d theta and d q(T) / d theta: theta enters q4 with +1 and q8 with -1 at both ends.
THETA_DIRECTION = np.array([0, 0, 0, 1.0, 0, 0, 0, -1.0, 0])


def half_step_angle(step_length: float, leg_length: float) -> float:
    """beta = asin(L / (2 l)) (rad): each straight leg's pitch at double support."""
    return math.asin(step_length / (2.0 * leg_length))


def arm_angles(arm_amplitude: float, mode: GaitMode) -> tuple[float, float]:
    """Shoulder angles (a6, a7) at t = 0 (rad); normal: the stance-side arm is back (+alpha)."""
    sign = 1.0 if mode is GaitMode.NORMAL else -1.0
    return sign * arm_amplitude, -sign * arm_amplitude


def boundary_configurations(
    step_length: float, leg_length: float, arm_amplitude: float, mode: GaitMode, theta: float
) -> tuple[np.ndarray, np.ndarray]:
    """q(0) (stance leg in front) and q(T) (swing leg in front, its tip at x = L), docs/model.md section 3."""
    beta = half_step_angle(step_length, leg_length)
    a6, a7 = arm_angles(arm_amplitude, mode)
    q0 = np.array([0.0, -beta, 0.0, beta + theta, 0.0, a6, a7, beta - theta, 0.0])
    q_t = np.array([0.0, beta, 0.0, theta - beta, 0.0, -a6, -a7, -beta - theta, 0.0])
    return q0, q_t
