"""The shooting boundary-value problem of a stride on a circle (docs/model.md section 4.9): two
steps, right foot then left foot, periodic modulo a yaw rotation of 2 L / R.

In its own (mirrored) model coordinates the left step turns the other way: step A, on the right
foot, ends at the double support C1 of radius R; step B, on the left foot, ends at C2 of radius
-R (``turning.TurningConfiguration``). Each starts where the other ends, through the leg
exchange: q_A(0) = P(C2), q_B(0) = P(C1). Unknowns: the initial velocities qd_A(0), qd_B(0)
(nq each) and the trunk pitches theta_1, theta_2 of C1 and C2. Equations: each step reaches its
touchdown configuration (nq each), and at each double support the momentum about the feet line is
conserved from the step that ends to the step that starts (the closure of docs/model.md section
4.5, twice). Solved by the project's Newton/chord solver with the flows' exact sensitivities, on
the coarse grid then finished on the fine one; the configurations' theta dependence by central
differences. Units: rad, rad/s, s, m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics import newton
from ..dynamics.flow import BallisticFlow, FlowResult
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings
from .bvp import BvpSolution
from .configurations import GaitMode
from .turning import TurningConfiguration

FD_STEP = 1e-6  # rad: the configurations' theta derivatives


@dataclass(frozen=True, eq=False)
class StrideSolution:
    """The two steps of a stride (A on the right foot, B on the left, each in its own model
    coordinates) as ballistic-step solutions, and the outcome of their joint solve."""

    converged: bool
    message: str
    iterations: int
    steps: tuple[BvpSolution, BvpSolution]


@dataclass(frozen=True)
class StrideProblem:
    """What the shooting of a stride solves: L (m), T (s), alpha (rad), the mode and the turn
    radius R (m, signed: positive turns left)."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode
    radius: float


