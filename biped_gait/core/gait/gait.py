"""One periodic gait, built once from typed immutable parts: the problem it solves, the
ballistic step (the BVP's solution), the double support, the step's figures, and the verdict.

SI units, angles in radians. Velocities in extended coordinates X = [x0, y0, z0, q1..q9] are in
the step's frame: stance leg 1 on the right, stance tip at the world origin. The JSON form, the
printed summary and the ROS message are views of a ``Gait`` (``views``, which imports this module;
this one imports no view), all driven by one field list.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .accuracy import IntegrationError
from .admissibility import Verdict, failure_message
from .bvp import BvpSolution, StepProblem
from .configurations import GaitMode
from ..dynamics.impulses import EffortOptions, ImpulseSolution
from ..model.biped import CoordinateNames
from .figures import StepFigures
from .margins import Margins
from .stability import Multipliers


@dataclass(frozen=True)
class GaitProblem:
    """A validated gait request: L (m), T (s), alpha (rad), mode, parameter set name, closure
    (``theta``/``slack``), effort (``l1``/``l2``), how the impulses are chosen (friction
    coefficient, joint-rate bound in rad/s, the effort's reading), step width (m, between the
    feet), turn radius (m, signed: positive turns left; inf: straight) and the margins asked."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode
    params: str
    closure: str
    effort: str
    options: EffortOptions
    step_width: float
    turn_radius: float = math.inf
    margins: Margins = Margins()

    @property
    def impulse_options(self) -> EffortOptions:
        """The options the double support's impulses are solved with: the friction cone at
        mu - the friction margin."""
        if not self.margins.friction:
            return self.options
        return replace(self.options, friction=self.options.friction - self.margins.friction)

    @property
    def limit_options(self) -> EffortOptions:
        """The options of the limits alone: the friction cone at mu, no joint-rate bound."""
        return replace(self.options, rate_bound=math.inf)

    def bvp(self, closure_target: float = 0.0) -> StepProblem:
        """The shooting problem of its step (``bvp.solve_bvp``), the closure gap made
        ``closure_target`` (kg m^2/s)."""
        return StepProblem(self.step_length, self.period, self.arm_amplitude, self.mode, self.closure,
                           self.step_width, closure_target)


@dataclass(frozen=True, eq=False)
class DoubleSupport:
    """The instantaneous double support of a gait (docs/model.md sections 4 and 6).

    ``impulses``: the solution of eqs. (6)-(10) (``success`` False: the LP/QP's reason);
    ``xd_b``, ``xd_a``: this step's end and the next step's start in this step's extended
    coordinates (after the slack correction, when that closure is used); ``slack``: s (rad/s);
    ``new_stance_foot``: the new stance tip (m); ``h_t_minus``/``h_t_plus``: yaw angular
    momentum (kg m^2/s) about the vertical through the old and the new stance foot, at T- and
    T+; the tip speeds (m/s) that the LP's sign constraints bound; the friction coefficient each
    reaction impulse needs (I_R1^-, I_R2, I_R2^+); the largest joint rate (rad/s, q3..q9) between
    the sub-phases, in Xd^- and Xd^+ (NaN when the impulse problem failed).
    """

    impulses: ImpulseSolution
    xd_b: np.ndarray
    xd_a: np.ndarray
    slack: float
    new_stance_foot: np.ndarray
    h_t_minus: tuple[float, float]
    h_t_plus: tuple[float, float]
    swing_tip_vz_before_impact: float
    old_stance_tip_vz_after_impact: float
    new_stance_tip_speed_after: float
    impulse_friction_ratios: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    max_intermediate_joint_rate: float = math.nan
    heading_change: float = 0.0  # rad: the next step's frame relative to this one's, mirrored (docs/model.md 5.2)
    foot_line_moment: float = 0.0  # kg m^2/s: what the ground's spin moments change of the feet-line momentum

    @property
    def yaw_momentum_jump(self) -> float:
        """|H(T+) - H(T-)| about the vertical through the new stance foot (kg m^2/s): what the
        impulses change in the yaw angular momentum, on one fixed axis."""
        return abs(self.h_t_plus[1] - self.h_t_minus[1])


