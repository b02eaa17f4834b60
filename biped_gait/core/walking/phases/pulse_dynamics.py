"""A torque pulse and its correction (docs/model.md sections 10, 11): the single support driven
by constant joint torques for a short time, its stance tip's reaction, the friction cone's rows on
a force, and the Gauss-Newton that corrects the pulses of the MuJoCo walk's double support
(``pulses``) so that they reach the re-aimed next step within the cone.

Units SI, rad; forces N, impulses N s.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from scipy.linalg import null_space
from scipy.optimize import linprog

from ...dynamics.hybrid import HybridStep
from ...dynamics.impulses import pyramid

PULSE_STEPS = 16  # RK4 steps per half pulse
FD_STEP = 1e-7  # the differences of the correction's Jacobian


class CorrectionFailed(Exception):
    """The pulses have no correction: the message says why."""


def ground_reaction(hybrid: HybridStep, q: np.ndarray, qd: np.ndarray, torque: np.ndarray) -> np.ndarray:
    """[Fx, Fy, Fz] (N, world axes of the step's model) at the stance tip, the joints driven by
    ``torque`` (nq, zero on the ankle): the extended model's inverse dynamics with the tip held."""
    bm = hybrid.bm
    return _stance_reaction(bm, q, qd, pin.aba(bm.single, bm.single_data, q, qd, torque))


def _stance_reaction(bm, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """[Fx, Fy, Fz] (N) at the stance tip of the single support's motion (q, qd, qdd)."""
    x, xd, xdd = bm.extended_state(q), np.concatenate([np.zeros(3), qd]), np.concatenate([np.zeros(3), qdd])
    return pin.rnea(bm.extended, bm.extended_data, x, xd, xdd)[:3].copy()


class PinnedTip:
    """The single support driven by joint torques, the stance tip pinned (the paper's model with
    torques, ``bm``): what the walk's tracking (``tracking``, ``balance.linearization``) and the
    engine's held motions (``engines.engine.Held``) need of what holds the tips. No held rows: its
    minimal coordinates are q. Not thread-safe (the model's Pinocchio data)."""

    def __init__(self, bm) -> None:
        self.bm = bm
        self.actuated = np.asarray(bm.actuated)

    def rows_of(self, q: np.ndarray) -> np.ndarray:
        """No rows held beyond the tree's root."""
        return np.zeros((0, self.bm.nq))

    def forward(self, q: np.ndarray, qd: np.ndarray, torque: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """qdd (rad/s^2) and the stance tip's reaction [Fx, Fy, Fz] (N, world axes of the step's
        model) under the actuated joints' ``torque`` (N m)."""
        bm = self.bm
        full = np.zeros(bm.nq)
        full[self.actuated] = torque
        qdd = pin.aba(bm.single, bm.single_data, q, qd, full)
        return qdd, _stance_reaction(bm, q, qd, qdd)


def pulse(hybrid: HybridStep, q: np.ndarray, qd: np.ndarray, torque: np.ndarray, duration: float,
          steps: int = PULSE_STEPS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The single support driven by constant joint torques ``torque`` (nq: zero on the passive
    ankle, N m) for ``duration`` (s), RK4 in ``steps`` steps: the end (q, qd) and the ground
    reaction at the steps' nodes (steps + 1 rows of [Fx, Fy, Fz], N)."""
    bm = hybrid.bm
    model, data = bm.single, bm.single_data
    h = duration / steps

    def f(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return pin.aba(model, data, a, b, torque)

    forces = [ground_reaction(hybrid, q, qd, torque)]
    for _ in range(steps):
        k1v, k1a = qd, f(q, qd)
        k2v, k2a = qd + h / 2 * k1a, f(q + h / 2 * k1v, qd + h / 2 * k1a)
        k3v, k3a = qd + h / 2 * k2a, f(q + h / 2 * k2v, qd + h / 2 * k2a)
        k4v, k4a = qd + h * k3a, f(q + h * k3v, qd + h * k3a)
        q = q + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        qd = qd + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
        forces.append(ground_reaction(hybrid, q, qd, torque))
    return q, qd, np.array(forces)


def cone_rows(force: np.ndarray, friction: float) -> np.ndarray:
    """-Fz (the normal force positive) and the rows of the friction cone's inscribed pyramid
    (``impulses.pyramid``) on ``force`` (N or N s; [Fx, Fy, Fz], or rows of them): values <= 0
    inside. One row of values per force."""
    force = np.asarray(force, dtype=float)
    return np.concatenate([-force[..., 2:3], force[..., :3] @ pyramid(friction).T], axis=-1)


def friction_ratio(forces: np.ndarray) -> float:
    """The largest |F_xy| / F_z of the rows of ``forces`` (inf where F_z <= 0)."""
    fz = forces[:, 2]
    horizontal = np.hypot(forces[:, 0], forces[:, 1])
    return float(np.max(np.where(fz > 0, horizontal / np.where(fz > 0, fz, 1.0), np.inf)))


SLACK = 1e-6  # N s, m/s: how far Gauss-Newton's result may violate a constraint (second-order effects)
MARGIN = 1e-7  # N s, m/s: Gauss-Newton's steps meet the linearized constraints with this margin
VIOLATION_COST = 1e3  # per N s (m/s) of a linearized constraint violated, against the step's scaled l1 norm
GAUSS_NEWTON_STEPS = 30
HALVINGS = 12  # of a Gauss-Newton step at most, until the merit falls


def gauss_newton(evaluate, jacobian, z: np.ndarray, scale, tolerance: float,
                 fresh: bool = True) -> tuple[np.ndarray, int]:
    """z meeting the equations of ``evaluate`` (z -> residual, constraints <= 0, anything) to
    ``tolerance`` and its constraints to ``SLACK``, from ``z``, and the steps taken. Each step is
    the least (in the units ``scale(z)`` gives, one per unknown) that meets the linearized equations, moved
    in their null space by the least (l1) that meets the linearized constraints (with ``MARGIN``;
    their violations paid at ``VIOLATION_COST``: a linear program), halved until the merit
    sum |residual| + sum max(constraint - SLACK, 0) falls. ``jacobian(z, residual, constraints,
    fresh)``: d(residual, constraints) / dz, ``fresh`` asking for all of it anew (else it may reuse
    what does not change much); asked fresh again when a step cannot lower the merit.
    ``CorrectionFailed`` if no step can, or after ``GAUSS_NEWTON_STEPS``."""
    residual, constraints, _ = evaluate(z)

    def merit(r: np.ndarray, c: np.ndarray) -> float:
        return float(np.abs(r).sum() + np.maximum(c - SLACK, 0.0).sum()) if np.all(np.isfinite(r)) else math.inf

    jac, steps = None, 0
    while True:
        if np.max(np.abs(residual)) < tolerance and np.max(constraints) <= SLACK:
            return z, steps
        if steps == GAUSS_NEWTON_STEPS:
            break
        if jac is None:
            with np.errstate(all="ignore"):
                jac = jacobian(z, residual, constraints, fresh)
            if not np.all(np.isfinite(jac)):
                raise CorrectionFailed(f"Gauss-Newton's Jacobian is not finite at residual "
                                          f"{np.max(np.abs(residual)):.2e}")
        units = scale(z)
        scaled = jac * units
        j_eq, j_in = scaled[:len(residual)], scaled[len(residual):]
        y = np.linalg.lstsq(j_eq, -residual, rcond=None)[0]
        free = null_space(j_eq)
        y = y + free @ _least_move(j_in @ free, -constraints - j_in @ y - MARGIN)
        step, now = units * y, merit(residual, constraints)
        for _ in range(HALVINGS):
            with np.errstate(all="ignore"):
                trial = evaluate(z + step)
            if merit(trial[0], trial[1]) < now:
                break
            step = step / 2
        else:
            if fresh:
                break
            jac, fresh = None, True
            continue
        z, (residual, constraints, _) = z + step, trial
        steps, fresh, jac = steps + 1, False, None
    raise CorrectionFailed(f"Gauss-Newton stalls at residual {np.max(np.abs(residual)):.2e}, "
                              f"constraint {np.max(constraints):.2e}")


def _least_move(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The w of least l1 norm with a w <= b, its violations paid at ``VIOLATION_COST`` (HiGHS;
    w = 0 when it meets them)."""
    m, k = a.shape
    if np.all(b >= 0.0):
        return np.zeros(k)
    cost = np.concatenate([np.ones(2 * k), np.full(m, VIOLATION_COST)])
    lp = linprog(cost, A_ub=np.hstack([a, -a, -np.eye(m)]), b_ub=b, bounds=(0, None), method="highs")
    if lp.status != 0:
        raise CorrectionFailed(f"the linearized constraints have no least move ({lp.message})")
    return lp.x[:k] - lp.x[k:2 * k]
