"""Walking at a commanded speed and turn: transition steps between gaits (docs/model.md section 8.8).

``SpeedFollower`` holds the commanded speed v (m/s; clamped to the speed rule's admissible
range) and yaw rate omega (rad/s; as the curvature omega / v, clamped to ``max_curvature``,
turning models only) and, before each step of the walker, moves the gait the walker aims at one
transition towards the gait of that command, the rule's (``speed``) gait of speed v at the
walk's arm amplitude and mode on the circle of curvature omega / v: the speed of the aimed gait
changes by at most ``max_change`` (m/s) per step (an acceleration bound), its period by at most
``speed.MAX_SLOPE`` times that (s: as fast as the rule's own period changes with the speed, so
that a walk that starts off the rule's gaits, the plan's, joins them gradually), and its
curvature 1 / R by at most ``max_curvature_change`` (1/m); L = v T. A straight gait's periodic
orbit is solved by the shooting BVP (``bvp``, coarse Newton finished on the walker's grid)
warm-started from the gait atlas's interpolation (``Atlas.guess``), else from the secant through
the last two gaits solved (the gait aimed at so far, when there is one); a gait on a circle is a
stride of two steps (``GaitPlanner.plan_stride``) warm-started from the last stride (or the
straight gait), continued in the curvature from it when the solve leaves its branch. A gait
whose swing foot would come up to the touchdown from under the ground (``speed.walkable_nodes``)
is refused.

A transition whose gait's momentum about the feet line (which no impulse changes) differs from
the walked gait's by more than the walker's momentum steering follows in a step (``MAX_PITCH``
times its authority) is shrunk in proportion, so that the change is spread over more steps. A
transition that cannot be reached (not solved, or not admissible) is replaced by the nearest
one that can: the gaits a half and a quarter of the way to it. If none can, the follower holds
the gait it walks and says so once, and tries again only when the command changes: a gait is
never retried step after step.

The walker (``Walker.retarget``) then makes the step a transition step: at its touchdown the
impulses are re-solved from the actual pre-impact state towards the new gait, and the next step
is re-aimed at the new gait's touchdown configuration (with momentum steering, its feet-line
momentum error contracting per step), the same hybrid step, BVP and impulses as every step.
Each transition's solve times are kept (``transitions``).
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, replace

import numpy as np

from ..gait.atlas import Atlas, AtlasError, atlas_path
from ..gait.bvp import StepProblem, solve_bvp
from ..gait.planner import BRANCH_BOUND, GaitPlanner, GaitRequest, StrideGuess
from ..dynamics.settings import Settings
from .speed import MAX_SLOPE, MIN_AUTHORITY, FixedCadence, LeastEffort, SpeedRule, walkable_nodes
from .steering import pelvis_pitch, planned_momentum
from .orbit import Cycle, PlannedOrbit, as_cycle
from .runner import Walker
from ..model.biped import BipedModel

MAX_CHANGE = 0.05  # m/s per step: the default bound on the aimed gait's change of speed
MAX_CURVATURE_CHANGE = 0.1  # 1/m per step: the default bound on the aimed gait's change of curvature
MAX_CURVATURE = 0.5  # 1/m: the default bound on the curvature (R >= 2 m; admissible strides at the
# default gait reach about 1 / 1.1 m, docs/results.md)
SPEED_RULES = ("least_effort", "cadence")
NEARER = (0.5, 0.25)  # the fractions of a transition tried when it cannot be reached
MAX_PITCH = 0.05
"""rad: a transition step leaves the walker's momentum about the feet line (which no impulse
changes) at most what this touchdown pitch steers away from its new gait's: the change of the
planned momentum, less the lag the walker carries into the step contracted by its steering rate,
within the authority a + b c (``steering``) times it. 0.7 to 0.75 kg m^2/s with the nine joints
(14 to 15 per rad), whose ramps of 0.05 m/s per step ask up to 1.2; with the hips (3 to 11 per
rad) 0.15 to 0.55, where their ramps ask up to 2.2. With 0.1 rad the hips' walk from the plan at
0.9 m/s fell in its second step (docs/model.md section 8.8)."""
MOMENTUM_SHRINKS = 3  # a transition shrunk at most this many times to keep within that bound
SHRINK_MARGIN = 0.9  # each time to this fraction of the bound, in proportion to the change it asked
PUT_OFF = 0.5  # a transition the walker put off: the next one this fraction of the way


@dataclass(frozen=True)
class GaitChange:
    """One transition, a change of the gait aimed at: before ``step``, towards ``speed`` (m/s,
    commanded ``commanded``) and the curvature ``curvature`` (1/m), the gait (L m, T s) and how
    long solving its orbit took (s), or why it failed (``failure``)."""

    step: int
    commanded: float
    speed: float
    step_length: float
    period: float
    solve_seconds: float
    failure: str = ""
    curvature: float = 0.0
    waited: bool = False  # no transition this step: the walker's momentum is still catching up with its gait


@dataclass(frozen=True)
class Envelope:
    """The commands a follower walks: speeds ``low`` to ``high`` (m/s), curvatures |omega / v| up
    to ``max_curvature`` (1/m; 0 for a model that walks straight), and the changes per step of
    the aimed gait's speed (m/s) and curvature (1/m)."""

    low: float
    high: float
    max_curvature: float
    max_change: float
    max_curvature_change: float

    def describe(self) -> str:
        """One line: the envelope in words."""
        turn = (f", |angular.z| <= {self.max_curvature:g} * linear.x (turn radius >= {1 / self.max_curvature:.3g} m)"
                if self.max_curvature > 0 else ", no turning (angular.z ignored)")
        return f"linear.x in [{self.low:.3f}, {self.high:.3f}] m/s{turn}"


