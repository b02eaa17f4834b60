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
from .impulses import ImpactProblem
from .model import BipedModel

CLOSURES = ("theta", "slack")
COARSE_TOL = 1e-9  # rad and kg m^2/s: where Newton on the coarse grid hands over to the fine grid


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
    nodes: tuple | None = None  # fine-grid nodes (t, q, qd, qdd) of the returned trajectory


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


def impact_problem(bm: BipedModel, q_t: np.ndarray, qd_b: np.ndarray, qd_a: np.ndarray) -> ImpactProblem:
    """Eqs. (6)-(10) at double-support configuration ``q_t``: this step ends with joint
    velocity ``qd_b``, the next starts with ``qd_a`` (in its own coordinates, spec section 5)."""
    j1, j2 = bm.tip_jacobians(q_t)
    xd_b = np.concatenate([np.zeros(3), qd_b])
    return ImpactProblem(bm.mass_matrix(q_t), j1, j2, xd_b, next_step_velocity(bm, q_t, qd_a), locked_rotation(bm, q_t))


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


class _Shooting:
    """The residual F(u) of the shooting problem, u = [qd(0), theta], and its exact Jacobian."""

    def __init__(self, bm: BipedModel, step_length: float, period: float, alpha: float, mode: GaitMode):
        self.bm, self.period = bm, period
        self.ends = lambda theta: boundary_configurations(step_length, bm.params.leg_length, alpha, mode, theta)
        self.evaluations = 0

    def __call__(self, flow: BallisticFlow, u: np.ndarray, with_theta: bool, jacobian: bool, keep_nodes: bool = False):
        """F (9 or 10), the flow's result, and dF/du when ``jacobian`` (else None)."""
        n_unknown = 10 if with_theta else 9
        theta = u[9]
        q0, q_t = self.ends(theta)
        seeds = None
        if jacobian:
            seeds = np.zeros((18, n_unknown))
            seeds[9:, :9] = np.eye(9)
            if with_theta:
                seeds[:9, 9] = THETA_DIRECTION
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is detected and reported
            res = flow.propagate(q0, u[:9], self.period, seeds, keep_nodes)
        self.evaluations += res.evaluations
        f = res.q - q_t
        if with_theta:
            f = np.append(f, closure_gap(self.bm, q_t, u[:9], res.qd))
        if not jacobian:
            return f, res, None
        jac = np.zeros((n_unknown, n_unknown))
        jac[:9] = res.sens[:9]
        if with_theta:
            jac[:9, 9] -= THETA_DIRECTION
            d_a, d_b = _closure_gradients(self.bm, q_t)
            jac[9, :9] = d_a + d_b @ res.sens[9:, :9]
            # The gap's explicit dependence on theta through the configuration q_T(theta) is a
            # smooth algebraic function: a central difference resolves it to ~1e-10 relative.
            h = 1e-6
            gap = lambda th: closure_gap(self.bm, self.ends(th)[1], u[:9], res.qd)  # noqa: E731
            jac[9, 9] = (gap(theta + h) - gap(theta - h)) / (2 * h) + d_b @ res.sens[9:, 9]
        return f, res, jac


def _max_norm(f: np.ndarray) -> float:
    return float(np.max(np.abs(f))) if np.all(np.isfinite(f)) else math.inf


