"""One verified periodic gait: request checks, BVP with closure, optimal impulses, reports.

``GaitPlanner.plan`` is the core entry point used by the CLI and, later, by the ROS nodes.
Inputs and outputs are SI with angles in radians; the request's checks raise ``ValueError``
with a one-line message (angles quoted in degrees, as users give them).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .boundary import GaitMode
from .bvp import CLOSURES, BvpSolution, impact_problem, solve_bvp
from .flow import BallisticFlow, hermite_samples
from .impulses import EFFORTS, solve_impulses
from .model import BipedModel
from .params import BipedParams, load_params
from .reports import StepTrajectory, step_figures
from .result import GaitResult

DEFAULT_STEPS = 32  # RK8 steps per ballistic step: end state within ~1e-10 of an adaptive solver
COARSE_STEPS = 16  # grid of Newton's iterations, finished on the fine grid by chord steps
DEFAULT_SAMPLES = 91


@dataclass(frozen=True)
class GaitRequest:
    """What to plan: step length L (m), period T (s), arm amplitude alpha (rad), gait mode,
    parameter set (name or file; empty: default), closure (``theta``/``slack``), effort
    (``l1``/``l2``)."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode | str = GaitMode.NORMAL
    params: str = ""
    closure: str = "theta"
    effort: str = "l1"


def _finite(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return float(value)


def validate_request(request: GaitRequest, params: BipedParams) -> tuple[float, float, float, GaitMode]:
    """Check a request against the biped; return (L, T, alpha, mode) or raise ``ValueError``."""
    step_length = _finite("step length", request.step_length)
    period = _finite("period", request.period)
    alpha = _finite("arm amplitude", request.arm_amplitude)
    two_l = 2 * params.leg_length
    if not 0 < step_length < two_l:
        raise ValueError(f"step length must be in (0, {two_l:.3f}) m (twice the leg length), got {step_length:g} m")
    if period <= 0:
        raise ValueError(f"period must be positive, got {period:g} s")
    if not 0 <= alpha < math.pi / 2:
        raise ValueError(f"arm amplitude must be in [0, 90) deg, got {math.degrees(alpha):g} deg")
    mode = GaitMode.parse(request.mode)
    if request.closure not in CLOSURES:
        raise ValueError(f"unknown closure {request.closure!r}: use 'theta' or 'slack'")
    if request.effort not in EFFORTS:
        raise ValueError(f"unknown effort {request.effort!r}: use 'l1' or 'l2'")
    return step_length, period, alpha, mode


class GaitPlanner:
    """Plans gaits for one parameter set; keeps its Pinocchio models and integrator.

    Not thread-safe (Pinocchio data are reused): give each thread or process its own planner.
    """

    def __init__(
        self,
        params: BipedParams | str | None = None,
        steps: int = DEFAULT_STEPS,
        coarse_steps: int = COARSE_STEPS,
        samples: int = DEFAULT_SAMPLES,
        tol: float = 1e-12,
        max_iter: int = 30,
    ):
        """``params``: a parameter set, its name or file (None: default); ``steps``/``coarse_steps``:
        RK8 grids of the fine flow and of Newton's iterations; ``samples``: trajectory samples
        reported per step; ``tol``: BVP residual bound (rad, kg m^2/s); ``max_iter``: Newton's
        iteration bound."""
        if samples < 2:
            raise ValueError(f"samples must be at least 2, got {samples}")
        self.tol, self.max_iter = tol, max_iter
        self.params = params if isinstance(params, BipedParams) else load_params(params)
        self.model = BipedModel.from_params(self.params)
        self.flow = BallisticFlow(self.model.single, steps)
        self.coarse_flow = BallisticFlow(self.model.single, coarse_steps) if coarse_steps < steps else None
        self.samples = samples

    def plan(self, request: GaitRequest, guess: tuple[np.ndarray, float] | None = None) -> GaitResult:
        """Solve one gait. ``guess`` = (qd(0), theta) of a nearby gait warm-starts the BVP.

        Raises ``ValueError`` for an invalid request; a solve that fails is returned with
        ``converged`` or ``admissible`` False and the reason in ``message``/``reasons``.
        """
        if request.params and request.params != self.params.name:
            raise ValueError(f"this planner holds parameter set {self.params.name!r}, not {request.params!r}")
        step_length, period, alpha, mode = validate_request(request, self.params)
        start = time.perf_counter()
        bm = self.model
        bvp = solve_bvp(bm, self.flow, step_length, period, alpha, mode, request.closure, guess,
                        tol=self.tol, max_iter=self.max_iter, coarse=self.coarse_flow)
        result = GaitResult.empty(request, step_length, period, alpha, mode, self.params.name)
        result.fill_bvp(bvp)
        if bvp.converged:
            self._double_support(result, bvp, request)
            self._single_support(result, bvp, period)
        result.judge()
        result.solve_time_s = time.perf_counter() - start
        return result

    def _double_support(self, result: GaitResult, bvp: BvpSolution, request: GaitRequest) -> None:
        bm = self.model
        q_t = bvp.q_target
        problem = impact_problem(bm, q_t, bvp.qd_b, bvp.qd_a)
        slack = 0.0
        if request.closure == "slack":
            # Paper comparison: theta = 0 and the smallest change of Xd^a along z_d that makes
            # eqs. (6)-(10) consistent.
            problem, slack = problem.reachable()
        sol = solve_impulses(problem, request.effort)
        xd_b, xd_a, j1, j2 = problem.xd_b, problem.xd_a, problem.j1, problem.j2
        new_foot = bm.swing_tip(q_t)
        result.fill_impulses(sol, xd_b, xd_a, slack)
        result.H_Tminus = [bm.vertical_momentum_about(q_t, xd_b, np.zeros(3)), bm.vertical_momentum_about(q_t, xd_b, new_foot)]
        result.H_Tplus = [bm.vertical_momentum_about(q_t, xd_a, np.zeros(3)), bm.vertical_momentum_about(q_t, xd_a, new_foot)]
        result.new_stance_foot = new_foot.tolist()
        if sol.success:
            result.swing_tip_vz_before_impact = float(j2[2] @ sol.xd_minus)
            result.old_stance_tip_vz_after_impact = float(j1[2] @ sol.xd_plus)
            result.new_stance_tip_speed_after = float(np.linalg.norm(j2 @ xd_a))

    def _single_support(self, result: GaitResult, bvp: BvpSolution, period: float) -> None:
        times = np.linspace(0.0, period, self.samples)
        q, qd = hermite_samples(bvp.nodes, times)
        qdd = np.array([self.flow.acceleration(a, b) for a, b in zip(q, qd)])
        traj = StepTrajectory(times, q, qd, qdd)
        energy = self.energy(bvp.nodes[1], bvp.nodes[2])
        result.fill_step(traj, step_figures(self.model, traj, period), float(np.max(np.abs(energy / energy[0] - 1))))

    def energy(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Total mechanical energy (J) at each row of (q, qd): kinetic plus gravitational
        potential, zero height at the stance tip."""
        model, data = self.model.single, self.model.single_data
        return np.array(
            [pin.computeKineticEnergy(model, data, a, b) + pin.computePotentialEnergy(model, data, a) for a, b in zip(q, qd)]
        )