class SpeedFollower:
    """Follows a commanded speed and turn with the walker's gaits (of the model ``bm``); ``rule``
    picks them, ``atlas`` (or None) warm-starts their orbits, ``settings`` are the BVP's (grids,
    tolerance); ``turning`` (None: the model walks straight) solves the strides of a turn, up
    to curvature ``max_curvature`` (1/m)."""

    def __init__(self, bm: BipedModel, rule: SpeedRule, orbit: PlannedOrbit | Cycle, settings: Settings,
                 atlas: Atlas | None = None, max_change: float = MAX_CHANGE, turning: GaitPlanner | None = None,
                 max_curvature: float = MAX_CURVATURE, max_curvature_change: float = MAX_CURVATURE_CHANGE) -> None:
        if not max_change > 0:
            raise ValueError(f"the change of speed per step must be positive, got {max_change}")
        if not max_curvature_change > 0:
            raise ValueError(f"the change of curvature per step must be positive, got {max_curvature_change}")
        self.bm, self.rule, self.settings, self.atlas, self.max_change = bm, rule, settings, atlas, max_change
        self.turning = turning
        self.max_curvature = max_curvature if turning is not None else 0.0
        self.max_curvature_change = max_curvature_change
        cycle = as_cycle(orbit)
        self.orbit, self.cycle = cycle[0], cycle  # the gait aimed at: its first step, its steps
        self.speed = self.orbit.step_length / self.orbit.period  # of the gait aimed at (m/s)
        self.curvature = 0.0 if math.isinf(self.orbit.turn_radius) else 1.0 / self.orbit.turn_radius  # 1/m
        # (L m, T s) and warm start (qd(0), theta) of the last two straight gaits aimed at, oldest first
        self._solved = [((self.orbit.step_length, self.orbit.period), (self.orbit.qd_a, pelvis_pitch(bm, self.orbit.q_t)))]
        self._stride: StrideGuess | None = (
            (cycle[0].qd_a, cycle[0].theta, cycle[1].qd_a, cycle[1].theta) if len(cycle) == 2 else None)
        self._commanded: tuple[float, float] | None = None  # (speed m/s, curvature 1/m); None: walk the plan
        self._held: tuple[float, float] | None = None  # a command none of whose transitions could be reached
        self._lock = threading.Lock()
        self._put_offs = 0  # transitions the walker put off since the last it made
        self.transitions: list[GaitChange] = []

    @property
    def envelope(self) -> Envelope:
        """The commands this follower walks."""
        return Envelope(self.rule.low, self.rule.high, self.max_curvature, self.max_change, self.max_curvature_change)

    @property
    def commanded(self) -> float:
        """The commanded speed (m/s), clamped (the aimed gait's before any command)."""
        with self._lock:
            return self.speed if self._commanded is None else self._commanded[0]

    @property
    def max_period_change(self) -> float:
        """The largest change of the aimed gait's period per step (s)."""
        return MAX_SLOPE * self.max_change

    def command(self, speed: float, yaw_rate: float = 0.0) -> tuple[float, float, bool]:
        """Command ``speed`` (m/s) and ``yaw_rate`` (rad/s, positive turns left); returns the speed
        and the yaw rate that will be walked (the speed clamped to the rule's admissible range,
        the curvature yaw_rate / speed to ``max_curvature``: none for a model that walks
        straight) and whether either was clamped. ``ValueError`` if one is not finite."""
        if not (math.isfinite(speed) and math.isfinite(yaw_rate)):
            raise ValueError(f"a commanded speed and yaw rate must be finite, got {speed}, {yaw_rate}")
        clamped, moved = self.rule.clamp(speed)
        curvature = float(np.clip(yaw_rate / clamped, -self.max_curvature, self.max_curvature))
        turned = abs(curvature * clamped - yaw_rate) > 1e-12
        with self._lock:
            self._commanded = (clamped, curvature)
        return clamped, curvature * clamped, moved or turned

    def before_step(self, walker: Walker) -> GaitChange | None:
        """Aim ``walker``'s next step one transition closer to the commanded speed and turn (None
        if it is at them already, no command came, or the command is held). A transition that
        cannot be reached is replaced by the nearest one that can (``NEARER``); if none can, the
        follower holds its gait until the command changes: the transition is returned with its
        ``failure``, which says so. A transition is shrunk to the momentum the walker's steering
        follows in a step (``MAX_PITCH``); a walker too far behind its gait for any of it waits
        (the transition returned with ``waited``, the gait unchanged)."""
        with self._lock:
            command = self._commanded
        if walker.state.aim.pending is None and walker.cycle[0] is not self.cycle[0]:
            self._put_off(walker)
        if command is None or command == self._held:
            return None
        commanded, aimed = command
        current = np.array([self.speed, self.orbit.period, self.curvature])
        turning = aimed != 0.0 or self.curvature != 0.0  # the period is held on a turn: its strides at one period
        goal = np.array([commanded, self.orbit.period if turning else self.rule.gait(commanded).period, aimed])
        if np.all(np.abs(goal - current) < (1e-9, 1e-9, 1e-12)):
            return None
        bounds = np.array([self.max_change, self.max_period_change, self.max_curvature_change])
        full = current + np.clip(goal - current, -bounds, bounds)
        start = time.perf_counter()
        failures = []
        fractions, shrunk = [PUT_OFF ** self._put_offs * f for f in (1.0, *NEARER)], 0
        limit, carried = self._momentum_limit(walker), self._carried_momentum(walker)
        rate = walker.state.aim.step.steering.rate if walker.state.aim.step.steering is not None else 1.0
        walked = planned_momentum(walker.hybrid, self.orbit)
        while fractions:
            fraction = fractions.pop(0)
            speed, period, curvature = current + fraction * (full - current)
            curvature = 0.0 if abs(curvature) < 1e-12 else float(curvature)
            step_length = float(speed * period)
            if curvature == 0.0:
                orbit, failure = self._orbit(walker, step_length, float(period))
            else:
                orbit, failure = self._stride_cycle(walker, step_length, float(period), curvature)
            if orbit is None:
                failures.append(failure)
                continue
            change, lag = planned_momentum(walker.hybrid, as_cycle(orbit)[0]) - walked, rate * (carried - walked)
            if abs(lag - change) <= limit or shrunk == MOMENTUM_SHRINKS:
                break
            # more momentum than the steering follows in a step: the part of the transition it can
            reach = (lag + math.copysign(limit, change)) / change * fraction if change else 0.0
            if reach <= 0.0:  # the walker is behind its gait already: it catches up first
                self.transitions.append(GaitChange(walker.state.step, commanded, self.speed, self.orbit.step_length,
                                                   self.orbit.period, time.perf_counter() - start, "",
                                                   self.curvature, waited=True))
                return self.transitions[-1]
            shrunk += 1
            fractions.insert(0, min(fraction, reach) * SHRINK_MARGIN)
            orbit = None
        if orbit is None:
            self._held = command
            speed, period, curvature = current
            step_length = float(speed * period)
            failures.append(f"holding the gait L = {self.orbit.step_length:.3f} m, T = {self.orbit.period:.3f} s"
                            f"{f', R = {1.0 / curvature:.3g} m' if curvature else ''} until the command changes")
        transition = GaitChange(walker.state.step, commanded, float(speed), step_length, float(period),
                                time.perf_counter() - start, "; ".join(failures) if orbit is None else "",
                                curvature)
        self.transitions.append(transition)
        if orbit is not None:
            walker.retarget(orbit)
            self._put_offs = 0
            self.cycle = as_cycle(orbit)
            self.orbit, self.speed, self.curvature = self.cycle[0], float(speed), curvature
            if curvature == 0.0:  # straight again: the next turn starts from a straight gait
                self._stride = None
                self._solved = [*self._solved[-1:],
                                ((self.orbit.step_length, self.orbit.period), (self.orbit.qd_a, pelvis_pitch(self.bm, self.orbit.q_t)))]
        return transition

    def _put_off(self, walker: Walker) -> None:
        """The walker put off the last transition (its re-aim could not make it from the touchdown,
        ``phases.impulsive``) and walks on at the gait it walked: aim from there, the next
        transition ``PUT_OFF`` times as large."""
        self.cycle = walker.cycle
        self.orbit = self.cycle[0]
        self.speed = self.orbit.step_length / self.orbit.period
        self.curvature = 0.0 if math.isinf(self.orbit.turn_radius) else 1.0 / self.orbit.turn_radius
        self._put_offs += 1

    def _momentum_limit(self, walker: Walker) -> float:
        """The largest change of the planned momentum about the feet line (kg m^2/s) a transition
        step may ask of ``walker``: what a touchdown pitch of ``MAX_PITCH`` steers at the gait it
        walks (the smallest authority of its steps); inf without momentum steering."""
        steerings = [step.steering for step in walker.state.aim.steps if step.steering is not None]
        if not steerings:
            return math.inf
        return MAX_PITCH * max(min(steering.ref.authority for steering in steerings), MIN_AUTHORITY)

    def _carried_momentum(self, walker: Walker) -> float:
        """The momentum about the feet line (kg m^2/s) the step ``walker`` begins carries from its
        touchdown, which no impulse changes: the closure's gain at that touchdown times the step's
        initial velocity."""
        hybrid, state = walker.hybrid, walker.state
        gain, _ = hybrid.impact(hybrid.exchange.configuration(state.q)).closure_gradients()
        return float(gain @ state.qd)

    def _stride_cycle(self, walker: Walker, step_length: float, period: float,
                      curvature: float) -> tuple[Cycle | None, str]:
        """The stride (L m, T s) on the circle of curvature ``curvature`` (1/m) at the walk's alpha
        and mode, warm-started from the last stride, moved by as much as the straight gait moves
        from its (L, T) to these (a stride's velocities change with (L, T) about as the straight
        gait's do: the last stride alone, 0.0125 s away, leaves the branch), or from the straight
        gait for the first; continued in the curvature from the warm start's when the solve
        leaves its branch. (None, why) if it is not reached or not admissible."""
        current = self.orbit
        if self._stride is not None:
            guess, solved_at = self._stride, self.curvature
            if (step_length, period) != (current.step_length, current.period):
                qd, theta = self._straight(walker, step_length, period)
                qd_0, theta_0 = self._straight(walker, current.step_length, current.period)
                guess = (guess[0] + qd - qd_0, guess[1] + theta - theta_0, guess[2] + qd - qd_0,
                         guess[3] + theta - theta_0)
        else:
            qd, theta = self._straight(walker, step_length, period)
            guess, solved_at = (qd, theta, qd, theta), 0.0
        request = GaitRequest(step_length, period, current.arm_amplitude, current.mode, turn_radius=1.0 / curvature)
        stride = self.turning.plan_stride(request, guess, stability=False, guess_curvature=solved_at)
        where = f"the stride L = {step_length:.3f} m, T = {period:.3f} s, R = {1.0 / curvature:.3g} m"
        if not stride.converged:
            return None, f"{where}: not reached from the last gait"
        if not stride.admissible:
            return None, f"{where}: not admissible ({'; '.join(stride.reasons)})"
        a, b = stride.steps
        self._stride = (a.qd_a, a.theta, b.qd_a, b.theta)
        return tuple(replace(PlannedOrbit.of(step), params=current.params, effort=current.effort,
                             options=current.options) for step in stride.steps), ""

    def _straight(self, walker: Walker, step_length: float, period: float) -> tuple[np.ndarray, float]:
        """qd(0) and theta of the straight gait (L m, T s): the last one solved, else its orbit
        solved now, else the secant's warm start."""
        (point, solved) = self._solved[-1]
        if point == (step_length, period):
            return solved
        orbit, _ = self._orbit(walker, step_length, period)
        return (orbit.qd_a, pelvis_pitch(self.bm, orbit.q_t)) if orbit is not None else self._secant((step_length, period))

    def _secant(self, point: tuple[float, float]) -> tuple[np.ndarray, float]:
        """The warm start at (L m, T s): the last gait's, moved along the secant through the last
        two by the projection of the step to ``point`` on theirs."""
        (p2, (qd2, theta2)) = self._solved[-1]
        if len(self._solved) < 2:
            return qd2, theta2
        p1, (qd1, theta1) = self._solved[0]
        chord = np.subtract(p2, p1)
        ratio = float(np.dot(np.subtract(point, p2), chord) / np.dot(chord, chord)) if np.any(chord) else 0.0
        return qd2 + ratio * (qd2 - qd1), theta2 + ratio * (theta2 - theta1)

    def _orbit(self, walker: Walker, step_length: float, period: float) -> tuple[PlannedOrbit | None, str]:
        """The periodic orbit of the gait (L m, T s) at the walk's alpha and mode, on the
        walker's grid; (None, why) if it does not converge on the branch of its warm starts."""
        current = self.orbit
        hybrid = walker.hybrid
        flow = hybrid.flow(walker.grid)
        coarse = hybrid.flow(self.settings.coarse_steps) if self.settings.coarse_steps < walker.grid else None
        guesses = [self._secant((step_length, period))]
        point = (step_length, period, current.arm_amplitude)
        if self.atlas is not None and (atlas_guess := self.atlas.guess(point)) is not None:
            guesses.insert(0, atlas_guess)
        message = "no warm start"
        for guess in guesses:
            step = solve_bvp(hybrid, flow, StepProblem(step_length, period, current.arm_amplitude, current.mode), guess,
                             self.settings, coarse)
            if not (step.converged and float(np.max(np.abs(step.qd_a - guess[0]))) <= BRANCH_BOUND):
                message = step.message if not step.converged else "the solve left the human-like branch"
                continue
            if hybrid.samples.swing_tip_motion(step.q_target, step.qd_b)[1][0] >= 0.0:
                message = "its swing foot would reach the touchdown from under the ground"
                break
            return replace(current, step_length=step_length, period=period, q0=step.q0, q_t=step.q_target,
                           qd_a=step.qd_a, qd_b=step.qd_b), ""
        return None, f"the gait L = {step_length:.3f} m, T = {period:.3f} s: {message}"