def _newton(system: _Shooting, flow: BallisticFlow, u: np.ndarray, with_theta: bool, tol: float, max_iter: int):
    """Damped Newton with the exact Jacobian: (u, converged, message, iterations, last jacobian)."""
    n = 10 if with_theta else 9
    f, _, jac = system(flow, u, with_theta, True)
    norm = _max_norm(f)
    for iteration in range(max_iter + 1):
        if not math.isfinite(norm):
            return u, False, "the integration diverged (non-finite state)", iteration, jac
        if norm < tol:
            return u, True, "converged", iteration, jac
        if iteration == max_iter:
            break
        try:
            step = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            return u, False, "singular shooting Jacobian", iteration, jac
        # Backtracking on the max-norm of the residual. The full step carries its Jacobian
        # unless quadratic convergence predicts it is the last one (residual ~ 10 norm^2).
        lam = 1.0
        last_expected = 10.0 * norm * norm < tol
        while True:
            trial = u.copy()
            trial[:n] += lam * step
            f_new, _, jac_new = system(flow, trial, with_theta, lam == 1.0 and not last_expected)
            new_norm = _max_norm(f_new)
            if new_norm < (1 - 1e-4 * lam) * norm or lam < 1e-3:
                break
            lam *= 0.5
        u, f, norm = trial, f_new, new_norm
        if math.isfinite(norm) and norm >= tol:
            jac = jac_new if jac_new is not None else system(flow, u, with_theta, True)[2]
    return u, False, f"no convergence in {max_iter} Newton iterations", max_iter, jac


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
    coarse: BallisticFlow | None = None,
) -> BvpSolution:
    """Solve the shooting problem on ``flow``'s grid; ``guess`` = (qd(0), theta) warm-starts it.

    Without a guess, Newton starts from the straight-line velocity (q_T - q_0) / T with
    theta = 0 held fixed, which leads to the human-like branch (swing knee flexion q9 >= 0);
    the ``theta`` closure then frees theta from there (started cold with theta free, Newton
    may reach the twin solution with the swing knee bent backwards).

    With a ``coarse`` flow, Newton's iterations run on the coarse grid and the solution is
    finished on ``flow``'s grid by chord steps with the coarse Jacobian, which the two grids
    share to within the coarse grid's error; if that stalls, Newton continues on the fine grid.
    ``tol`` bounds the end-point residual (rad) and the closure gap (kg m^2/s).
    """
    if closure not in CLOSURES:
        raise ValueError(f"unknown closure {closure!r}: use 'theta' or 'slack'")
    with_theta = closure == "theta"
    n = 10 if with_theta else 9
    system = _Shooting(bm, step_length, period, arm_amplitude, mode)
    newton_flow = coarse or flow
    # On the coarse grid, converging further than its own discretization error gains nothing.
    newton_tol = max(tol, COARSE_TOL) if coarse is not None else tol
    iterations = 0
    if guess is None:
        q0, q_t = system.ends(0.0)
        u = np.concatenate([(q_t - q0) / period, [0.0]])
        if with_theta:
            u, ok, message, its, _ = _newton(system, newton_flow, u, False, newton_tol, max_iter)
            iterations += its
            if not ok:
                return _solution(system, flow, u, with_theta, False, f"{message} (theta = 0 stage)", iterations)
    else:
        u = np.concatenate([np.asarray(guess[0], float), [guess[1] if with_theta else 0.0]])
    u, ok, message, its, jac = _newton(system, newton_flow, u, with_theta, newton_tol, max_iter)
    iterations += its
    if not ok or coarse is None:
        return _solution(system, flow, u, with_theta, ok, message, iterations)
    # Chord steps on the fine grid with the coarse Jacobian: linear convergence at the rate of
    # the grids' Jacobian mismatch (about the coarse grid's relative error).
    f, res, _ = system(flow, u, with_theta, False, keep_nodes=True)
    norm = _max_norm(f)
    for _ in range(6):
        if norm < tol:
            return _solution(system, flow, u, with_theta, True, "converged", iterations, res)
        trial = u.copy()
        trial[:n] -= np.linalg.solve(jac, f)
        f_new, res_new, _ = system(flow, trial, with_theta, False, keep_nodes=True)
        new_norm = _max_norm(f_new)
        if not new_norm < 0.1 * norm:
            break
        u, f, res, norm = trial, f_new, res_new, new_norm
        iterations += 1
    u, ok, message, its, _ = _newton(system, flow, u, with_theta, tol, max_iter)
    return _solution(system, flow, u, with_theta, ok, message, iterations + its)


def _solution(system: _Shooting, flow: BallisticFlow, u: np.ndarray, with_theta: bool, ok: bool, message: str,
              iterations: int, res=None) -> BvpSolution:
    """Package the outcome; ``res`` is the fine-grid flow at ``u`` if already computed."""
    if res is None or res.nodes is None:
        _, res, _ = system(flow, u, with_theta, False, keep_nodes=True)
    theta = float(u[9]) if with_theta else 0.0
    q0, q_t = system.ends(theta)
    finite = np.all(np.isfinite(res.q)) and np.all(np.isfinite(res.qd))
    return BvpSolution(
        converged=ok,
        message=message,
        iterations=iterations,
        theta=theta,
        q0=q0,
        q_target=q_t,
        qd_a=u[:9].copy(),
        qd_b=res.qd.copy(),
        end_residual=float(np.max(np.abs(res.q - q_t))) if finite else math.inf,
        closure_gap=closure_gap(system.bm, q_t, u[:9], res.qd) if finite else math.inf,
        evaluations=system.evaluations,
        nodes=res.nodes,
    )