@dataclass(frozen=True, eq=False)
class Gait:
    """A solved gait of a model whose vectors are ``names``: ``step`` always; ``double_support``
    and ``figures`` when the BVP converged; the ``verdict``; the solve's wall time (s); how it was ``found`` (``guess``: from
    the caller's warm start, ``atlas``: from the atlas's interpolated warm start,
    ``continuation``: by continuation from the nearest admissible gait, ``cold``: from the
    straight-line start); and, when it is not admissible, a ``hint`` of where admissible gaits are;
    the open-loop Floquet multipliers of its Poincare map (``stability``, when the double support
    was solved); the estimate of its integration error (``accuracy``, when the BVP converged)."""

    problem: GaitProblem
    names: CoordinateNames
    step: BvpSolution
    double_support: DoubleSupport | None
    figures: StepFigures | None
    verdict: Verdict
    solve_time_s: float
    found: str = "cold"
    hint: str = ""
    stability: Multipliers | None = None
    accuracy: IntegrationError | None = None

    # The request's figures, as every user of a gait reads them.
    step_length = property(lambda self: self.problem.step_length, doc="L (m)")
    period = property(lambda self: self.problem.period, doc="T (s)")
    arm_amplitude = property(lambda self: self.problem.arm_amplitude, doc="alpha (rad)")
    mode = property(lambda self: self.problem.mode, doc="the gait mode")
    params = property(lambda self: self.problem.params, doc="name of the parameter set")
    converged = property(lambda self: self.step.converged, doc="the ballistic BVP converged")
    admissible = property(lambda self: self.verdict.admissible, doc="the gait can be walked")
    within_limits = property(lambda self: self.verdict.admissible or not self.verdict.limits,
                             doc="the gait meets the limits (it may miss the margins asked)")
    reasons = property(lambda self: self.verdict.reasons, doc="why not, when not")
    theta = property(lambda self: self.step.theta, doc="trunk pitch at double support (rad)")
    qd_a = property(lambda self: self.step.qd_a, doc="qd(0) (rad/s)")

    @property
    def W(self) -> float:
        """The effort W = sum |I-| + |I+| (N m s); NaN when the double support has no solution."""
        return self.double_support.impulses.W if self.double_support is not None else math.nan

    @property
    def message(self) -> str:
        """What failed in the solve, "" when nothing did."""
        return failure_message(self.step, self.double_support.impulses if self.double_support else None)

    @property
    def usable(self) -> bool:
        """Converged, admissible, with a finite effort: a gait whose W counts in a study."""
        return self.converged and self.admissible and math.isfinite(self.W)

    @property
    def meets_contract(self) -> bool:
        """Solved, and its estimated integration error within the accuracy contract."""
        return self.accuracy is not None and self.accuracy.within_contract

    def warm_start(self) -> tuple[np.ndarray, float] | None:
        """The guess (qd(0), theta) a neighbouring solve can start from; None after a failure."""
        return (self.step.qd_a.copy(), self.step.theta) if self.converged else None

    def without_samples(self) -> "Gait":
        """This gait without its sampled trajectory and integration nodes, nor its step on the
        coarse grid (what studies keep)."""
        figures = self.figures.without_samples() if self.figures is not None else None
        return replace(self, step=replace(self.step, nodes=None, coarse=None), figures=figures)



@dataclass(frozen=True, eq=False)
class Stride:
    """A gait on a circle of radius ``radius`` (m, signed: positive turns left): a stride of two
    steps, A on the right foot and B on the left (each a ``Gait`` in its own model coordinates,
    without stability of its own), periodic modulo a yaw rotation of ``heading_change`` (rad);
    the open-loop multipliers of the stride's Poincare map (both steps, their impulses held
    fixed); the solve's wall time (s), how it was ``found`` (``continuation`` in curvature from
    the straight gait, ``atlas``, ``guess``), and, when it is not admissible, a ``hint``."""

    radius: float
    steps: tuple[Gait, Gait]
    stability: Multipliers | None
    solve_time_s: float
    found: str
    hint: str = ""

    problem = property(lambda self: self.steps[0].problem, doc="the request (step A's)")
    converged = property(lambda self: all(s.converged for s in self.steps))
    admissible = property(lambda self: all(s.admissible for s in self.steps))
    meets_contract = property(lambda self: all(s.meets_contract for s in self.steps),
                              doc="both steps solved within the accuracy contract")

    def warm_start(self) -> tuple[np.ndarray, float, np.ndarray, float] | None:
        """The guess (qd_A(0), theta_1, qd_B(0), theta_2) a neighbouring solve can start from;
        None after a failure."""
        a, b = self.steps
        return (a.qd_a.copy(), a.theta, b.qd_a.copy(), b.theta) if self.converged else None

    @property
    def reasons(self) -> tuple[str, ...]:
        return tuple(f"step {name} ({foot} foot): {reason}" for (name, foot), step in
                     zip((("A", "right"), ("B", "left")), self.steps) for reason in step.reasons)

    @property
    def W(self) -> float:
        """The effort of the stride's two double supports (N m s)."""
        return float(sum(s.W for s in self.steps))

    @property
    def heading_change(self) -> float:
        """The heading change per stride (rad, signed): 2 L / R."""
        return 2 * self.problem.step_length / self.radius
