"""A-posteriori figures of a ballistic step (docs/model.md section 6).

Ground reaction at the stance tip (paper eq. 1: three forces, N, and the moment about the
vertical, N m), by inverse dynamics (``samples``, reported) and by Newton-Euler on the whole body
(here, the check); swing-tip height (m); friction ratio; angular momentum about vertical axes
(kg m^2/s); energy drift. Everything in the world frame, stance tip at the origin.
"""

from __future__ import annotations

import math

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..model.biped import BipedModel, cross
from ..dynamics.samples import SampleEvaluator


@dataclass(frozen=True, eq=False)
class StepTrajectory:
    """Samples of one ballistic step: t (s), q (rad), qd (rad/s), qdd (rad/s^2), each row a time."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray


def ground_reaction_momentum(bm: BipedModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """[Fx, Fy, Fz, Mz] at the stance tip from Newton-Euler on the whole body.

    F = m a_G - m g (CoM acceleration); Mz = d/dt of the angular momentum about the vertical
    through the tip (gravity has no vertical moment, the ground force none about the tip).
    """
    model, data = bm.single, bm.single_data
    pin.centerOfMass(model, data, q, qd, qdd)  # com, vcom, acom
    pin.computeCentroidalMomentumTimeVariation(model, data, q, qd, qdd)
    mass = data.mass[0]
    com, acom = data.com[0], data.acom[0]
    force = mass * acom - mass * model.gravity.linear
    # d/dt (h_G + c x m v_G) = dh_G + c x m a_G (the v_G x m v_G term is zero).
    dh_origin = data.dhg.angular + cross(com, mass * acom)
    return np.array([force[0], force[1], force[2], dh_origin[2]])


def energy_drift(samples: SampleEvaluator, q: np.ndarray, qd: np.ndarray) -> float:
    """max |E / E(first row) - 1| over the rows of (q, qd), E the total mechanical energy: how far
    a ballistic integration is from conserving energy (dimensionless)."""
    e = samples.energy(q, qd)
    return float(np.max(np.abs(e / e[0] - 1)))


@dataclass(frozen=True, eq=False)
class StepFigures:
    """The figures of a ballistic step; ``samples``, ``grf`` and ``h_vertical`` are its sampled
    curves (None once dropped, as sweeps do to keep results small)."""

    samples: StepTrajectory | None
    grf: np.ndarray | None  # samples x 4: Fx, Fy, Fz (N), Mz (N m)
    h_vertical: np.ndarray | None  # samples, kg m^2/s, about the vertical through the stance tip
    min_grf_z: float
    min_swing_height: float
    max_friction_ratio: float
    q3_range: tuple[float, float]  # rad, the stance knee (q3 of the paper's nine coordinates)
    q5_range: tuple[float, float]  # rad, the torso yaw (q5)
    q9_min: float  # rad, the least swing-knee angle (q9)
    energy_drift: float
    min_late_swing_height: float  # m, on [0.95 T, T): where the swing tip comes down to the ground
    swing_arrival_speed: float  # m/s, the swing tip's vertical velocity at the touchdown (T-)

    def without_samples(self) -> "StepFigures":
        """These figures without the sampled curves."""
        return replace(self, samples=None, grf=None, h_vertical=None)


def step_figures(
    samples: SampleEvaluator, t: np.ndarray, q: np.ndarray, qd: np.ndarray, period: float, drift: float
) -> StepFigures:
    """The figures of a step sampled at times ``t`` (s) in states (q, qd) (rows), evaluated in one
    call: ground reaction, swing clearance on (0.05 T, 0.95 T) and on [0.95 T, T), the swing
    tip's vertical velocity at the last sample (the touchdown, t = T), friction ratio, joint
    ranges, yaw momentum, and the integration's energy ``drift``."""
    bm = samples.bm
    knee, torso, swing_knee = bm.index("knee"), bm.index("torso_yaw", ""), bm.index("knee", "swing")
    evaluated = samples.dynamics(q, qd)
    grf = evaluated.grf
    interior = (t > 0.05 * period) & (t < 0.95 * period)
    heights = evaluated.swing_height[interior]
    late = evaluated.swing_height[(t >= 0.95 * period) & (t < t[-1])]
    _, arrival = samples.swing_tip_motion(q[-1:], qd[-1:])
    fz = grf[:, 2]
    ratio = np.where(fz > 0, np.hypot(grf[:, 0], grf[:, 1]) / np.where(fz > 0, fz, 1.0), np.inf)
    return StepFigures(
        samples=StepTrajectory(t, q, qd, evaluated.qdd),
        grf=grf,
        h_vertical=evaluated.yaw_momentum,
        min_grf_z=float(fz.min()),
        min_swing_height=float(heights.min()),
        max_friction_ratio=float(ratio.max()),
        q3_range=(float(q[:, knee].min()), float(q[:, knee].max())),
        q5_range=(float(q[:, torso].min()), float(q[:, torso].max())),
        q9_min=float(q[:, swing_knee].min()),
        energy_drift=drift,
        min_late_swing_height=float(late.min()) if late.size else math.inf,
        swing_arrival_speed=float(arrival[0]),
    )
