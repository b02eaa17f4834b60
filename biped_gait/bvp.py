"""The ballistic boundary-value problem with exact periodic closure (spec sections 3-4).

Unknowns: qd(0) (9) and, in the ``theta`` closure, the trunk pitch theta at double support.
Equations: q(T; q0(theta), qd(0)) = q_T(theta) (9) and, in the ``theta`` closure, the
conservation of the angular momentum about the foot-to-foot line through the double support,
z_d^T D_e(q_T) (Xd^a - Xd^b) = 0 (1). Newton's method with the exact Jacobian of the computed
flow map (variational equations), a backtracking line search, and bounded iterations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .boundary import P_INVERSE, THETA_DIRECTION, GaitMode, boundary_configurations
from .flow import BallisticFlow
from .model import BipedModel

CLOSURES = ("theta", "slack")


@dataclass
class BvpSolution:
    """Result of the shooting: always returned, ``converged`` says whether to trust it."""

    converged: bool
    message: str
    iterations: int
    theta: float
    q0: np.ndarray
    q_target: np.ndarray
    qd_a: np.ndarray
    qd_b: np.ndarray
    end_residual: float
    closure_gap: float
    evaluations: int


def locked_rotation(bm: BipedModel, q_t: np.ndarray) -> np.ndarray:
    """z_d (12,): unit-rate rigid rotation of the locked biped about the foot-to-foot line.

    Only q1d and q2d are non-zero; the rotation axis points from the old stance tip (origin)
    to the new one. Requires q1 = 0, as every double-support configuration has.
    """
    tip = bm.swing_tip(q_t)
    axis = tip / np.linalg.norm(tip)
    z = np.zeros(12)
    z[3], z[4] = axis[0], axis[1]
    return z


def next_step_velocity(bm: BipedModel, q_t: np.ndarray, qd_a: np.ndarray) -> np.ndarray:
    """Xd^a: the next step's initial velocity in this step's extended coordinates (spec 5)."""
    qd = P_INVERSE @ qd_a
    _, j2 = bm.tip_jacobians(q_t)
    return np.concatenate([-j2[:, 3:] @ qd, qd])


def closure_gap(bm: BipedModel, q_t: np.ndarray, qd_a: np.ndarray, qd_b: np.ndarray) -> float:
    """z_d^T D_e (Xd^a - Xd^b) (kg m^2/s): zero when the double support can close the cycle."""
    z = locked_rotation(bm, q_t)
    xd_b = np.concatenate([np.zeros(3), qd_b])
    return float(z @ bm.mass_matrix(q_t) @ (next_step_velocity(bm, q_t, qd_a) - xd_b))


def _closure_gradients(bm: BipedModel, q_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d gap / d qd_a and d gap / d qd_b at fixed configuration (the gap is linear in both)."""
    row = locked_rotation(bm, q_t) @ bm.mass_matrix(q_t)
    _, j2 = bm.tip_jacobians(q_t)
    d_a = (row[3:] - row[:3] @ j2[:, 3:]) @ P_INVERSE
    return d_a, -row[3:]


def solve_bvp(
    bm: BipedModel,
    flow: BallisticFlow,
    step_length: float,
    period: float,
    arm_amplitude: float,
    mode: GaitMode,
    closure: str = "theta",
    guess: tuple[np.ndarray, float] | None = None,
    tol: float = 1e-12,
    max_iter: int = 30,
) -> BvpSolution:
    """Solve the shooting problem; ``guess`` = (qd(0), theta) warm-starts it.

    Without a guess, Newton starts from the straight-line velocity (q_T - q_0) / T and
    theta = 0, which leads to the human-like branch (swing knee flexion q9 >= 0).
    ``tol`` bounds the end-point residual (rad) and the closure gap (kg m^2/s).
    """
    if closure not in CLOSURES:
        raise ValueError(f"unknown closure {closure!r}: use 'theta' or 'slack'")
    leg = bm.params.leg_length
    with_theta = closure == "theta"

    def ends(theta: float) -> tuple[np.ndarray, np.ndarray]:
        return boundary_configurations(step_length, leg, arm_amplitude, mode, theta)

    if guess is None:
        q0, q_t = ends(0.0)
        u = np.concatenate([(q_t - q0) / period, [0.0]])
    else:
        u = np.concatenate([np.asarray(guess[0], float), [guess[1] if with_theta else 0.0]])
    n_unknown = 10 if with_theta else 9
    seeds = np.zeros((18, n_unknown))
    seeds[9:, :9] = np.eye(9)
    if with_theta:
        seeds[:9, 9] = THETA_DIRECTION
    evaluations = 0

    def residual(u: np.ndarray, jacobian: bool):
        nonlocal evaluations
        theta = u[9]
        q0, q_t = ends(theta)
        res = flow.propagate(q0, u[:9], period, seeds if jacobian else None)
        evaluations += res.evaluations
        f = res.q - q_t
        if with_theta:
            f = np.append(f, closure_gap(bm, q_t, u[:9], res.qd))
        if not jacobian:
            return f, res, None
        jac = np.zeros((n_unknown, n_unknown))
        jac[:9] = res.sens[:9]
        if with_theta:
            jac[:9, 9] -= THETA_DIRECTION
            d_a, d_b = _closure_gradients(bm, q_t)
            jac[9, :9] = d_a + d_b @ res.sens[9:, :9]
            # The gap's explicit dependence on theta through the configuration q_T(theta) is a
            # smooth algebraic function: a central difference resolves it to ~1e-10 relative.
            h = 1e-6
            explicit = (
                closure_gap(bm, ends(theta + h)[1], u[:9], res.qd) - closure_gap(bm, ends(theta - h)[1], u[:9], res.qd)
            ) / (2 * h)
            jac[9, 9] = explicit + d_b @ res.sens[9:, 9]
        return f, res, jac

    message = f"no convergence in {max_iter} Newton iterations"
    converged = False
    f, res, jac = residual(u, True)
    norm = float(np.max(np.abs(f)))
    iterations = 0
    while True:
        if not math.isfinite(norm):
            message = "the integration diverged (non-finite state)"
            break
        if norm < tol:
            converged, message = True, "converged"
            break
        if iterations == max_iter:
            break
        iterations += 1
        try:
            step = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            message = "singular shooting Jacobian"
            break
        # Backtracking on the max-norm of the residual; the full step carries its Jacobian.
        lam = 1.0
        while True:
            trial = u.copy()
            trial[:n_unknown] += lam * step
            f_new, res_new, jac_new = residual(trial, lam == 1.0)
            new_norm = float(np.max(np.abs(f_new))) if np.all(np.isfinite(f_new)) else math.inf
            if new_norm < (1 - 1e-4 * lam) * norm or lam < 1e-3:
                break
            lam *= 0.5
        u, f, res, norm = trial, f_new, res_new, new_norm
        if math.isfinite(norm) and norm >= tol:
            jac = jac_new if jac_new is not None else residual(u, True)[2]
    theta = float(u[9]) if with_theta else 0.0
    q0, q_t = ends(theta)
    return BvpSolution(
        converged=converged,
        message=message,
        iterations=iterations,
        theta=theta,
        q0=q0,
        q_target=q_t,
        qd_a=u[:9].copy(),
        qd_b=res.qd.copy(),
        end_residual=float(np.max(np.abs(res.q - q_t))),
        closure_gap=closure_gap(bm, q_t, u[:9], res.qd),
        evaluations=evaluations,
    )
