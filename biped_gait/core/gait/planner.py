"""Planning one verified periodic gait: request checks, the BVP with its closure, the optimal
impulses of the double support, the step's figures, the verdict.

``GaitPlanner.plan`` is the core entry point of the CLI, the studies and the ROS nodes. Without
a caller's warm start it finds the gait on the human-like branch: from the gait atlas's
interpolated warm start; failing that (or if that gait is not admissible), by continuation from
the nearest admissible atlas gait (or, without an atlas, from the human-like gait at
L = T = 0.45 s); last, from the straight-line cold start. Inputs and outputs are SI with angles
in radians; a bad request raises ``ValueError`` with a one-line message (angles quoted in
degrees, as users give them).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .admissibility import judge
from .atlas import Atlas, AtlasError, atlas_path
from .bvp import CLOSURES, BvpSolution, solve_bvp
from .configurations import GaitMode
from .continuation import continue_to
from ..dynamics.flow import hermite_samples
from .gait import DoubleSupport, Gait, GaitProblem
from ..dynamics.hybrid import HybridStep
from ..dynamics.impulses import EFFORTS, EffortOptions, ImpulseSolution, friction_ratios, solve_impulses
from ..model.biped import BipedModel
from ..model.params import BipedParams, load_params
from .figures import StepFigures, energy_drift, step_figures
from .margins import Margins, with_margins
from ..dynamics.settings import DEFAULTS, Settings
from .stability import open_loop

SEED = (0.45, 0.45, math.radians(23.5))  # (L m, T s, alpha rad): the straight-line start finds the human-like gait
BRANCH_BOUND = 1.0  # rad/s: a solve that ends farther than this from its warm start left the branch


@dataclass(frozen=True)
class GaitRequest:
    """What to plan: step length L (m), period T (s), arm amplitude alpha (rad), gait mode (a
    ``GaitMode`` or its name, parsed here), parameter set (name or file; empty: the planner's),
    closure (``theta``/``slack``), effort (``l1``/``l2``); the friction coefficient (NaN: the
    parameter set's; inf: no cone), the bound on the double support's joint rates (rad/s; inf:
    none), the effort's reading (``joint``/``absolute``), and the margins: the swing tip's least
    clearance (m) and the friction margin (the impulses and the step within mu - it). The
    options' names, units and defaults are those of ``biped_gait.gait_options``."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode = GaitMode.NORMAL
    params: str = ""
    closure: str = "theta"
    effort: str = "l1"
    friction: float = math.nan
    rate_bound: float = math.inf
    effort_coordinates: str = "joint"
    min_clearance: float = 0.0
    friction_margin: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", GaitMode.parse(self.mode))


def _finite(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value}")
    return float(value)


def _number(name: str, value: object) -> float:
    """A number that may be infinite (a bound or coefficient that can be dropped)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ValueError(f"{name} must be a number, got {value!r}")
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
    friction = _number("friction coefficient", request.friction)
    friction = params.friction if math.isnan(friction) else friction
    if friction == 0:
        raise ValueError("friction coefficient 0 is a frictionless floor, on which no gait walks (NaN: the parameter "
                         "set's coefficient; inf: no cone)")
    options = EffortOptions(friction, _number("joint-rate bound", request.rate_bound), request.effort_coordinates)
    clearance = _finite("swing clearance margin", request.min_clearance)
    margin = _finite("friction margin", request.friction_margin)
    if clearance < 0:
        raise ValueError(f"swing clearance margin must be 0 (none) or positive, got {clearance:g} m")
    if not 0 <= margin < friction:
        raise ValueError(f"friction margin must be in [0, {friction:g}) (the friction coefficient), got {margin:g}")
    return GaitProblem(step_length, period, alpha, request.mode, params.name, request.closure, request.effort, options,
                       Margins(clearance, margin))


class GaitPlanner:
    """Plans gaits for one parameter set; keeps its Pinocchio models and hybrid step.

    Not thread-safe (Pinocchio data are reused): give each thread or process its own planner.
    """

    def __init__(self, params: BipedParams | str | None = None, settings: Settings = DEFAULTS, atlas: bool = True,
                 on_note: Callable[[str], None] | None = None):
        """``params``: a parameter set, its name or file (None: the default); ``settings``: the
        numerical settings (grids, tolerance, iterations, samples); ``atlas``: use the gait
        atlas of these parameters (shipped, or in the cache) when there is a current one;
        ``on_note``: told (once per mode) why there is none (default: a Python warning)."""
        self.settings = settings
        self.source = params if isinstance(params, str) else None
        self.params = params if isinstance(params, BipedParams) else load_params(params)
        self.use_atlas = atlas
        self._atlases: dict[GaitMode, Atlas | None] = {}
        self.atlas_notes: dict[GaitMode, str] = {}
        self._note = on_note or (lambda text: warnings.warn(text, stacklevel=4))
        self.model = BipedModel.from_params(self.params)
        self.hybrid = HybridStep(self.model)
        self.flow = self.hybrid.flow(settings.fine_steps)
        self.coarse_flow = self.hybrid.flow(settings.coarse_steps) if settings.coarse_steps < settings.fine_steps else None

    def atlas(self, mode: GaitMode) -> Atlas | None:
        """The current atlas of these parameters and ``mode`` (loaded once), or None; why not
        is in ``atlas_notes[mode]`` (and said once as a warning)."""
        if mode not in self._atlases:
            atlas = None
            if self.use_atlas:
                try:
                    atlas = Atlas.load(atlas_path(self.params, mode), self.params, self.source)
                except AtlasError as exc:
                    self.atlas_notes[mode] = str(exc)
                    self._note(f"{exc}; planning without it ({mode.value} gaits)")
            self._atlases[mode] = atlas
        return self._atlases[mode]

    def plan(self, request: GaitRequest, guess: tuple[np.ndarray, float] | None = None, cold: bool = False) -> Gait:
        """Solve one gait. ``guess`` = (qd(0), theta) of a nearby gait warm-starts the BVP (a
        continuation chain's own step); ``cold``: only the straight-line start; without either
        the gait is found on the human-like branch (module docstring). ``Gait.found`` says how.

        Raises ``ValueError`` for an invalid request; a solve that fails is returned with
        ``converged`` or ``admissible`` False and the reasons in ``verdict`` (and a ``hint`` of
        where admissible gaits are, when the atlas knows).
        """
        if request.params and request.params != self.params.name:
            raise ValueError(f"this planner holds parameter set {self.params.name!r}, not {request.params!r}")
        problem = validate_request(request, self.params)
        start = time.perf_counter()
        if guess is not None or cold:
            gait = self._solve(problem, guess, "guess" if guess is not None else "cold")
        else:
            gait = self._find(problem)
        return replace(gait, solve_time_s=time.perf_counter() - start)

    def _find(self, problem: GaitProblem) -> Gait:
        """The gait of ``problem`` on the human-like branch: atlas, then continuation, then cold."""
        point = (problem.step_length, problem.period, problem.arm_amplitude)
        atlas = self.atlas(problem.mode)
        if atlas is not None and problem.margins:
            atlas = atlas.within(problem.margins, problem.options.friction)
        first = None
        guess = atlas.guess(point) if atlas is not None else None
        if guess is not None:
            first = self._solve(problem, guess, "atlas")
            if not _near(first, guess):
                first = None
            elif first.admissible or not atlas.admissible_near(point):
                return self._hinted(first, atlas, point)
        origin = self._origin(problem, atlas)
        if origin is not None:
            guess = continue_to(self.hybrid, self.coarse_flow or self.flow, problem.mode, problem.closure, self.settings,
                                origin[0], origin[1], point)
            if guess is not None:
                gait = self._solve(problem, guess, "continuation")
                if gait.converged and (gait.admissible or first is None):
                    return self._hinted(gait, atlas, point)
        if first is not None:
            return self._hinted(first, atlas, point)
        return self._hinted(self._solve(problem, None, "cold"), atlas, point)

    def _origin(self, problem: GaitProblem, atlas: Atlas | None):
        """Where a continuation to ``problem`` starts: the nearest admissible atlas node, else
        the human-like gait at ``SEED``, solved cold; as ((L, T, alpha), (qd(0), theta)), or None
        if that fails."""
        point = (problem.step_length, problem.period, problem.arm_amplitude)
        index = atlas.nearest(point) if atlas is not None else None
        if index is not None:
            return atlas.grid.point(index), (atlas.nodes["qd_a"][index], float(atlas.nodes["theta"][index]))
        step = solve_bvp(self.hybrid, self.flow, *SEED, problem.mode, problem.closure, None, self.settings, self.coarse_flow)
        return (SEED, (step.qd_a, step.theta)) if step.converged else None

    @staticmethod
    def _hinted(gait: Gait, atlas: Atlas | None, point: tuple[float, float, float]) -> Gait:
        if gait.admissible or atlas is None:
            return gait
        return replace(gait, hint=atlas.hint(point))

    def _solve(self, problem: GaitProblem, guess: tuple[np.ndarray, float] | None, found: str) -> Gait:
        """The gait of ``problem`` solved from ``guess`` (None: the straight-line start)."""
        step = solve_bvp(self.hybrid, self.flow, problem.step_length, problem.period, problem.arm_amplitude,
                         problem.mode, problem.closure, guess, self.settings, self.coarse_flow)
        double_support = figures = None
        within_limits = None
        if step.converged:
            double_support, within_limits = self._double_support(step, problem)
            figures = self._figures(step, problem.period)
        impulses = double_support.impulses if double_support else None
        verdict = with_margins(judge(step, impulses, figures, problem.options.friction), impulses, figures,
                               problem.options.friction, problem.margins, within_limits)
        stability = None
        if double_support is not None and double_support.impulses.success:
            stability = open_loop(self.hybrid, self.flow, problem.period, step.q0, step.qd_a,
                                  double_support.impulses.i_minus, double_support.impulses.i_plus)
        return Gait(problem, step, double_support, figures, verdict, math.nan, found, stability=stability)

    def _double_support(self, step: BvpSolution, problem: GaitProblem) -> tuple[DoubleSupport, ImpulseSolution | None]:
        """The double support with the impulses under the request's margins, and, when those
        have no solution but the margins narrow the impulse problem, the impulses under the
        limits alone (else None)."""
        bm = self.model
        q_t = step.q_target
        impact = self.hybrid.impact(q_t)
        lp = impact.problem(step.qd_b, step.qd_a)
        slack = 0.0
        if problem.closure == "slack":
            # Paper comparison: theta = 0 and the smallest change of Xd^a along z_d that makes
            # eqs. (6)-(10) consistent.
            lp, slack = lp.reachable()
        sol = solve_impulses(lp, problem.effort, problem.impulse_options)
        within_limits = None
        if not sol.success and problem.impulse_options != problem.limit_options:
            within_limits = solve_impulses(lp, problem.effort, problem.limit_options)
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
            impulse_friction_ratios=friction_ratios(sol.x),
            max_intermediate_joint_rate=float(np.max(np.abs(np.concatenate([sol.xd_minus[5:], sol.xd_plus[5:]])))),
        ), within_limits

    def _figures(self, step: BvpSolution, period: float) -> StepFigures:
        times = np.linspace(0.0, period, self.settings.samples)
        q, qd = hermite_samples(step.nodes, times)
        samples = self.hybrid.samples
        return step_figures(samples, times, q, qd, period, energy_drift(samples, step.nodes[1], step.nodes[2]))


def _near(gait: Gait, guess: tuple[np.ndarray, float]) -> bool:
    """Whether a solve stayed near its warm start (on the warm start's branch)."""
    return gait.converged and float(np.max(np.abs(gait.step.qd_a - guess[0]))) <= BRANCH_BOUND
