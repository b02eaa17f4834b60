"""Rotation matrices about the frame axes and their Tait-Bryan angles, for the configurations'
geometry (a few microseconds a call, where SciPy's ``Rotation`` costs a hundred). Angles in rad.
"""

from __future__ import annotations

import math

import numpy as np

_AXES = {"x": 0, "y": 1, "z": 2}


def rotation(axis: str, angle: float) -> np.ndarray:
    """The rotation by ``angle`` (rad) about the frame's ``axis`` (x, y or z), right-handed."""
    c, s = math.cos(angle), math.sin(angle)
    i = _AXES[axis]
    j, k = (i + 1) % 3, (i + 2) % 3
    out = np.eye(3)
    out[j, j], out[j, k], out[k, j], out[k, k] = c, -s, s, c
    return out


def euler(matrix: np.ndarray, axes: str) -> tuple[float, float, float]:
    """(a, b, c) (rad) with ``matrix`` = R_axes[0](a) R_axes[1](b) R_axes[2](c), for three distinct
    axes (intrinsic Tait-Bryan angles; b in [-pi/2, pi/2])."""
    i, j, k = (_AXES[a] for a in axes.lower())
    sign = 1.0 if (j - i) % 3 == 1 else -1.0  # an even permutation of (x, y, z)
    b = math.asin(max(-1.0, min(1.0, sign * matrix[i, k])))
    a = math.atan2(-sign * matrix[j, k], matrix[k, k])
    c = math.atan2(-sign * matrix[i, j], matrix[i, i])
    return a, b, c
