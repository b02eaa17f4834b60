"""Starting a walk from standing and stopping it standing (docs/model.md section 8.10).

The double support is instantaneous and the feet are points: the ground's impulses act at the two
feet, the joint impulses are internal, so the angular momentum about the line through both feet
(the feet line) is the same after a double support as before it (``ImpactMap.momentum_row``;
legs leaning with hip joints aside, section 5.2). A gait carries 8 to 21 kg m^2/s of it, so no
single double support takes the robot from rest onto a gait, or from a gait to rest. A start and
a stop each take one ballistic step of their own between two double supports:

- **Stop** (``plan_stop``). The gait's double support at a touchdown gives the stop step any
  initial velocity v (rad/s, the step's own model coordinates) that keeps the touchdown's
  feet-line momentum; the stop step flies for a free duration T_s (s) to a standing
  configuration, the gait's boundary configuration q(T) at a free step length L_s (m) and a
  given trunk pitch (``Pose``), and arrives with ZERO momentum about its new feet line; a last
  double support brings everything to rest (the effort LP with Xd^a = 0). nq + 2 unknowns
  (v, T_s, L_s), nq + 2 equations (the momentum kept, q(T_s) = the standing configuration, zero
  arrival momentum).
- **Start** (``plan_start``). From rest in the standing configuration at the gait's step length
  and a free trunk pitch theta_s, a double support from rest gives the start step a velocity of
  zero feet-line momentum; the start step flies for a free duration to the gait's touchdown
  configuration q_T and arrives with the gait's feet-line momentum M_p, so that the gait's own
  double support then takes it onto the gait. Unknowns (v, T_s, theta_s).

Both are solved by Newton's method with a homotopy on the momentum, from the gait's value (where
the gait's own step is the solution) to zero. Each double support is chosen by the walk's effort
LP (``solve_impulses``: vertical reactions >= 0, the floor's friction cone) and each step is
judged as a gait's step is (ground reaction, clearance, knee, friction, arrival from above); what
fails is refused (``StartStopError``) with its reason and numbers.

A necessary condition explains most refusals (``com_friction``): the reaction impulses of a
double support sum to the change of the linear momentum, and each lies in the friction cone, so
the centre of mass's velocity can change by Delta v only with Delta v_z >= 0 and |Delta v_xy| <=
mu Delta v_z. Stopping asks the CoM to arrive falling at least 1 / mu times faster than it moves
horizontally; starting from rest gives it at most mu times more horizontal than upward speed.

Configurations in rad, velocities in rad/s, in the model coordinates (stance leg 1 on the right,
its tip at the origin) of the step they belong to; a standing configuration is in the coordinates
of the step that ends in it (its stance tip, the back foot, at the origin; the front foot at
(L, w, 0)). Durations in s, momenta in kg m^2/s, impulses in N m s and N s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..dynamics import newton
from ..dynamics.flow import BallisticFlow, FlowResult, hermite_samples
from ..dynamics.hybrid import HybridStep
from ..dynamics.impulses import ImpulseSolution, friction_ratios, solve_impulses
from ..gait.admissibility import describe, figure_limits
from ..gait.configurations import boundary_configurations
from ..gait.figures import StepFigures, energy_drift, step_figures
from .steering import momentum_row, pelvis_pitch
from .orbit import PlannedOrbit

TOLERANCE = 1e-12  # rad, kg m^2/s: the walker's re-aim's
NEWTON_ITERATIONS = 30
FIRST_STAGE = 0.125  # the homotopy's first step in its parameter (0: the gait's momentum, 1: zero)
SMALLEST_STAGE = 1.0 / 64
FD_STEP = 1e-6  # m, rad: central differences in the free pose parameter
SAMPLES = 91  # samples of a start or stop step for its figures


class StartStopError(Exception):
    """A start or a stop cannot be made: the message says which part failed and why."""


@dataclass(frozen=True)
class Pose:
    """A standing double-support configuration: the gait's boundary configuration q(T) at step
    length ``step_length`` (m: the front foot that far ahead of the back one, the hips' spacing
    apart) and trunk pitch ``theta`` (rad, + forward), the gait's arm amplitude and mode."""

    step_length: float
    theta: float


