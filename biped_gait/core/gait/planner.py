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
from collections.abc import Callable, Iterable
from concurrent.futures import Future
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from .admissibility import judge
from .atlas import Atlas, AtlasError, atlas_path, period_runs
from .bvp import CLOSURES, BvpSolution, StepProblem, solve_bvp
from .configurations import GaitMode
from .continuation import BRANCH_JUMP, STEP_ITERATIONS, continue_to
from ..dynamics.flow import BallisticFlow, FlowResult, hermite_samples
from .gait import DoubleSupport, Gait, GaitProblem, Stride
from ..dynamics.hybrid import HybridStep
from ..dynamics.impulses import EFFORTS, EffortOptions, ImpulseSolution, friction_ratios, solve_impulses
from ..model.biped import BipedModel
from ..model.params import BipedParams, load_params, names_set
from .figures import StepFigures, energy_drift, step_figures
from .grid import PlanGrids
from .margins import Margins, with_margins
from ..dynamics.settings import DEFAULTS, Settings
from .monodromy import SpeculativeFlow
from . import richardson
from .solve_cache import cached
from .accuracy import END_POINT_BOUND
from .stability import Multipliers, PoincareMap, multipliers_of, open_loop

if TYPE_CHECKING:
    from .lasting import LastingPlanner, LastingRequest
    from .actuated_swing import ActuatedSwingCycle, SwingRequest
    from .lasting_support import LastingSupport
    from .turning_atlas import TurningAtlas

SEED = (0.45, 0.45, math.radians(23.5))  # (L m, T s, alpha rad): the straight-line start finds the human-like gait
BRANCH_BOUND = 1.0  # rad/s: a solve that ends farther than this from its warm start left the branch
CLOSURE_ROUNDS = 10  # re-solves of the closure matched to the spin moments' share (2 to 4 suffice)
CURVATURE_STEP = 0.1  # 1/m: the largest change of 1 / R in one step of a stride's continuation
MIN_CURVATURE_STEP = 1e-3  # 1/m: below this the continuation is given up
RADIUS_BISECTIONS = 4  # halvings of the curvature interval where a stride stops being admissible
REFINEMENTS = 4  # doublings of the planner's grid allowed to meet the accuracy contract (32 steps to 512)
# Newton's iterations solving a plan again on its estimate's grid, from its own solution: one or two where that grid
# is in its asymptotic range; beyond these, that grid is too coarse to estimate from (the estimate is infinite).
ESTIMATE_ITERATIONS = 4
StrideGuess = tuple[np.ndarray, float, np.ndarray, float]  # (qd_A(0), theta_1, qd_B(0), theta_2)


