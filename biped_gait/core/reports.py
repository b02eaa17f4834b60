"""A-posteriori figures of a ballistic step (docs/model.md section 6).

Ground reaction at the stance tip (paper eq. 1: three forces, N, and the moment about the
vertical, N m), computed two ways; swing-tip height (m); friction ratio; angular momentum
about vertical axes (kg m^2/s). Everything in the world frame, stance tip at the origin.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from .model import SWING_TIP, BipedModel, cross


@dataclass(frozen=True)
class StepTrajectory:
    """Samples of one ballistic step: t (s), q (rad), qd (rad/s), qdd (rad/s^2), each row a time."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray


def ground_reaction_inverse_dynamics(bm: BipedModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """[Fx, Fy, Fz, Mz] at the stance tip by RNEA of the extended model with the root at rest.

    The generalized force of the root translation joint is the ground force; the spatial force
    that joint transmits, taken at the tip with world axes, gives the vertical moment.
    """
    model, data = bm.extended, bm.extended_data
    x = bm.extended_state(q)
    xd = np.concatenate([np.zeros(3), qd])
    xdd = np.concatenate([np.zeros(3), qdd])
    tau = pin.rnea(model, data, x, xd, xdd)
    return np.array([tau[0], tau[1], tau[2], data.f[1].angular[2]])


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


def swing_tip_heights(bm: BipedModel, q: np.ndarray) -> np.ndarray:
    """Height z (m) of the swing tip at each configuration (rows of ``q``)."""
    model, data = bm.single, bm.single_data
    frame = model.getFrameId(SWING_TIP)
    out = np.empty(len(q))
    for i, qi in enumerate(q):
        pin.forwardKinematics(model, data, qi)
        out[i] = pin.updateFramePlacement(model, data, frame).translation[2]
    return out


def vertical_momentum_over_step(bm: BipedModel, traj: StepTrajectory) -> np.ndarray:
    """Angular momentum (kg m^2/s) about the vertical through the stance tip, at each sample."""
    origin = np.zeros(3)
    return np.array(
        [bm.vertical_momentum_about(q, np.concatenate([np.zeros(3), qd]), origin) for q, qd in zip(traj.q, traj.qd)]
    )


def energy(bm: BipedModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Total mechanical energy (J) at each row of (q, qd): kinetic plus gravitational potential,
    zero height at the stance tip."""
    model, data = bm.single, bm.single_data
    return np.array(
        [pin.computeKineticEnergy(model, data, a, b) + pin.computePotentialEnergy(model, data, a) for a, b in zip(q, qd)]
    )


def energy_drift(bm: BipedModel, q: np.ndarray, qd: np.ndarray) -> float:
    """max |E / E(first row) - 1| over the rows of (q, qd): how far a ballistic integration is
    from conserving energy (dimensionless)."""
    e = energy(bm, q, qd)
    return float(np.max(np.abs(e / e[0] - 1)))


@dataclass(frozen=True)
class StepFigures:
    """The figures of a ballistic step; ``samples``, ``grf`` and ``h_vertical`` are its sampled
    curves (None once dropped, as sweeps do to keep results small)."""

    samples: StepTrajectory | None
    grf: np.ndarray | None  # samples x 4: Fx, Fy, Fz (N), Mz (N m)
    h_vertical: np.ndarray | None  # samples, kg m^2/s, about the vertical through the stance tip
    min_grf_z: float
    min_swing_height: float
    max_friction_ratio: float
    q3_range: tuple[float, float]
    q5_range: tuple[float, float]
    q9_min: float
    energy_drift: float

    def without_samples(self) -> "StepFigures":
        """These figures without the sampled curves."""
        return replace(self, samples=None, grf=None, h_vertical=None)


def step_figures(bm: BipedModel, traj: StepTrajectory, period: float, drift: float) -> StepFigures:
    """Ground reaction, swing clearance on (0.05 T, 0.95 T), friction ratio, joint ranges, and
    the integration's energy ``drift``."""
    grf = np.array([ground_reaction_inverse_dynamics(bm, *row) for row in zip(traj.q, traj.qd, traj.qdd)])
    interior = (traj.t > 0.05 * period) & (traj.t < 0.95 * period)
    heights = swing_tip_heights(bm, traj.q[interior])
    fz = grf[:, 2]
    ratio = np.where(fz > 0, np.hypot(grf[:, 0], grf[:, 1]) / np.where(fz > 0, fz, 1.0), np.inf)
    return StepFigures(
        samples=traj,
        grf=grf,
        h_vertical=vertical_momentum_over_step(bm, traj),
        min_grf_z=float(fz.min()),
        min_swing_height=float(heights.min()),
        max_friction_ratio=float(ratio.max()),
        q3_range=(float(traj.q[:, 2].min()), float(traj.q[:, 2].max())),
        q5_range=(float(traj.q[:, 4].min()), float(traj.q[:, 4].max())),
        q9_min=float(traj.q[:, 8].min()),
        energy_drift=drift,
    )