def pose_configuration(hybrid: HybridStep, orbit: PlannedOrbit, pose: Pose) -> np.ndarray:
    """q (rad) of ``pose`` with ``orbit``'s arms, in the coordinates of the step ending in it.
    ``StartStopError`` if the legs cannot reach (L >= 2 l)."""
    reach = 2.0 * hybrid.bm.params.leg_length
    if not abs(pose.step_length) < reach:
        raise StartStopError(f"a standing step length of {pose.step_length:.3f} m is beyond the legs' reach "
                             f"({reach:.3f} m)")
    return boundary_configurations(hybrid.bm)(pose.step_length, orbit.arm_amplitude, orbit.mode, pose.theta)[1]


@dataclass(frozen=True, eq=False)
class BallisticStep:
    """One start or stop step: from the double support at ``q_from`` (in the coordinates of the
    step before) with initial velocity ``qd_a`` (rad/s, its own coordinates, starting at ``q0``)
    for ``duration`` (s) to ``q_to`` with velocity ``qd_b``; its figures (``gait.figures``)."""

    q_from: np.ndarray
    q0: np.ndarray
    qd_a: np.ndarray
    duration: float
    q_to: np.ndarray
    qd_b: np.ndarray
    figures: StepFigures

    def reasons(self, friction: float, knee_lower: float) -> list[str]:
        """Why the step cannot be walked (none: it can): its figures' violated conditions."""
        f = self.figures
        values = (f.min_grf_z, f.min_swing_height, f.q9_min, f.max_friction_ratio, friction,
                  f.min_late_swing_height, f.swing_arrival_speed)
        return describe(figure_limits(*values, knee_lower), *values)


@dataclass(frozen=True, eq=False)
class StartStopSupport:
    """A double support of a start or a stop at ``q`` (rad) from ``qd_b`` (this step's, rad/s) to
    the next step's ``qd_a`` (zero for a stop's last): the LP's impulses, the friction each
    reaction impulse needs, and the next step's velocity after running the impulses forward
    (``ImpactMap.forward``; at rest, zero to rounding)."""

    q: np.ndarray
    qd_b: np.ndarray
    qd_a: np.ndarray
    impulses: ImpulseSolution
    friction_ratios: np.ndarray
    after: np.ndarray

    @property
    def W(self) -> float:
        """The effort sum |I^-| + |I^+| (N m s)."""
        return self.impulses.W


@dataclass(frozen=True, eq=False)
class StopPlan:
    """A stop: the stop step from the touchdown to the standing ``pose``, and the double support
    that brings the robot to rest there (``rest``)."""

    pose: Pose
    step: BallisticStep
    rest: StartStopSupport


@dataclass(frozen=True, eq=False)
class StartPlan:
    """A start: from rest in ``pose``, the double support ``launch`` and the start step to the
    gait's touchdown configuration, where it arrives with the gait's feet-line momentum."""

    pose: Pose
    launch: StartStopSupport
    step: BallisticStep