class StrideResidual:
    """The residual F(u) of the shooting of the stride ``problem``, u = [qd_A(0), theta_1,
    qd_B(0), theta_2], and its Jacobian, its closure gaps made ``closure_targets``."""

    def __init__(self, hybrid: HybridStep, problem: StrideProblem, closure_targets: tuple[float, float] = (0.0, 0.0)):
        self.hybrid, self.period, self.radius = hybrid, problem.period, problem.radius
        self.closure_targets = closure_targets  # kg m^2/s at C1 and C2 (``bvp.StepProblem``'s closure_target)
        self.turning = TurningConfiguration(hybrid.bm)
        self.n = hybrid.bm.nq
        self.step_length, self.alpha, self.mode = problem.step_length, problem.arm_amplitude, problem.mode
        self.evaluations = 0

    @property
    def lean(self) -> float:
        """The body's lean into the turn at the double supports (rad): atan(v^2 / (g |R|)), v = L / T,
        the lean of a body whose weight and centripetal force add up along it."""
        speed = self.step_length / self.period
        return math.atan(speed * speed / (self.hybrid.bm.params.gravity * abs(self.radius)))

    def touchdown(self, theta: float, which: int) -> np.ndarray:
        """C1 (``which`` 0, radius R) or C2 (1, radius -R) at trunk pitch ``theta``."""
        return self.turning(self.step_length, self.alpha, self.mode, theta, self.radius * (1 - 2 * which), self.lean)

    def split(self, u: np.ndarray) -> tuple[tuple[np.ndarray, float], tuple[np.ndarray, float]]:
        n = self.n
        return (u[:n], float(u[n])), (u[n + 1: 2 * n + 1], float(u[2 * n + 1]))

    def ends(self, u: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(q(0), q(T)) of steps A and B."""
        exchange = self.hybrid.exchange
        c1, c2 = self.touchdown(u[self.n], 0), self.touchdown(u[2 * self.n + 1], 1)
        return [(exchange.configuration(c2), c1), (exchange.configuration(c1), c2)]

    def __call__(self, flow: BallisticFlow, u: np.ndarray, jacobian: bool,
                 keep_nodes: bool = False) -> tuple[np.ndarray, np.ndarray | None, list[FlowResult]]:
        """F (2 nq + 2), dF/du when ``jacobian``, and the two steps' flows."""
        n, exchange = self.n, self.hybrid.exchange
        steps = self.split(u)
        ends = self.ends(u)
        runs, f = [], []
        for k, ((qd0, _), (q0, q_t)) in enumerate(zip(steps, ends)):
            seeds = None
            if jacobian:  # columns: the step's own initial velocity, then the start's theta (the other step's)
                other_theta = steps[1 - k][1]
                start = lambda th: exchange.configuration(self.touchdown(th, 1 - k))  # noqa: E731
                seeds = np.zeros((2 * n, n + 1))
                seeds[n:, :n] = np.eye(n)
                seeds[:n, n] = (start(other_theta + FD_STEP) - start(other_theta - FD_STEP)) / (2 * FD_STEP)
            with np.errstate(over="ignore", invalid="ignore"):
                run = flow.propagate(q0, qd0, self.period, seeds, keep_nodes)
            self.evaluations += run.evaluations
            runs.append(run)
        for k, (run, (_, q_t)) in enumerate(zip(runs, ends)):
            next_qd = steps[1 - k][0]
            f += [run.q - q_t, [self.hybrid.impact(q_t).closure_gap(next_qd, run.qd) - self.closure_targets[k]]]
        f = np.concatenate(f)
        if not jacobian:
            return f, None, runs
        jac = np.zeros((2 * n + 2, 2 * n + 2))
        for k, (run, ((_, theta), (_, q_t))) in enumerate(zip(runs, zip(steps, ends))):
            rows, own, other = slice(k * (n + 1), (k + 1) * (n + 1)), k * (n + 1), (1 - k) * (n + 1)
            end = lambda th: self.touchdown(th, k)  # noqa: E731
            d_end = (end(theta + FD_STEP) - end(theta - FD_STEP)) / (2 * FD_STEP)
            jac[rows.start: rows.start + n, own: own + n] = run.sens[:n, :n]
            jac[rows.start: rows.start + n, other + n] = run.sens[:n, n]
            jac[rows.start: rows.start + n, own + n] = -d_end
            impact = self.hybrid.impact(q_t)
            d_next, d_end_velocity = impact.closure_gradients()
            gap_row = rows.stop - 1
            jac[gap_row, other: other + n] = d_next
            jac[gap_row, own: own + n] = d_end_velocity @ run.sens[n:, :n]
            jac[gap_row, other + n] = d_end_velocity @ run.sens[n:, n]
            next_qd = self.split(u)[1 - k][0]
            gap = lambda th: self.hybrid.impact(end(th)).closure_gap(next_qd, run.qd)  # noqa: E731
            jac[gap_row, own + n] = (gap(theta + FD_STEP) - gap(theta - FD_STEP)) / (2 * FD_STEP)
        return f, jac, runs


def solve_stride(hybrid: HybridStep, flow: BallisticFlow, problem: StrideProblem,
                 guess: tuple[np.ndarray, float, np.ndarray, float], settings: Settings = DEFAULTS,
                 coarse: BallisticFlow | None = None, closure_targets: tuple[float, float] = (0.0, 0.0)
                 ) -> StrideSolution:
    """Solve the stride ``problem`` from ``guess`` = (qd_A(0), theta_1, qd_B(0), theta_2) on ``flow``'s grid:
    Newton on ``coarse`` (if given) finished by chord steps on ``flow``, else Newton on ``flow``.
    ``settings.tolerance`` bounds the end-point residuals (rad) and the closure gaps' distance to
    ``closure_targets`` (kg m^2/s, at C1 and C2: what the spin moments change, as in
    ``bvp.StepProblem``)."""
    system = StrideResidual(hybrid, problem, closure_targets)
    u0 = np.concatenate([guess[0], [guess[1]], guess[2], [guess[3]]])
    tol = settings.tolerance
    newton_flow = coarse or flow
    newton_tol = max(tol, settings.coarse_tolerance) if coarse is not None else tol
    result = newton.newton(lambda x, jac: system(newton_flow, x, jac), u0, newton_tol, settings.max_iterations)
    iterations = result.iterations
    if result.converged and coarse is not None:
        fine = lambda x: system(flow, x, False, keep_nodes=True)[::2]  # noqa: E731
        finish = newton.chord(fine, result.x, result.jacobian, tol, settings.chord_iterations, contraction=0.1)
        if not finish.converged:
            finish = newton.newton(lambda x, jac: system(flow, x, jac), finish.x, tol, settings.max_iterations)
        result, iterations = finish, iterations + finish.iterations
    return _solution(system, flow, result, iterations)


def _solution(system: StrideResidual, flow: BallisticFlow, result: newton.SolveResult, iterations: int
              ) -> StrideSolution:
    """Package both steps on ``flow``'s grid, with their nodes."""
    u = result.x
    _, _, runs = system(flow, u, False, keep_nodes=True)
    steps = []
    for k, (((qd0, theta), (q0, q_t)), run) in enumerate(zip(zip(system.split(u), system.ends(u)), runs)):
        finite = bool(np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd)))
        next_qd = system.split(u)[1 - k][0]
        steps.append(BvpSolution(
            converged=result.converged, message=result.message, iterations=iterations, theta=theta, q0=q0,
            q_target=q_t, qd_a=np.array(qd0), qd_b=run.qd.copy(),
            end_residual=float(np.max(np.abs(run.q - q_t))) if finite else math.inf,
            closure_gap=system.hybrid.impact(q_t).closure_gap(next_qd, run.qd) if finite else math.inf,
            evaluations=system.evaluations, nodes=run.nodes))
    return StrideSolution(result.converged, result.message, iterations, (steps[0], steps[1]))