@dataclass(frozen=True)
class GaitRequest:
    """What to plan: step length L (m), period T (s), arm amplitude alpha (rad), gait mode (a
    ``GaitMode`` or its name, parsed here), parameter set (name or file; empty: the planner's),
    closure (``theta``/``slack``), effort (``l1``/``l2``); the friction coefficient (NaN: the
    parameter set's; inf: no cone), the bound on the double support's joint rates (rad/s; inf:
    none), the effort's reading (``joint``/``absolute``), the margins: the swing tip's least
    clearance (m) and the friction margin (the impulses and the step within mu - it), the step
    width (m, between the feet; NaN: the hips' spacing) and the turn radius (m, signed: positive
    turns left; inf: straight; a finite one is a stride, ``GaitPlanner.plan_stride``). The
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
    step_width: float = math.nan
    turn_radius: float = math.inf

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
    width = validate_step_width(request.step_width, params)
    radius = validate_turn_radius(request.turn_radius, params)
    if math.isfinite(radius) and (width != params.hip_spacing or request.closure != "theta"):
        raise ValueError("a gait on a circle has its feet at the hips' spacing (turned) and the theta closure")
    clearance = _finite("swing clearance margin", request.min_clearance)
    margin = _finite("friction margin", request.friction_margin)
    if clearance < 0:
        raise ValueError(f"swing clearance margin must be 0 (none) or positive, got {clearance:g} m")
    if not 0 <= margin < friction:
        raise ValueError(f"friction margin must be in [0, {friction:g}) (the friction coefficient), got {margin:g}")
    return GaitProblem(step_length, period, alpha, request.mode, params.name, request.closure, request.effort, options,
                       width, radius, Margins(clearance, margin))

def validate_turn_radius(turn_radius: float, params: BipedParams) -> float:
    """The turn radius (m) of a request: inf (straight), or finite beyond the hips' half spacing
    with hip roll and yaw joints; ``ValueError`` otherwise."""
    radius = _number("turn radius", turn_radius)
    if math.isnan(radius) or radius == 0:
        raise ValueError(f"turn radius must be a non-zero number of metres (inf: straight), got {radius:g}")
    if math.isinf(radius):
        return math.inf
    if not params.joints.lateral_hips:
        raise ValueError(f"parameter set {params.name} walks straight only: walking on a circle needs hip roll and "
                         "yaw joints (e.g. aoustin2013-hips)")
    if abs(radius) <= params.hip_half_width:
        raise ValueError(f"turn radius must exceed the hips' half spacing ({params.hip_half_width:g} m), "
                         f"got {radius:g} m")
    return radius


STEP_WIDTH_SPAN = 0.5
"""Step widths a model with lateral hip joints walks at: the hips' spacing within this fraction
of it (0.2 to 0.6 m for the shipped sets)."""


def validate_step_width(step_width: float, params: BipedParams) -> float:
    """The step width (m) of a request (NaN: the hips' spacing); ``ValueError`` outside the
    range the model can walk."""
    spacing = params.hip_spacing
    width = _number("step width", step_width)
    if math.isnan(width):
        return spacing
    width = _finite("step width", width)
    if width == spacing:
        return width
    if not params.joints.lateral_hips:
        raise ValueError(f"parameter set {params.name} walks with its feet at the hips' spacing ({spacing:g} m) only: "
                         f"a step width of {width:g} m needs hip roll and yaw joints (e.g. aoustin2013-hips)")
    low, high = spacing * (1 - STEP_WIDTH_SPAN), spacing * (1 + STEP_WIDTH_SPAN)
    if not low <= width <= high:
        raise ValueError(f"step width must be in [{low:g}, {high:g}] m for parameter set {params.name} "
                         f"(its hips' spacing {spacing:g} m +- {STEP_WIDTH_SPAN:.0%}), got {width:g} m")
    return width


def lasting_request(request: GaitRequest, duration: float) -> "LastingRequest | None":
    """The double support of ``duration`` s asked beside ``request`` (with its effort and the
    margins a walk tracking it needs, ``LastingRequest.walkable``: the plan served is the one the
    simulator walks), or None for 0 (the paper's instantaneous double support); ``ValueError`` (one
    line) for a duration that is none (negative, NaN, inf) or beside a stride on a circle (planned
    for straight gaits only)."""
    if duration == 0.0:
        return None
    from .lasting import LastingRequest  # CasADi's import only when a lasting double support is asked

    lasting = LastingRequest.walkable(duration, request.effort)
    if math.isfinite(request.turn_radius):
        raise ValueError("double_support: a lasting double support is planned for straight gaits only")
    return lasting


def swing_request(request: GaitRequest, actuated_swing: float, duration: float,
                  walkable: bool = False) -> "SwingRequest | None":
    """The cycle with the swing actuated for ``actuated_swing`` s at each end asked beside
    ``request``, with a double support of ``duration`` s: the least effort without margins, or with
    ``walkable`` the cycle a walk tracks (``SwingRequest.walkable``: the plan served is the one the
    simulator walks); None for 0 (the paper's ballistic swing). ``ValueError`` (one line) for a
    duration that is none, not below half the period, or beside a stride on a circle."""
    if actuated_swing == 0.0:
        return None
    from .actuated_swing import SwingRequest  # CasADi's import only when an actuated swing is asked
    from .lasting import LastingRequest

    swing = (SwingRequest.walkable(actuated_swing, duration, request.effort) if walkable
             else SwingRequest(actuated_swing, LastingRequest(duration, request.effort)))
    if 2 * actuated_swing >= request.period:
        raise ValueError(f"actuated_swing must be below half the period ({request.period / 2:g} s), "
                         f"got {actuated_swing:g} s")
    if math.isfinite(request.turn_radius):
        raise ValueError("actuated_swing: planned for straight gaits only")
    return swing


class GaitPlanner:
    """Plans gaits for one parameter set; keeps its Pinocchio models, hybrid step and flows, and
    its atlases (loaded when it is made, so that its first plan costs what the next ones do).

    Not thread-safe (Pinocchio data are reused): give each thread or process its own planner.
    It keeps one thread of its own, which integrates each gait's variational flow for the
    multipliers while the double support is solved (``monodromy``).
    """

    def __init__(self, params: BipedParams | str | None = None, settings: Settings = DEFAULTS, atlas: bool = True,
                 on_note: Callable[[str], None] | None = None, modes: Iterable[GaitMode | str] | None = None):
        """``params``: a parameter set, its name or file (None: the default); ``settings``: the
        numerical settings (grids, tolerance, iterations, samples); ``atlas``: use the gait
        atlas of these parameters (shipped, or in the cache) when there is a current one, loaded
        here for each of ``modes`` (None: every mode; another mode's is loaded when first asked
        for: a process that plans one gait loads one atlas); ``on_note``: told (once per mode)
        why there is none (default: a Python warning)."""
        self.settings = settings
        self.source = params if isinstance(params, str) else None
        self.params = params if isinstance(params, BipedParams) else load_params(params)
        self.use_atlas = atlas
        self._atlases: dict[GaitMode, Atlas | None] = {}
        self._turning_atlases: dict[GaitMode, TurningAtlas | None] = {}
        self.atlas_notes: dict[GaitMode, str] = {}
        self._told: set[GaitMode] = set()
        self._note = on_note or (lambda text: warnings.warn(text, stacklevel=4))
        self.model = BipedModel.from_params(self.params)
        self.hybrid = HybridStep(self.model)
        self.grid = PlanGrids.of(self.hybrid, settings.fine_steps, settings.coarse_steps)
        self.flow, self.coarse_flow = self.grid.flow, self.grid.coarse
        self._refined: dict[int, PlanGrids] = {}  # the finer grids plans were refined to, by steps
        for mode in GaitMode if modes is None else map(GaitMode.parse, modes):
            self._atlases[mode] = self._load_atlas(mode)

    def _load_atlas(self, mode: GaitMode) -> Atlas | None:
        """The current atlas of these parameters and ``mode``, or None (why: ``atlas_notes[mode]``)."""
        if not self.use_atlas:
            return None
        try:
            return Atlas.load(atlas_path(self.params, mode), self.params, self.source)
        except AtlasError as exc:
            self.atlas_notes[mode] = str(exc)
            return None

    @cached_property
    def lasting(self) -> "LastingPlanner":
        """The double supports that last d seconds (``core/gait/lasting.py``), on this planner's model
        and flow; its programs are built when first solved (a few seconds each). Imported here: CasADi
        takes a quarter of a second to import, which a plan of the paper's gait does not need."""
        from .lasting import LastingPlanner

        return LastingPlanner(self.model, self.hybrid.exchange, self.flow, self.params.friction)

    def lasting_cycle(self, gait: Gait, request: "LastingRequest") -> tuple["LastingSupport", "LastingSupport"]:
        """``gait``'s periodic cycle with a double support of ``request.duration`` s and its
        impulsive limit d -> 0+ (the cycle's seed; its ``effort_total`` is E(0+)), what the ``plan``
        verb and the planner node answer. The cycle is kept on disk (``LastingPlanner.periodic``)."""
        limit = self.lasting.limit(gait, request.effort)
        return self.lasting.periodic(gait, request, limit=limit), limit

    def swing_cycle(self, gait: Gait, request: "SwingRequest") -> "ActuatedSwingCycle":
        """``gait``'s cycle with the swing actuated at its two ends (``core/gait/actuated_swing.py``),
        started from the impulsive cycle of the same d, what the ``plan`` verb and the simulator
        walk; kept on disk (``solve_cache``), as the impulsive cycle is."""
        from .actuated_swing import ActuatedSwingPlanner

        lasting = self.lasting
        return cached("swing_cycle", (lasting.program_key, lasting.boundary(gait), request),
                      lambda: ActuatedSwingPlanner(lasting).cycle(gait, request))

    def atlas(self, mode: GaitMode) -> Atlas | None:
        """The current atlas of these parameters and ``mode`` (loaded when the planner is made,
        or now if it was not among its modes), or None; why not is in ``atlas_notes[mode]``,
        said once as a note when the mode is first asked for."""
        if mode not in self._atlases:
            self._atlases[mode] = self._load_atlas(mode)
        if mode in self.atlas_notes and mode not in self._told:
            self._told.add(mode)
            self._note(f"{self.atlas_notes[mode]}; planning without it ({mode.value} gaits)")
        return self._atlases[mode]

    def _validate(self, request: GaitRequest) -> GaitProblem:
        """The problem of ``request``; ``ValueError`` if it is bad or names another parameter set
        (its ``params`` may name this one by its name, by its file's path, or not at all)."""
        if not names_set(request.params, self.params, self.source):
            raise ValueError(f"this planner holds parameter set {self.params.name!r}"
                             f"{f' ({self.source})' if self.source and self.source != self.params.name else ''}, "
                             f"not {request.params!r}")
        return validate_request(request, self.params)

    def plan(self, request: GaitRequest, guess: tuple[np.ndarray, float] | None = None, cold: bool = False) -> Gait:
        """Solve one gait. ``guess`` = (qd(0), theta) of a nearby gait warm-starts the BVP (a
        continuation chain's own step); ``cold``: only the straight-line start; without either
        the gait is found on the human-like branch (module docstring). ``Gait.found`` says how.

        Raises ``ValueError`` for an invalid request; a solve that fails is returned with
        ``converged`` or ``admissible`` False and the reasons in ``verdict`` (and a ``hint`` of
        where admissible gaits are, when the atlas knows).
        """
        problem = self._validate(request)
        if math.isfinite(problem.turn_radius):
            raise ValueError("a gait on a circle is a stride of two steps: plan it with plan_stride")
        start = time.perf_counter()
        if guess is not None or cold:
            gait = self._solve(problem, guess, "guess" if guess is not None else "cold")
        else:
            gait = self._find(problem)
        return replace(gait, solve_time_s=time.perf_counter() - start)

    def plan_stride(self, request: GaitRequest, guess: StrideGuess | None = None, stability: bool = True,
                    guess_curvature: float | None = None) -> Stride:
        """Solve one gait on a circle (``request.turn_radius`` finite): a stride of two steps
        (docs/model.md section 4.9). ``guess`` = (qd_A(0), theta_1, qd_B(0), theta_2) of a nearby
        stride warm-starts it (with ``guess_curvature``, the curvature in 1/m it was solved at: a
        solve that leaves the guess's branch is done again along a continuation from it); without
        one the turning atlas's, checked like the guess; a stride the atlas leads to that is not
        admissible is compared with the one reached from the straight gait at the same (L, T,
        alpha, mode) by continuation in the curvature 1 / R (an atlas node may sit on the other
        branch). ``ValueError`` for an invalid request; a stride that is not admissible (or not
        reached) is returned so, with the smallest radius of an admissible stride at that
        (L, T, alpha) in its ``hint``; ``stability``: with the stride's open-loop multipliers (they
        cost about what the solve does)."""
        problem = self._validate(request)
        if not math.isfinite(problem.turn_radius):
            raise ValueError("a straight gait is one step: plan it with plan")
        start = time.perf_counter()
        stride = None
        atlas = self.turning_atlas(problem.mode) if guess is None else None
        point = (problem.step_length, problem.period, problem.arm_amplitude, 1.0 / problem.turn_radius)
        if atlas is not None and (atlas_guess := atlas.guess(point)) is not None:
            stride = self._stride(problem, atlas_guess, "atlas", stability)
            if not (stride.converged and _stride_near(stride, atlas_guess)):
                stride = None
        path: list[tuple[float, StrideGuess]] = []
        if stride is None and guess is not None:
            stride = self._stride(problem, guess, "guess", stability)
            resumable = guess_curvature is not None and guess_curvature != point[3]  # a continuation has a span
            if resumable and not (stride.converged and _stride_near(stride, guess)):
                resumed = self._curvature_path(problem, start=(guess_curvature, guess))[-1][1]
                stride = self._stride(problem, resumed, "continuation", stability)
        elif stride is None or not stride.admissible:
            straight = self.plan(replace(request, turn_radius=math.inf))
            if not straight.converged and stride is None:
                raise ValueError(f"no straight gait to turn from at this (L, T, alpha): {straight.message}")
            if straight.converged:
                path = self._curvature_path(problem, straight)
                reached = self._stride(problem, path[-1][1], "continuation", stability)
                if stride is None or reached.admissible:
                    stride = reached
        if not stride.admissible:
            smallest = atlas.smallest_radius(point[:3]) if atlas is not None and atlas.grid.contains(
                (*point[:3], abs(point[3]))) else None
            if smallest is not None:
                radius, (length, period, alpha) = smallest
                hint = (f"smallest admissible turn radius (turning atlas grid) at L = {length:g} m, T = {period:g} s, "
                        f"alpha = {math.degrees(alpha):.0f} deg: {radius:.3g} m")
            else:
                hint = self._radius_hint(problem, path or self._curvature_path(problem, self.plan(
                    replace(request, turn_radius=math.inf))))
            stride = replace(stride, hint=hint)
        return replace(stride, solve_time_s=time.perf_counter() - start)

    def turning_atlas(self, mode: GaitMode) -> TurningAtlas | None:
        """The current turning atlas of these parameters and ``mode`` (loaded once), or None (no
        lateral hips, no atlas, or a stale one: said once, as for ``atlas``)."""
        from .turning_atlas import TurningAtlas, turning_atlas_path  # strides only: a straight plan does without

        if mode not in self._turning_atlases:
            atlas = None
            if self.use_atlas and self.params.joints.lateral_hips:
                try:
                    atlas = TurningAtlas.load(turning_atlas_path(self.params, mode), self.params, self.source)
                except AtlasError as exc:
                    self._note(f"{exc}; planning strides without it ({mode.value} gaits)")
            self._turning_atlases[mode] = atlas
        return self._turning_atlases[mode]

    def _stride(self, problem: GaitProblem, guess: StrideGuess, found: str, stability: bool = True) -> Stride:
        """The stride of ``problem`` solved from ``guess``, on a grid that meets the accuracy
        contract (``_refining``), with its multipliers if ``stability``."""
        return self._refining(lambda grid, start, coarser: self._stride_on(grid, problem, start, found, stability,
                                                                          coarser), guess)

    def _stride_on(self, grid: PlanGrids, problem: GaitProblem, guess: StrideGuess, found: str, stability: bool,
                   coarser: Stride | None = None, estimate: bool = True) -> Stride:
        """The stride of ``problem`` solved from ``guess`` on ``grid``, its closures matched
        to what the spin moments do (legs leaning), with its steps' integration errors if
        ``estimate`` (against ``coarser``, the stride on the estimate's grid, if solved already;
        else solved again there from this one) and its multipliers if ``stability``."""
        from .stride import StrideProblem, solve_stride  # strides only: a straight plan does without

        stride = StrideProblem(problem.step_length, problem.period, problem.arm_amplitude, problem.mode,
                               problem.turn_radius)

        def solve(on: BallisticFlow, coarse: BallisticFlow | None, start: StrideGuess, targets: tuple[float, float],
                  settings: Settings = self.settings):
            return solve_stride(self.hybrid, on, stride, start, settings, coarse, targets)

        targets = np.zeros(2)
        closure = _ClosureRounds()
        for _ in range(CLOSURE_ROUNDS):
            solution = solve(grid.flow, grid.coarse, guess, tuple(targets))
            a, b = solution.steps
            steps = (self.step_gait(problem, a, found, b.qd_a), self.step_gait(problem, b, found, a.qd_a))
            if not all(g.double_support is not None and g.double_support.impulses.success for g in steps):
                break
            asked = np.array([-g.double_support.foot_line_moment for g in steps])
            if max(abs(g.step.closure_gap - t) for g, t in zip(steps, asked)) <= self.settings.tolerance:
                break
            targets = closure.next(targets, asked)
            guess = (a.qd_a, a.theta, b.qd_a, b.theta)
        else:  # the rounds ran out: no consistent double supports (the LPs flip between vertices)
            steps = (self._unsettled(problem, a, found, b.qd_a), self._unsettled(problem, b, found, a.qd_a))
        if estimate and all(g.converged for g in steps):
            def again() -> tuple[Gait, ...]:
                ca, cb = solve(grid.estimate, None, (a.qd_a, a.theta, b.qd_a, b.theta), (a.closure_gap, b.closure_gap),
                               self._estimate_settings).steps
                return self.step_gait(problem, ca, found, cb.qd_a), self.step_gait(problem, cb, found, ca.qd_a)

            steps = self._estimated(grid, problem, steps, coarser and coarser.steps, again)
        multipliers = None
        if stability and all(g.double_support is not None and g.double_support.impulses.success for g in steps):
            maps = [PoincareMap(self.hybrid, grid.flow, problem.period, g.double_support.impulses.i_minus,
                                g.double_support.impulses.i_plus) for g in steps]
            jacobians = [m.jacobian(np.concatenate([g.step.q0, g.step.qd_a])) for m, g in zip(maps, steps)]
            multipliers = multipliers_of(jacobians[1] @ jacobians[0])
        return Stride(problem.turn_radius, steps, multipliers, math.nan, found)

    def _radius_hint(self, problem: GaitProblem, path: list[tuple[float, StrideGuess]]) -> str:
        """The smallest radius (m) of an admissible stride along the continuation ``path`` (its
        curvatures, 1/m, and strides, from the straight gait towards the request's), by bisection
        (``RADIUS_BISECTIONS`` halvings of the last interval), in words. The strides it tries are
        probes on the planner's grid, read for their admissibility only: no estimate, no refinement."""
        where = (f"L = {problem.step_length:g} m, T = {problem.period:g} s, "
                 f"alpha = {math.degrees(problem.arm_amplitude):g} deg")

        def admissible(curvature: float, guess: StrideGuess) -> Stride | None:
            stride = self._stride_on(self.grid, replace(problem, turn_radius=1.0 / curvature), guess, "continuation",
                                     False, estimate=False)
            return stride if stride.admissible else None

        low, high = 0, len(path)  # path[:low] admissible (the straight gait is), path[high:] not
        while low < high:
            middle = (low + high) // 2
            if admissible(*path[middle]) is not None:
                low = middle + 1
            else:
                high = middle
        if low == 0:
            return f"no admissible stride on a circle at {where} (the straight gait's neighbourhood included)"
        good, guess = path[low - 1]
        bad = path[low][0] if low < len(path) else 1.0 / problem.turn_radius
        for _ in range(RADIUS_BISECTIONS):
            middle = 0.5 * (good + bad)
            stride = admissible(middle, guess)
            if stride is not None:
                a, b = stride.steps
                good, guess = middle, (a.qd_a, a.theta, b.qd_a, b.theta)
            else:
                bad = middle
        return f"smallest turn radius of an admissible stride at {where}: {abs(1.0 / good):.3g} m"

    def _curvature_path(self, problem: GaitProblem, straight: Gait | None = None,
                        start: tuple[float, StrideGuess] | None = None) -> list[tuple[float, StrideGuess]]:
        """To the stride of radius R from the ``straight`` gait, or from ``start`` = (curvature
        1/m, its stride): continuation in the curvature 1 / R, each step on the coarse grid
        warm-started from the last, halved where it fails or jumps (``continuation.BRANCH_JUMP``);
        the curvatures (1/m) reached and their strides, the last nearest the request's (the
        start's first: the straight gait's at a vanishing curvature, if no step succeeds)."""
        from .stride import StrideProblem, solve_stride

        target = 1.0 / problem.turn_radius
        if start is None:
            origin, guess = 0.0, (straight.qd_a, straight.theta, straight.qd_a, straight.theta)
            path = [(MIN_CURVATURE_STEP * target / abs(target), guess)]
        else:
            origin, guess = start
            path = [start]
        span = target - origin
        coarse = replace(self.settings, tolerance=max(self.settings.tolerance, self.settings.coarse_tolerance),
                         max_iterations=STEP_ITERATIONS)
        flow = self.coarse_flow or self.flow
        curvature, step = origin, min(1.0, CURVATURE_STEP / abs(span))
        while curvature != target and step * abs(span) >= MIN_CURVATURE_STEP:
            trial = curvature + step * span
            if (trial - target) * span > 0:
                trial = target
            on_path = StrideProblem(problem.step_length, problem.period, problem.arm_amplitude, problem.mode,
                                    1.0 / trial)
            solution = solve_stride(self.hybrid, flow, on_path, guess, coarse)
            a, b = solution.steps
            if solution.converged and max(np.max(np.abs(a.qd_a - guess[0])), np.max(np.abs(b.qd_a - guess[2]))) <= BRANCH_JUMP:
                curvature, guess = trial, (a.qd_a, a.theta, b.qd_a, b.theta)
                path.append((curvature, guess))
                step = min(2.0 * step, CURVATURE_STEP / abs(span))
            else:
                step *= 0.5
        return path

    def _find(self, problem: GaitProblem) -> Gait:
        """The gait of ``problem`` on the human-like branch: atlas, then continuation, then cold;
        a refusal with its hint (``_hinted``)."""
        point = (problem.step_length, problem.period, problem.arm_amplitude)
        atlas = self.atlas(problem.mode)
        if atlas is not None and problem.margins:
            atlas = atlas.within(problem.margins, problem.options.friction)
        first = None
        guess = atlas.guess(point) if atlas is not None else None
        if guess is not None:
            first = self._solve(problem, guess, "atlas", atlas.grid_steps(point))
            if not _near(first, guess):
                first = None
            elif first.admissible or not atlas.admissible_near(point):
                return self._hinted(first, atlas, problem)
        origin = self._origin(problem, atlas)
        if origin is not None:
            guess = continue_to(self.hybrid, self.coarse_flow or self.flow, self.settings, origin[0], origin[1],
                                problem.bvp())
            if guess is not None:
                gait = self._solve(problem, guess, "continuation")
                if gait.converged and (gait.admissible or first is None):
                    return self._hinted(gait, atlas, problem)
        if first is not None:
            return self._hinted(first, atlas, problem)
        return self._hinted(self._solve(problem, None, "cold"), atlas, problem)

    def _origin(self, problem: GaitProblem, atlas: Atlas | None):
        """Where a continuation to ``problem`` starts: the nearest admissible atlas node, else
        the human-like gait at ``SEED``, solved cold; as ((L, T, alpha), (qd(0), theta)), or None
        if that fails."""
        point = (problem.step_length, problem.period, problem.arm_amplitude)
        index = atlas.nearest(point) if atlas is not None else None
        if index is not None:
            return atlas.grid.point(index), (atlas.nodes["qd_a"][index], float(atlas.nodes["theta"][index]))
        step = solve_bvp(self.hybrid, self.flow, StepProblem(*SEED, problem.mode, problem.closure), None, self.settings,
                         self.coarse_flow)
        return (SEED, (step.qd_a, step.theta)) if step.converged else None

    def _hinted(self, gait: Gait, atlas: Atlas | None, problem: GaitProblem) -> Gait:
        """``gait``, with a hint if it is refused: a region of admissible gaits that holds the
        request's other fields (the atlas's periods, if the atlas was built for those fields;
        else periods solved at them, ``_solved_hint``), which does not hold the refused one."""
        if gait.admissible or atlas is None:
            return gait
        differ = self._beyond_atlas(problem)
        point = (problem.step_length, problem.period, problem.arm_amplitude)
        return replace(gait, hint=self._solved_hint(gait, problem, atlas, differ) if differ else atlas.hint(point))

    def _beyond_atlas(self, problem: GaitProblem) -> str:
        """The fields of ``problem`` the atlases were not built for (theirs: a request's defaults),
        said as a user gives them; '' if none."""
        built = validate_request(GaitRequest(problem.step_length, problem.period, problem.arm_amplitude,
                                             problem.mode), self.params)
        options, default = problem.options, built.options
        fields = [(problem.step_width != built.step_width, f"step width {problem.step_width:.3f} m"),
                  (problem.closure != built.closure, f"closure {problem.closure}"),
                  (problem.effort != built.effort, f"effort {problem.effort}"),
                  (options.friction != default.friction, f"friction {options.friction:g}"),
                  (options.rate_bound != default.rate_bound, f"joint-rate bound {options.rate_bound:g} rad/s"),
                  (options.coordinates != default.coordinates, f"effort on {options.coordinates} angles")]
        return ", ".join(text for differs, text in fields if differs)

    def _solved_hint(self, gait: Gait, problem: GaitProblem, atlas: Atlas, differ: str) -> str:
        """The hint of a refusal whose fields ``differ`` from the atlas's: the gaits at the atlas's
        periods at the request's L, alpha and other fields, solved by continuation in T from the
        refused ``gait`` each way (a way ends where a solve does not converge), their admissible
        runs without the refused period."""
        periods = atlas.grid.periods
        admissible = np.zeros(len(periods), dtype=bool)
        for way in (1.0, -1.0):
            guess = gait.warm_start()
            for j in sorted((j for j in range(len(periods)) if way * (periods[j] - problem.period) > 1e-9),
                            key=lambda j: way * periods[j]):
                if guess is None:
                    break
                solved = self._solve(replace(problem, period=float(periods[j])), guess, "continuation")
                admissible[j], guess = solved.admissible, solved.warm_start()
        what = "within the margins" if problem.margins else "admissible"
        where = f"L = {problem.step_length:.3f} m, alpha = {math.degrees(problem.arm_amplitude):.0f} deg, {differ}"
        runs = period_runs(periods, admissible, problem.period)
        if runs:
            return f"nearest {what} (solved along T from this gait): {runs} at {where}"
        return (f"no {what} gait along T from this gait, at the atlas's periods in [{periods[0]:.3f}, "
                f"{periods[-1]:.3f}] s, at {where}")

    def _solve(self, problem: GaitProblem, guess: tuple[np.ndarray, float] | None, found: str,
               steps: int = 0) -> Gait:
        """The gait of ``problem`` solved from ``guess`` (None: the straight-line start), on a grid
        that meets the accuracy contract (``_refining``), from ``steps`` per T (the atlas's; 0:
        the planner's own grid)."""
        return self._refining(lambda grid, start, coarser: self._solve_on(grid, problem, start, found, coarser), guess,
                              self._grid(steps))

    def _grid(self, steps: int) -> PlanGrids:
        """The planner's grid, or one of ``steps`` per T if that is finer (Newton's iterations on
        half as many)."""
        if steps <= self.grid.steps:
            return self.grid
        if steps not in self._refined:
            self._refined[steps] = PlanGrids.of(self.hybrid, steps, steps // 2)
        return self._refined[steps]

    def _refining(self, solve: Callable[[PlanGrids, Any, Any], Gait | Stride], guess: Any, grid: PlanGrids | None = None
                  ) -> Gait | Stride:
        """``solve(grid, guess, None)`` on ``grid`` (default: the planner's), and again on grids of
        twice as many steps (up to ``REFINEMENTS`` doublings of the planner's grid, each from the
        last solution, which is also what its estimate compares with) while it converges but its
        estimated integration error exceeds the contract (a refined solve that fails leaves the
        last one, its estimate saying it misses it)."""
        grid = grid or self.grid
        result = solve(grid, guess, None)
        while grid.steps < self.grid.steps << REFINEMENTS:
            if not result.converged or result.meets_contract:
                break
            grid = self._grid(2 * grid.steps)
            refined = solve(grid, result.warm_start(), result)
            if not refined.converged:
                break
            result = refined
        return result

    def _solve_on(self, grid: PlanGrids, problem: GaitProblem, guess: tuple[np.ndarray, float] | None,
                  found: str, coarser: Gait | None = None) -> Gait:
        """The gait of ``problem`` solved from ``guess`` on ``grid``, with its integration error
        (against ``coarser``, the gait on the estimate's grid, if solved already)."""
        shooting = SpeculativeFlow(grid.flow, grid.background)
        step = solve_bvp(self.hybrid, shooting, problem.bvp(), guess, self.settings, grid.coarse, with_coarse=True)
        flow = self._variational_flow(problem, step, shooting)
        gait = self.step_gait(problem, step, found)
        for _ in range(CLOSURE_ROUNDS):  # legs leaning: the closure matched to what the spin moments do
            ds = gait.double_support
            if problem.closure != "theta" or ds is None or not ds.impulses.success or \
                    abs(ds.foot_line_moment) <= self.settings.tolerance or \
                    abs(step.closure_gap + ds.foot_line_moment) <= self.settings.tolerance:
                break  # nothing to match: the spin moments change nothing (or the closure already matches)
            shooting = SpeculativeFlow(grid.flow, grid.background)
            step = solve_bvp(self.hybrid, shooting, problem.bvp(-ds.foot_line_moment), (step.qd_a, step.theta),
                             self.settings, grid.coarse, with_coarse=True)
            flow = self._variational_flow(problem, step, shooting)
            gait = self.step_gait(problem, step, found)
        else:
            gait = self._unsettled(problem, step, found)
        if gait.converged:
            gait = self._integration_error(grid, problem, gait, coarser)
        if gait.double_support is not None and gait.double_support.impulses.success:
            gait = replace(gait, stability=self._multipliers(grid, problem, step, gait.double_support.impulses, flow))
        return gait

    def _integration_error(self, grid: PlanGrids, problem: GaitProblem, gait: Gait, coarser: Gait | None) -> Gait:
        """``gait``, solved on ``grid``, with its integration error: against ``coarser``, the gait
        on the estimate's grid, or (None) its step's solution on that grid (the shooting's coarse
        one, else its step solved again there from its own solution, with the same closure),
        its double support's LP started from the plan's basis (``_estimated``)."""
        def again() -> tuple[Gait]:
            step, near = gait.step, gait.double_support and gait.double_support.impulses
            if step.coarse is None:  # a grid without a coarse flow (its estimate's is then half of it)
                step = solve_bvp(self.hybrid, grid.estimate, problem.bvp(step.closure_gap), (step.qd_a, step.theta),
                                 self._estimate_settings, None)
            else:
                step = step.coarse
            return self.step_gait(problem, step, gait.found, near=near),

        return self._estimated(grid, problem, (gait,), coarser and (coarser,), again)[0]

    @property
    def _estimate_settings(self) -> Settings:
        """The settings of a plan solved again on its estimate's grid (``ESTIMATE_ITERATIONS``)."""
        return replace(self.settings, max_iterations=ESTIMATE_ITERATIONS)

    def _estimated(self, grid: PlanGrids, problem: GaitProblem, plans: tuple[Gait, ...],
                   coarse: tuple[Gait, ...] | None, again: Callable[[], tuple[Gait, ...]]) -> tuple[Gait, ...]:
        """The steps of a plan (``plans``, on ``grid``) with their integration errors
        (``richardson``): against ``coarse``, the same steps on the estimate's grid, if solved
        already; else against ``again()``, the plan solved again there, unless an end point already
        misses the contract (the plan is then refined: its figures' errors are not estimated)."""
        ends = [grid.estimate.propagate(plan.step.q0, plan.step.qd_a, problem.period).q for plan in plans]
        if coarse is None and all(richardson.end_point(plan, end, grid.ratio) <= END_POINT_BOUND
                                  for plan, end in zip(plans, ends)):
            coarse = again()
        return tuple(replace(plan, accuracy=richardson.estimate(plan, other, end, grid.ratio))
                     for plan, other, end in zip(plans, coarse or (None,) * len(plans), ends))

    def _multipliers(self, grid: PlanGrids, problem: GaitProblem, step: BvpSolution, impulses: ImpulseSolution,
                     flow: Future[FlowResult]) -> Multipliers:
        """The open-loop multipliers of the solved ``step`` with its ``impulses``, from ``flow``,
        the step's variational flow on ``grid`` begun on the background thread (waited for here)."""
        return open_loop(self.hybrid, grid.flow, problem.period, step.q0, step.qd_a, impulses.i_minus,
                         impulses.i_plus, flow.result())

    def _variational_flow(self, problem: GaitProblem, step: BvpSolution,
                          shooting: SpeculativeFlow) -> Future[FlowResult] | None:
        """The step's full-state variational flow (for its multipliers) on the background thread,
        begun at the shooting's last chord step (``shooting``) or now, while the double support
        is solved; None if the step did not converge."""
        return shooting.variational_flow(problem.period, step.q0, step.qd_a) if step.converged else None

    def _unsettled(self, problem: GaitProblem, step: BvpSolution, found: str,
                   next_qd_a: np.ndarray | None = None) -> Gait:
        """The gait of a step whose closure did not settle on what its double support's spin
        moments change in ``CLOSURE_ROUNDS`` rounds: not converged, saying so."""
        message = (f"the closure does not settle on what the double support's spin moments change (legs leaning; "
                   f"{CLOSURE_ROUNDS} rounds)")
        return self.step_gait(problem, replace(step, converged=False, message=message), found, next_qd_a)

    def step_gait(self, problem: GaitProblem, step: BvpSolution, found: str,
                  next_qd_a: np.ndarray | None = None, near: ImpulseSolution | None = None) -> Gait:
        """The gait of one solved ballistic step: its double support towards ``next_qd_a`` (the next
        step's initial velocity, its own coordinates; default the step's own: a periodic gait), its
        LP started from the basis of ``near``'s (a nearby double support's), its figures and the
        verdict; no stability."""
        double_support = figures = None
        within_limits = None
        if step.converged:
            double_support, within_limits = self._double_support(step, problem,
                                                                 step.qd_a if next_qd_a is None else next_qd_a, near)
            figures = self._figures(step, problem.period)
        impulses = double_support.impulses if double_support else None
        verdict = with_margins(judge(step, impulses, figures, problem.options.friction,
                                     self.params.joints.role("knee").limits.lower),
                               impulses, figures, problem.options.friction, problem.margins, within_limits)
        return Gait(problem, self.model.coordinate_names, step, double_support, figures, verdict, math.nan, found)

    def _double_support(self, step: BvpSolution, problem: GaitProblem, next_qd_a: np.ndarray,
                        near: ImpulseSolution | None = None) -> tuple[DoubleSupport, ImpulseSolution | None]:
        """The double support towards ``next_qd_a`` with the impulses under the request's
        margins, and, when those have no solution but the margins narrow the impulse problem, the
        impulses under the limits alone (else None)."""
        bm = self.model
        q_t = step.q_target
        impact = self.hybrid.impact(q_t)
        lp = impact.problem(step.qd_b, next_qd_a)
        slack = 0.0
        if problem.closure == "slack":
            # Paper comparison: theta = 0 and the smallest change of Xd^a along z_d that makes
            # eqs. (6)-(10) consistent.
            lp, slack = lp.reachable()
        sol = solve_impulses(lp, problem.effort, problem.impulse_options, near and near.basis)
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
            speed_after = float(np.linalg.norm(lp.j2[:3] @ xd_a))
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
            impulse_friction_ratios=friction_ratios(sol),
            max_intermediate_joint_rate=float(np.max(np.abs(sol.joint_rates))),
            heading_change=self.hybrid.exchange.heading(q_t),
            foot_line_moment=sol.foot_line_moment(lp) if sol.success else 0.0,
        ), within_limits

    def _figures(self, step: BvpSolution, period: float) -> StepFigures:
        times = np.linspace(0.0, period, self.settings.samples)
        q, qd = hermite_samples(step.nodes, times)
        samples = self.hybrid.samples
        return step_figures(samples, times, q, qd, period, energy_drift(samples, step.nodes[1], step.nodes[2]))


class _ClosureRounds:
    """Broyden's method on a stride's closure targets t (kg m^2/s, at C1 and C2): r(t) = what
    the LPs' spin moments ask - t, from the Jacobian -I (the first step is the plain fixed point
    t = ask: the ask depends little on t); the LPs are piecewise linear, so two or three rounds
    past the first reach 1e-12 where the plain fixed point takes six."""

    def __init__(self) -> None:
        self.jacobian = -np.eye(2)
        self.last: tuple[np.ndarray, np.ndarray] | None = None

    def next(self, targets: np.ndarray, asked: np.ndarray) -> np.ndarray:
        """The next targets after a round at ``targets`` whose LPs asked ``asked``."""
        residual = asked - targets
        if self.last is not None:
            step, change = targets - self.last[0], residual - self.last[1]
            if step @ step > 0:
                self.jacobian += np.outer(change - self.jacobian @ step, step) / (step @ step)
        self.last = (targets, residual)
        return targets - np.linalg.solve(self.jacobian, residual)


def _stride_near(stride: Stride, guess: StrideGuess) -> bool:
    """Whether the solved ``stride`` stayed on the branch of its warm start (``BRANCH_BOUND``)."""
    a, b = stride.steps
    return max(float(np.max(np.abs(a.qd_a - guess[0]))), float(np.max(np.abs(b.qd_a - guess[2])))) <= BRANCH_BOUND


def _near(gait: Gait, guess: tuple[np.ndarray, float]) -> bool:
    """Whether a solve stayed near its warm start (on the warm start's branch)."""
    return gait.converged and float(np.max(np.abs(gait.step.qd_a - guess[0]))) <= BRANCH_BOUND
