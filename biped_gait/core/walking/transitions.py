"""Walking at a commanded speed: transition steps between gaits (docs/model.md section 8.8).

``SpeedFollower`` holds the commanded speed (m/s; clamped to the speed rule's admissible range)
and, before each step of the walker, moves the gait the walker aims at one transition towards
the gait of that speed: the speed of the aimed gait changes by at most ``max_change`` (m/s) per
step (an acceleration bound), the rule (``speed``) gives the next gait's (L, T) at the walk's
arm amplitude and mode, and its periodic orbit is solved by the shooting BVP (``bvp``, coarse
Newton finished on the walker's grid) warm-started from the gait atlas's interpolation
(``Atlas.guess``), else from the secant through the last two gaits solved (the gait aimed at
so far, when there is one). A gait whose swing foot would come up to the touchdown from under
the ground (``speed.walkable_nodes``) is refused.

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
from ..gait.bvp import solve_bvp
from ..gait.planner import BRANCH_BOUND
from ..dynamics.settings import Settings
from .speed import FixedCadence, LeastEffort, SpeedRule, walkable_nodes
from .steering import pelvis_pitch
from .walk import PlannedOrbit, Walker
from ..model.biped import BipedModel

MAX_CHANGE = 0.05  # m/s per step: the default bound on the aimed gait's change of speed
SPEED_RULES = ("least_effort", "cadence")


@dataclass(frozen=True)
class Transition:
    """One transition: before ``step``, towards ``speed`` (m/s, commanded ``commanded``), the
    gait (L m, T s) and how long solving its orbit took (s), or why it failed (``failure``)."""

    step: int
    commanded: float
    speed: float
    step_length: float
    period: float
    solve_seconds: float
    failure: str = ""


class SpeedFollower:
    """Follows a commanded speed with the walker's gaits (of the model ``bm``); ``rule`` picks
    them, ``atlas`` (or None) warm-starts their orbits, ``settings`` are the BVP's (grids,
    tolerance)."""

    def __init__(self, bm: BipedModel, rule: SpeedRule, orbit: PlannedOrbit, settings: Settings,
                 atlas: Atlas | None = None, max_change: float = MAX_CHANGE) -> None:
        if not max_change > 0:
            raise ValueError(f"the change of speed per step must be positive, got {max_change}")
        self.bm, self.rule, self.settings, self.atlas, self.max_change = bm, rule, settings, atlas, max_change
        self.orbit = orbit
        self.speed = orbit.step_length / orbit.period  # of the gait aimed at (m/s)
        # (L m, T s) and warm start (qd(0), theta) of the last two gaits aimed at, oldest first
        self._solved = [((orbit.step_length, orbit.period), (orbit.qd_a, pelvis_pitch(bm, orbit.q_t)))]
        self._commanded = self.speed
        self._lock = threading.Lock()
        self.transitions: list[Transition] = []

    @property
    def commanded(self) -> float:
        """The commanded speed (m/s), clamped."""
        with self._lock:
            return self._commanded

    def command(self, speed: float) -> tuple[float, bool]:
        """Command ``speed`` (m/s); returns the speed that will be walked (clamped to the rule's
        admissible range) and whether it was clamped. ``ValueError`` if it is not finite."""
        if not math.isfinite(speed):
            raise ValueError(f"a commanded speed must be finite, got {speed}")
        clamped, moved = self.rule.clamp(speed)
        with self._lock:
            self._commanded = clamped
        return clamped, moved

    def before_step(self, walker: Walker) -> Transition | None:
        """Aim ``walker``'s next step one transition closer to the commanded speed (None if it is
        at that speed already). A gait whose orbit cannot be solved is not aimed at: the
        transition is returned with its ``failure``, and the next step tries again."""
        commanded = self.commanded
        if abs(commanded - self.speed) < 1e-9:
            return None
        speed = self.speed + float(np.clip(commanded - self.speed, -self.max_change, self.max_change))
        gait = self.rule.gait(speed)
        start = time.perf_counter()
        orbit, failure = self._orbit(walker, gait.step_length, gait.period)
        transition = Transition(walker.state.step, commanded, speed, gait.step_length, gait.period,
                                time.perf_counter() - start, failure)
        self.transitions.append(transition)
        if orbit is not None:
            walker.retarget(orbit)
            self.orbit, self.speed = orbit, speed
            self._solved = [*self._solved[-1:],
                            ((orbit.step_length, orbit.period), (orbit.qd_a, pelvis_pitch(self.bm, orbit.q_t)))]
        return transition

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
            step = solve_bvp(hybrid, flow, step_length, period, current.arm_amplitude, current.mode, "theta", guess,
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
                 source: str | None = None) -> tuple[SpeedFollower, str]:
    """A follower of speed commands for ``walker``'s gait (its parameters, alpha and mode), and a
    note ('' if none): ``rule`` ``least_effort`` needs the current gait atlas of the walker's
    parameters (``source``: the name or file the user gave them by), and falls back to
    ``cadence`` (the walker's period) with a note saying why; ``cadence`` uses the atlas's
    walkable step lengths when there is one."""
    if rule not in SPEED_RULES:
        raise ValueError(f"unknown speed rule {rule!r}: use {' or '.join(SPEED_RULES)}")
    orbit, params = walker.orbit, walker.bm.params
    notes = []
    try:
        atlas = Atlas.load(atlas_path(params, orbit.mode), params, source)
    except AtlasError as exc:
        atlas = None
        notes.append(str(exc))
    walkable = walkable_nodes(atlas, orbit.arm_amplitude, walker.hybrid, walker.grid) if atlas is not None else None
    if rule == "least_effort" and atlas is not None:
        try:
            return SpeedFollower(walker.bm, LeastEffort(atlas, orbit.arm_amplitude, walkable), orbit, settings, atlas,
                                 max_change), ""
        except ValueError as exc:
            notes.append(str(exc))
    try:
        cadence = FixedCadence(orbit.period, atlas, walkable)
    except ValueError as exc:
        cadence = FixedCadence(orbit.period)
        notes.append(str(exc))
    if rule == "least_effort":
        notes.append(f"walking at a fixed cadence (T = {orbit.period:g} s) instead of the least effort per metre")
    return SpeedFollower(walker.bm, cadence, orbit, settings, atlas, max_change), "; ".join(notes)
