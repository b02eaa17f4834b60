"""Planning one verified periodic gait: request checks, the BVP with its closure, the optimal
impulses of the double support, the step's figures, the verdict.

``GaitPlanner.plan`` is the core entry point of the CLI, the studies and the ROS nodes. Inputs
and outputs are SI with angles in radians; a bad request raises ``ValueError`` with a one-line
message (angles quoted in degrees, as users give them).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .admissibility import judge
from .bvp import CLOSURES, BvpSolution, solve_bvp
from .configurations import GaitMode
from .flow import hermite_samples
from .gait import DoubleSupport, Gait, GaitProblem
from .hybrid import HybridStep
from .impulses import EFFORTS, solve_impulses
from .model import BipedModel
from .params import BipedParams, load_params
from .reports import StepFigures, energy_drift, step_figures
from .settings import DEFAULTS, Settings


@dataclass(frozen=True)
class GaitRequest:
    """What to plan: step length L (m), period T (s), arm amplitude alpha (rad), gait mode (a
    ``GaitMode`` or its name, parsed here), parameter set (name or file; empty: the planner's),
    closure (``theta``/``slack``), effort (``l1``/``l2``)."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode = GaitMode.NORMAL
    params: str = ""
    closure: str = "theta"
    effort: str = "l1"

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", GaitMode.parse(self.mode))


def _finite(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return float(value)


def validate_request(request: GaitRequest, params: BipedParams) -> GaitProblem:
    """Check a request against the biped described by ``params``; ``ValueError`` if it is bad."""
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
    if request.closure not in CLOSURES:
        raise ValueError(f"unknown closure {request.closure!r}: use 'theta' or 'slack'")
    if request.effort not in EFFORTS:
        raise ValueError(f"unknown effort {request.effort!r}: use 'l1' or 'l2'")
    return GaitProblem(step_length, period, alpha, request.mode, params.name, request.closure, request.effort)


class GaitPlanner:
    """Plans gaits for one parameter set; keeps its Pinocchio models and hybrid step.

    Not thread-safe (Pinocchio data are reused): give each thread or process its own planner.
    """

    def __init__(self, params: BipedParams | str | None = None, settings: Settings = DEFAULTS):
        """``params``: a parameter set, its name or file (None: the default); ``settings``: the
        numerical settings (grids, tolerance, iterations, samples)."""
        self.settings = settings
        self.params = params if isinstance(params, BipedParams) else load_params(params)
        self.model = BipedModel.from_params(self.params)
        self.hybrid = HybridStep(self.model)
        self.flow = self.hybrid.flow(settings.fine_steps)
        self.coarse_flow = self.hybrid.flow(settings.coarse_steps) if settings.coarse_steps < settings.fine_steps else None

    def plan(self, request: GaitRequest, guess: tuple[np.ndarray, float] | None = None) -> Gait:
        """Solve one gait. ``guess`` = (qd(0), theta) of a nearby gait warm-starts the BVP.

        Raises ``ValueError`` for an invalid request; a solve that fails is returned with
        ``converged`` or ``admissible`` False and the reasons in ``verdict``.
        """
        if request.params and request.params != self.params.name:
            raise ValueError(f"this planner holds parameter set {self.params.name!r}, not {request.params!r}")
        problem = validate_request(request, self.params)
        start = time.perf_counter()
        step = solve_bvp(self.hybrid, self.flow, problem.step_length, problem.period, problem.arm_amplitude,
                         problem.mode, problem.closure, guess, self.settings, self.coarse_flow)
        double_support = figures = None
        if step.converged:
            double_support = self._double_support(step, problem)
            figures = self._figures(step, problem.period)
        verdict = judge(step, double_support.impulses if double_support else None, figures)
        return Gait(problem, step, double_support, figures, verdict, time.perf_counter() - start)

    def _double_support(self, step: BvpSolution, problem: GaitProblem) -> DoubleSupport:
        bm = self.model
        q_t = step.q_target
        impact = self.hybrid.impact(q_t)
        lp = impact.problem(step.qd_b, step.qd_a)
        slack = 0.0
        if problem.closure == "slack":
            # Paper comparison: theta = 0 and the smallest change of Xd^a along z_d that makes
            # eqs. (6)-(10) consistent.
            lp, slack = lp.reachable()
        sol = solve_impulses(lp, problem.effort)
        xd_b, xd_a = lp.xd_b, lp.xd_a
        new_foot = bm.swing_tip(q_t)
        origin = np.zeros(3)
        vz_before = vz_after = speed_after = math.nan
        if sol.success:
            vz_before = float(lp.j2[2] @ sol.xd_minus)
            vz_after = float(lp.j1[2] @ sol.xd_plus)
            speed_after = float(np.linalg.norm(lp.j2 @ xd_a))
        return DoubleSupport(
            impulses=sol,
            xd_b=xd_b,
            xd_a=xd_a,
            slack=slack,
            new_stance_foot=new_foot,
            h_t_minus=(bm.vertical_momentum_about(q_t, xd_b, origin), bm.vertical_momentum_about(q_t, xd_b, new_foot)),
            h_t_plus=(bm.vertical_momentum_about(q_t, xd_a, origin), bm.vertical_momentum_about(q_t, xd_a, new_foot)),
            swing_tip_vz_before_impact=vz_before,
            old_stance_tip_vz_after_impact=vz_after,
            new_stance_tip_speed_after=speed_after,
        )

    def _figures(self, step: BvpSolution, period: float) -> StepFigures:
        times = np.linspace(0.0, period, self.settings.samples)
        q, qd = hermite_samples(step.nodes, times)
        samples = self.hybrid.samples
        return step_figures(samples, times, q, qd, period, energy_drift(samples, step.nodes[1], step.nodes[2]))