class _Leg:
    """A start or stop step as equations in x = (v, tau, p): from the double support at
    ``q_from(p)`` (the step starts at its leg exchange) with velocity v (rad/s) for duration tau
    (s) to ``q_to(p)``; p the free pose parameter (m or rad). The feet-line momentum v carries
    out of the first double support is ``start``, the one it arrives with ``end`` (kg m^2/s)."""

    def __init__(self, hybrid: HybridStep, flow: BallisticFlow, q_from: Callable[[float], np.ndarray],
                 q_to: Callable[[float], np.ndarray], start: float, end: float) -> None:
        self.hybrid, self.flow, self.q_from, self.q_to, self.start, self.end = hybrid, flow, q_from, q_to, start, end

    def _residual(self, x: np.ndarray, jacobian: bool) -> tuple[np.ndarray, np.ndarray | None]:
        """F (nq + 2): q(tau) - q_to, the momentum out of the first double support less ``start``,
        the arrival momentum less ``end``; with ``jacobian``, dF / d(v, tau)."""
        hybrid, n = self.hybrid, self.hybrid.bm.nq
        v, tau, p = x[:n], float(x[n]), float(x[n + 1])
        if not tau > 0:
            return np.full(n + 2, np.nan), None
        try:
            q_from, q_to = self.q_from(p), self.q_to(p)
        except StartStopError:
            return np.full(n + 2, np.nan), None
        gain = hybrid.impact(q_from).closure_gradients()[0]
        seeds = np.vstack([np.zeros((n, n)), np.eye(n)]) if jacobian else None
        with np.errstate(over="ignore", invalid="ignore"):
            run: FlowResult = self.flow.propagate(hybrid.exchange.configuration(q_from), v, tau, seeds)
        row = momentum_row(hybrid, q_to)
        f = np.concatenate([run.q - q_to, [gain @ v - self.start, row @ run.qd - self.end]])
        if not jacobian or not np.all(np.isfinite(f)):
            return f, None
        jac = np.zeros((n + 2, n + 1))
        jac[:n, :n], jac[:n, n] = run.sens[:n], run.qd
        jac[n, :n] = gain
        jac[n + 1, :n], jac[n + 1, n] = row @ run.sens[n:], row @ self.flow.acceleration(run.q, run.qd)
        return f, jac

    def __call__(self, x: np.ndarray, jacobian: bool):
        """Newton's residual: F, dF/dx (exact in (v, tau), by central differences in p), None."""
        f, jac = self._residual(x, jacobian)
        if jac is None:
            return f, None, None
        plus, minus = x.copy(), x.copy()
        plus[-1] += FD_STEP
        minus[-1] -= FD_STEP
        column = (self._residual(plus, False)[0] - self._residual(minus, False)[0]) / (2 * FD_STEP)
        return f, np.column_stack([jac, column]), None


def _homotopy(leg: _Leg, x0: np.ndarray, set_stage: Callable[[float], None], what: str, unknown: str) -> np.ndarray:
    """Solve ``leg`` at the homotopy parameter 1 from its solution ``x0`` at 0, ``set_stage``
    moving the momenta to a stage: each stage's Newton starts from the secant through the last two
    solutions; stages grow after a success and halve after a failure. ``StartStopError`` naming
    how far it got, and where the free pose parameter (``unknown``, in words) got to, if a stage
    smaller than ``SMALLEST_STAGE`` fails."""
    done, stage, x = 0.0, FIRST_STAGE, np.asarray(x0, float)
    previous: tuple[float, np.ndarray] | None = None
    while done < 1.0:
        trial = min(1.0, done + stage)
        set_stage(trial)
        guess = x if previous is None else x + (x - previous[1]) * (trial - done) / (done - previous[0])
        result = newton.newton(leg, guess, TOLERANCE, NEWTON_ITERATIONS)
        if result.converged:
            previous, done, x, stage = (done, x), trial, result.x, stage * 1.5
            continue
        stage *= 0.5
        if stage < SMALLEST_STAGE:
            n = leg.hybrid.bm.nq
            raise StartStopError(f"{what}: no step found beyond {100 * done:.0f} % of the way from the gait's feet-line "
                                 f"momentum to zero (there: T = {x[n]:.3f} s, {unknown(x[n + 1])}; "
                                 f"{result.message})")
    return x


def orbit_momentum(hybrid: HybridStep, orbit: PlannedOrbit) -> float:
    """M_p: the gait's feet-line momentum at its touchdown (kg m^2/s)."""
    return float(momentum_row(hybrid, np.asarray(orbit.q_t)) @ np.asarray(orbit.qd_b))


def orbit_theta(hybrid: HybridStep, orbit: PlannedOrbit) -> float:
    """theta_p: the trunk pitch of the gait's touchdown configuration (rad)."""
    return float(orbit.theta) if math.isfinite(orbit.theta) else pelvis_pitch(hybrid.bm, np.asarray(orbit.q_t))


def _straight(orbit: PlannedOrbit) -> None:
    if not math.isinf(orbit.turn_radius):
        raise StartStopError("starting and stopping are planned for straight gaits only (this one turns, "
                             f"R = {orbit.turn_radius:g} m)")