def follower_for(walker: Walker, settings: Settings, rule: str = SPEED_RULES[0], max_change: float = MAX_CHANGE,
                 source: str | None = None, max_curvature: float = MAX_CURVATURE,
                 max_curvature_change: float = MAX_CURVATURE_CHANGE) -> tuple[SpeedFollower, str]:
    """A follower of speed and turn commands for ``walker``'s gait (its parameters, alpha and
    mode), and a note ('' if none): ``rule`` ``least_effort`` needs the current gait atlas of
    the walker's parameters (``source``: the name or file the user gave them by), and falls back
    to ``cadence`` (the walker's period) with a note saying why; ``cadence`` uses the atlas's
    walkable step lengths when there is one. Turns (up to ``max_curvature``, 1/m) with a model
    of lateral hip joints only."""
    if rule not in SPEED_RULES:
        raise ValueError(f"unknown speed rule {rule!r}: use {' or '.join(SPEED_RULES)}")
    orbit, params = walker.orbit, walker.bm.params
    cycle = walker.cycle
    notes = []
    try:
        atlas = Atlas.load(atlas_path(params, orbit.mode), params, source)
    except AtlasError as exc:
        atlas = None
        notes.append(str(exc))
    walkable = walkable_nodes(atlas, orbit.arm_amplitude, walker.hybrid, walker.grid) if atlas is not None else None
    turning = (GaitPlanner(params, replace(settings, fine_steps=walker.grid), on_note=lambda _: None)
               if params.joints.lateral_hips else None)
    extra = dict(turning=turning, max_curvature=max_curvature, max_curvature_change=max_curvature_change)
    if rule == "least_effort" and atlas is not None:
        try:
            return SpeedFollower(walker.bm, LeastEffort(atlas, orbit.arm_amplitude, walkable), cycle, settings, atlas,
                                 max_change, **extra), ""
        except ValueError as exc:
            notes.append(str(exc))
    try:
        cadence = FixedCadence(orbit.period, atlas, walkable)
    except ValueError as exc:
        cadence = FixedCadence(orbit.period)
        notes.append(str(exc))
    if rule == "least_effort":
        notes.append(f"walking at a fixed cadence (T = {orbit.period:g} s) instead of the least effort per metre")
    return SpeedFollower(walker.bm, cadence, cycle, settings, atlas, max_change, **extra), "; ".join(notes)
