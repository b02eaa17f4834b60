"""The ballistic boundary-value problem with exact periodic closure (docs/model.md sections 3-4).

Unknowns: qd(0) (nq) and, in the ``theta`` closure, the trunk pitch theta at double support.
Equations: q(T; q0(theta), qd(0)) = q_T(theta) (nq) and, in the ``theta`` closure, the
conservation of the angular momentum about the foot-to-foot line through the double support,
z_d^T D_e(q_T) (Xd^a - Xd^b) = 0 (1), from the hybrid step's impact map. Solved by the
project's Newton/chord solver (``newton``) with the exact Jacobian of the computed flow map
(variational equations).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..dynamics import newton
from .configurations import GaitMode, boundary_configurations
from ..dynamics.flow import BallisticFlow, FlowResult
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings

CLOSURES = ("theta", "slack")
# How the solver's outcomes read in a gait's message.
_MESSAGES = {newton.DIVERGED: "the integration diverged (non-finite state)", newton.SINGULAR: "singular shooting Jacobian"}


@dataclass(frozen=True, eq=False)
class BvpSolution:
    """Result of the shooting (the gait's ballistic step): always returned, ``converged`` says
    whether to trust it. Angles rad, velocities rad/s, ``closure_gap`` kg m^2/s."""

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
    coarse: "BvpSolution | None" = None  # the same step on the coarse grid, when asked for (``solve_bvp``)


@dataclass(frozen=True)
class StepProblem:
    """What the shooting of one ballistic step solves: L (m), T (s), alpha (rad), the mode, the
    closure (``theta``: the trunk pitch theta free and the momentum about the feet line closed;
    ``slack``: theta = 0), the step width (m between the feet; None: the hips' spacing), and the
    closure gap the solve makes (``closure_target``, kg m^2/s: 0, the momentum about the feet
    line conserved; with the feet's spin axes tilted, minus what the ground's spin moments change
    of it, ``ImpulseSolution.foot_line_moment``)."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode
    closure: str = "theta"
    step_width: float | None = None
    closure_target: float = 0.0


class ShootingResidual:
    """The residual F(u) of the shooting problem ``problem``, u = [qd(0), theta], and its exact
    Jacobian."""

    def __init__(self, hybrid: HybridStep, problem: StepProblem):
        self.hybrid, self.period = hybrid, problem.period
        self.closure_target = problem.closure_target  # kg m^2/s: what the closure gap must be
        self.configurations = boundary_configurations(hybrid.bm)
        self.n = hybrid.bm.nq
        self.step_length, self.alpha, self.mode = problem.step_length, problem.arm_amplitude, problem.mode
        self.step_width = problem.step_width
        self.evaluations = 0

    def ends(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        """q(0) and q(T) at trunk pitch ``theta`` (rad)."""
        return self.configurations(self.step_length, self.alpha, self.mode, theta, self.step_width)

    def __call__(self, flow: BallisticFlow, u: np.ndarray, with_theta: bool, jacobian: bool,
                 keep_nodes: bool = False) -> tuple[np.ndarray, np.ndarray | None, FlowResult]:
        """F (nq or nq + 1), dF/du when ``jacobian`` (else None), and the flow's result."""
        n = self.n
        n_unknown = n + 1 if with_theta else n
        theta = u[n]
        q0, q_t = self.ends(theta)
        seeds = None
        if jacobian:
            seeds = np.zeros((2 * n, n_unknown))
            seeds[n:, :n] = np.eye(n)
            if with_theta:
                d0, d_t = self.configurations.theta_derivatives(self.step_length, self.alpha, self.mode, theta,
                                                                self.step_width)
                seeds[:n, n] = d0
        with np.errstate(over="ignore", invalid="ignore"):  # divergence is detected and reported
            res = flow.propagate(q0, u[:n], self.period, seeds, keep_nodes)
        self.evaluations += res.evaluations
        f = res.q - q_t
        impact = self.hybrid.impact(q_t) if with_theta else None
        if with_theta:
            f = np.append(f, impact.closure_gap(u[:n], res.qd) - self.closure_target)
        if not jacobian:
            return f, None, res
        jac = np.zeros((n_unknown, n_unknown))
        jac[:n] = res.sens[:n]
        if with_theta:
            jac[:n, n] -= d_t
            d_a, d_b = impact.closure_gradients()
            jac[n, :n] = d_a + d_b @ res.sens[n:, :n]
            # The gap's explicit dependence on theta through the configuration q_T(theta) is a
            # smooth algebraic function: a central difference resolves it to ~1e-10 relative.
            h = 1e-6
            gap = lambda th: self.hybrid.impact(self.ends(th)[1]).closure_gap(u[:n], res.qd)  # noqa: E731
            jac[n, n] = (gap(theta + h) - gap(theta - h)) / (2 * h) + d_b @ res.sens[n:, n]
        return f, jac, res

    def newton_residual(self, flow: BallisticFlow, u: np.ndarray, with_theta: bool) -> newton.NewtonResidual:
        """F as the Newton solver takes it, over the free unknowns (qd(0), and theta if free);
        a fixed theta is ``u[nq]``."""
        n = self.n + 1 if with_theta else self.n

        def fun(x: np.ndarray, jacobian: bool):
            full = u.copy()
            full[:n] = x
            return self(flow, full, with_theta, jacobian)

        return fun


def solve_bvp(
    hybrid: HybridStep,
    flow: BallisticFlow,
    problem: StepProblem,
    guess: tuple[np.ndarray, float] | None = None,
    settings: Settings = DEFAULTS,
    coarse: BallisticFlow | None = None,
    with_coarse: bool = False,
) -> BvpSolution:
    """Solve the shooting of ``problem`` on ``flow``'s grid; ``guess`` = (qd(0), theta)
    warm-starts it.

    Without a guess, Newton starts from the straight-line velocity (q_T - q_0) / T with
    theta = 0 held fixed, which leads to the human-like branch (swing knee flexion q9 >= 0);
    the ``theta`` closure then frees theta from there (started cold with theta free, Newton
    may reach the twin solution with the swing knee bent backwards).

    With a ``coarse`` flow, Newton's iterations run on the coarse grid and the solution is
    finished on ``flow``'s grid by chord steps with the coarse Jacobian, which the two grids
    share to within the coarse grid's error; if that stalls, Newton continues on the fine grid.
    ``settings.tolerance`` bounds the end-point residual (rad) and the closure gap's distance to
    ``problem.closure_target`` (kg m^2/s). ``with_coarse``: the coarse grid's own solution too,
    converged to ``settings.tolerance`` (or to rounding, below ``settings.coarse_tolerance``) by
    chord steps with Newton's last Jacobian (one coarse flow, as a rule), as
    ``BvpSolution.coarse``: what a plan's integration error is estimated against
    (``richardson``); None where that does not converge, or without a ``coarse`` flow.
    """
    if problem.closure not in CLOSURES:
        raise ValueError(f"unknown closure {problem.closure!r}: use 'theta' or 'slack'")
    with_theta = problem.closure == "theta"
    system = ShootingResidual(hybrid, problem)
    nq = system.n
    n = nq + 1 if with_theta else nq
    tol, max_iter = settings.tolerance, settings.max_iterations
    newton_flow = coarse or flow
    # On the coarse grid, converging further than its own discretization error gains nothing.
    newton_tol = max(tol, settings.coarse_tolerance) if coarse is not None else tol

    def run_newton(u: np.ndarray, free_theta: bool, on: BallisticFlow, bound: float):
        k = nq + 1 if free_theta else nq
        result = newton.newton(system.newton_residual(on, u, free_theta), u[:k], bound, max_iter)
        u = u.copy()
        u[:k] = result.x
        return u, result

    iterations = 0
    if guess is None:
        q0, q_t = system.ends(0.0)
        u = np.concatenate([(q_t - q0) / problem.period, [0.0]])
        if with_theta:
            u, result = run_newton(u, False, newton_flow, newton_tol)
            iterations += result.iterations
            if not result.converged:
                return _solution(system, flow, u, with_theta, False, f"{_message(result)} (theta = 0 stage)", iterations)
    else:
        u = np.concatenate([np.asarray(guess[0], float), [guess[1] if with_theta else 0.0]])
    u, result = run_newton(u, with_theta, newton_flow, newton_tol)
    iterations += result.iterations
    if not result.converged or coarse is None:
        return _solution(system, flow, u, with_theta, result.converged, _message(result), iterations)

    def chord_residual(on: BallisticFlow):
        def residual(x: np.ndarray):
            full = u.copy()
            full[:n] = x
            f, _, res = system(on, full, with_theta, False, keep_nodes=True)
            return f, res

        return residual

    on_coarse = None
    if with_coarse:
        settled = newton.chord(chord_residual(coarse), u[:n], result.jacobian, tol, settings.chord_iterations,
                               contraction=0.1, start=(result.residual, result.aux))
        # A chord step that stalls stops at rounding (about 5e-12 with the 13-DOF legs, above the
        # 1e-12 asked): below the coarse tolerance, that is still the coarse grid's own solution to
        # far better than the grids' difference the estimate reads from it.
        if settled.converged or (settled.status == newton.STALLED and settled.norm < newton_tol):
            on_coarse = _solution(system, coarse, np.concatenate([settled.x, u[n:]]), with_theta, True,
                                  newton.CONVERGED, iterations + settled.iterations, settled.aux)
    # Chord steps on the fine grid with the coarse Jacobian: linear convergence at the rate of
    # the grids' Jacobian mismatch (about the coarse grid's relative error).
    finish = newton.chord(chord_residual(flow), u[:n], result.jacobian, tol, settings.chord_iterations, contraction=0.1)
    u[:n] = finish.x
    iterations += finish.iterations
    if finish.converged:
        return replace(_solution(system, flow, u, with_theta, True, newton.CONVERGED, iterations, finish.aux),
                       coarse=on_coarse)
    u, result = run_newton(u, with_theta, flow, tol)
    return replace(_solution(system, flow, u, with_theta, result.converged, _message(result),
                             iterations + result.iterations), coarse=on_coarse)


def _message(result: newton.SolveResult) -> str:
    return _MESSAGES.get(result.status, result.message)


def _solution(system: ShootingResidual, flow: BallisticFlow, u: np.ndarray, with_theta: bool, ok: bool, message: str,
              iterations: int, res: FlowResult | None = None) -> BvpSolution:
    """Package the outcome; ``res`` is the fine-grid flow at ``u`` if already computed."""
    if res is None or res.nodes is None:
        _, _, res = system(flow, u, with_theta, False, keep_nodes=True)
    n = system.n
    theta = float(u[n]) if with_theta else 0.0
    q0, q_t = system.ends(theta)
    finite = np.all(np.isfinite(res.q)) and np.all(np.isfinite(res.qd))
    return BvpSolution(
        converged=ok,
        message=message,
        iterations=iterations,
        theta=theta,
        q0=q0,
        q_target=q_t,
        qd_a=u[:n].copy(),
        qd_b=res.qd.copy(),
        end_residual=float(np.max(np.abs(res.q - q_t))) if finite else math.inf,
        closure_gap=system.hybrid.impact(q_t).closure_gap(u[:n], res.qd) if finite else math.inf,
        evaluations=system.evaluations,
        nodes=res.nodes,
    )