def plan_stop(hybrid: HybridStep, orbit: PlannedOrbit, grid: int) -> StopPlan:
    """The stop from a touchdown of the straight gait ``orbit``: the stop step to the standing pose
    at the gait's trunk pitch and a free step length L_s, arriving with zero feet-line momentum,
    and the double support to rest; ``grid`` RK8 steps per step (the walker's). Homotopy on the
    arrival momentum from the gait's (where the gait's own step, L_s = L, is the solution) to
    zero. ``StartStopError`` if no stop step is found, or it or a double support cannot be made."""
    _straight(orbit)
    q_t, m_p, theta = np.asarray(orbit.q_t), orbit_momentum(hybrid, orbit), orbit_theta(hybrid, orbit)
    leg = _Leg(hybrid, hybrid.flow(grid), lambda p: q_t, lambda p: pose_configuration(hybrid, orbit, Pose(p, theta)),
               m_p, m_p)

    def stage(s: float) -> None:
        leg.end = (1.0 - s) * m_p

    x = _homotopy(leg, np.concatenate([orbit.qd_a, [orbit.period, orbit.step_length]]), stage, "the stop",
                  lambda length: f"L_s = {length:.3f} m, the legs' reach {2 * hybrid.bm.params.leg_length:.3f} m")
    n = hybrid.bm.nq
    pose = Pose(float(x[n + 1]), theta)
    step = _judged(hybrid, orbit, leg.flow, q_t, x[:n], float(x[n]), pose_configuration(hybrid, orbit, pose),
                   f"the stop step to L_s = {pose.step_length:.3f} m")
    double_support(hybrid, orbit, q_t, np.asarray(orbit.qd_b), step.qd_a, "the double support into the stop step")
    rest = double_support(hybrid, orbit, step.q_to, step.qd_b, None, "the stop's double support to rest")
    return StopPlan(pose, step, rest)


def plan_start(hybrid: HybridStep, orbit: PlannedOrbit, grid: int) -> StartPlan:
    """The start onto the straight gait ``orbit`` from rest in the standing pose at the gait's step
    length and a free trunk pitch theta_s: the double support from rest, and the start step to
    the gait's touchdown configuration, arriving with the gait's feet-line momentum (the gait's
    double support then takes it onto the gait); ``grid`` RK8 steps per step. Homotopy on the
    start's momentum from the gait's (theta_s = theta_p, the gait's own step) to zero.
    ``StartStopError`` if no start step is found, or it or a double support cannot be made."""
    _straight(orbit)
    q_t, m_p, length = np.asarray(orbit.q_t), orbit_momentum(hybrid, orbit), orbit.step_length
    leg = _Leg(hybrid, hybrid.flow(grid), lambda p: pose_configuration(hybrid, orbit, Pose(length, p)), lambda p: q_t,
               m_p, m_p)

    def stage(s: float) -> None:
        leg.start = (1.0 - s) * m_p

    x = _homotopy(leg, np.concatenate([orbit.qd_a, [orbit.period, orbit_theta(hybrid, orbit)]]), stage, "the start",
                  lambda theta: f"theta_s = {math.degrees(theta):.1f} deg")
    n = hybrid.bm.nq
    pose = Pose(length, float(x[n + 1]))
    q_pose = pose_configuration(hybrid, orbit, pose)
    step = _judged(hybrid, orbit, leg.flow, q_pose, x[:n], float(x[n]), q_t,
                   f"the start step from theta_s = {math.degrees(pose.theta):.1f} deg")
    launch = double_support(hybrid, orbit, q_pose, np.zeros(n), step.qd_a, "the start's double support from rest")
    double_support(hybrid, orbit, q_t, step.qd_b, np.asarray(orbit.qd_a), "the double support onto the gait")
    return StartPlan(pose, launch, step)


def _judged(hybrid: HybridStep, orbit: PlannedOrbit, flow: BallisticFlow, q_from: np.ndarray, v: np.ndarray,
            tau: float, q_to: np.ndarray, what: str) -> BallisticStep:
    """The solved step with its figures, or ``StartStopError`` with the conditions it violates."""
    run = flow.propagate(hybrid.exchange.configuration(q_from), v, tau, keep_nodes=True)
    times = np.linspace(0.0, tau, SAMPLES)
    q, qd = hermite_samples(run.nodes, times)
    samples = hybrid.samples
    figures = step_figures(samples, times, q, qd, tau, energy_drift(samples, run.nodes[1], run.nodes[2]))
    step = BallisticStep(np.asarray(q_from), hybrid.exchange.configuration(q_from), np.asarray(v), tau,
                         np.asarray(q_to), run.qd, figures)
    reasons = step.reasons(orbit.options.friction, hybrid.bm.params.joints.role("knee").limits.lower)
    if reasons:
        raise StartStopError(f"{what} (T = {tau:.3f} s) cannot be walked: " + "; ".join(reasons))
    return step


def com_friction(hybrid: HybridStep, q: np.ndarray, xd_before: np.ndarray, xd_after: np.ndarray) -> float:
    """|Delta v_xy| / Delta v_z of the centre of mass across a double support at ``q`` from the
    double-support velocity ``xd_before`` to ``xd_after`` (rad/s, m/s): the least friction
    coefficient any double support making that change needs (the reactions sum to the change of
    the linear momentum, each within its cone); inf when Delta v_z <= 0 (the ground cannot pull)."""
    bm = hybrid.bm
    before, _, _ = bm.momentum(q, xd_before)
    after, _, _ = bm.momentum(q, xd_after)
    dv = (after - before) / bm.total_mass
    return float(math.hypot(dv[0], dv[1]) / dv[2]) if dv[2] > 0 else math.inf


def double_support(hybrid: HybridStep, orbit: PlannedOrbit, q: np.ndarray, qd_b: np.ndarray,
                   qd_a: np.ndarray | None, what: str) -> StartStopSupport:
    """The double support at ``q`` from ``qd_b`` (this step's, rad/s) to the next step's ``qd_a``
    (None: to rest, every velocity zero), its impulses by ``orbit``'s effort and options (the
    friction cone), made consistent by the least change along the locked rotation (rounding on a
    solved start or stop). ``StartStopError`` with the LP's reason, the friction the CoM's change
    of velocity needs at least and, where the LP without the cone is solvable, the friction it
    needs, if it has no solution."""
    impact = hybrid.impact(q)
    n = hybrid.bm.nq
    problem, _ = impact.problem(qd_b, np.zeros(n) if qd_a is None else qd_a).reachable()
    sol = solve_impulses(problem, orbit.effort, orbit.options)
    if not sol.success:
        needed = f"; the centre of mass's change of velocity alone needs mu >= " \
                 f"{com_friction(hybrid, q, problem.xd_b, problem.xd_a):.3g}"
        if math.isfinite(orbit.options.friction):
            free = solve_impulses(problem, orbit.effort, replace(orbit.options, friction=math.inf))
            needed += (f", the LP without the cone mu = {float(np.max(friction_ratios(free))):.3g}" if free.success
                       else ", and without the cone the LP has no solution either")
        raise StartStopError(f"{what}: no impulses ({sol.message}{needed}; the floor's mu = "
                             f"{orbit.options.friction:g})")
    after = impact.forward(qd_b, sol.i_minus, sol.i_plus)
    return StartStopSupport(np.asarray(q), np.asarray(qd_b), np.zeros(n) if qd_a is None else np.asarray(qd_a),
                            sol, friction_ratios(sol), after)


def why_not(kind: str, hybrid: HybridStep, orbit: PlannedOrbit, grid: int) -> str:
    """Why a walk of ``orbit`` cannot start from rest (``kind`` 'start') or stop at rest ('stop'):
    the refusal of ``plan_start`` / ``plan_stop``; or, where one is found, that the walker does
    not walk start and stop steps (none is found for the shipped parameter sets: docs/model.md
    section 8.10)."""
    plan = {"start": plan_start, "stop": plan_stop}[kind]
    try:
        found = plan(hybrid, orbit, grid)
    except StartStopError as exc:
        return str(exc)
    return (f"a {kind} step was found (T = {found.step.duration:.3f} s, pose L = {found.pose.step_length:.3f} m, "
            f"theta = {math.degrees(found.pose.theta):.1f} deg), but the walker does not walk {kind} steps")
