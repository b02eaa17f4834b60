"""A phase of the walk: what moves in it, what ends it, what comes next (docs/model.md section 8).

The walk is a hybrid system; each of its modes is a ``Phase``, a value. The runner
(``runner.Walker``) asks the current phase for its ``motion`` (what the engine integrates: the
single-support tree, with joint torques or without) and its ``guard`` (what ends it: the swing
foot's touchdown, an instant, and a deadline past which the robot has fallen), has the engine
integrate until the guard fires (applying the pushes and sampling on the way), then calls the
phase's ``reset`` with how it ended (``End``). The reset returns a ``Transition``, a value: the
next phase, the walk's state in it (``state.WalkState``) and the events to report (a
``events.Touchdown``), or raises ``events.Fall`` with the reason. A phase without motion is
instantaneous: its reset follows at once (the impulsive double support).

Times are in the step (s after its start, ``WalkState.t``); states in the step's model
coordinates. Units SI, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...dynamics.hybrid import HybridStep
from ..engines.engine import Engine, Motion
from ..events import SINGLE_SUPPORT, Foot
from ..feedback import Feedback
from ..push import TrunkPush
from ..state import WalkState

TIME_TOLERANCE = 1e-12  # s: an instant of a guard is reached this close to it (the sums of steps round)
TOUCHDOWN, AT, AFTER = "touchdown", "at", "after"
"""What ended a phase: the swing foot's touchdown, the instant ``Guard.at``, an engine step that
ended at or after ``Guard.after``."""


@dataclass(frozen=True)
class Guard:
    """What ends a phase, whichever comes first (times in the step, s): the swing foot's touchdown
    once ``touchdown_after`` has passed (its witness, the swing tip's height, armed then so that
    the toe-off scuff does not count); the instant ``at`` (the engine's steps end on it); the first
    engine step's end at or after ``after`` (the steps are not cut for it). Past ``deadline`` with
    none of them the robot has fallen, for the reason ``overdue``."""

    touchdown_after: float = math.inf
    at: float = math.inf
    after: float = math.inf
    deadline: float = math.inf
    overdue: str = ""


@dataclass(frozen=True, eq=False)
class End:
    """How a phase ended: ``event`` (``TOUCHDOWN``, ``AT``, ``AFTER``), at ``t`` (s in the step), in
    the state (``q``, ``qd``: at a touchdown, just before the impact, the pushes still due in the
    step applied)."""

    event: str
    t: float
    q: np.ndarray
    qd: np.ndarray


@dataclass(frozen=True, eq=False)
class Transition:
    """What a reset returns: the next ``phase``, the walk's ``state`` where it starts, and the
    ``events`` to report (a ``Touchdown`` ends a step)."""

    phase: "Phase"
    state: WalkState
    events: tuple = ()


@dataclass(frozen=True, eq=False)
class WalkContext:
    """What the phases of one walk share and never change: the planner's hybrid step (its model,
    flows, guard, impact maps, sample evaluation), the feedback (the re-aim), the engine (for
    what a phase needs of its own model: the passive impact), and the trunk pushes' velocity
    jumps."""

    hybrid: HybridStep
    feedback: Feedback
    engine: Engine
    trunk_push: TrunkPush

    @property
    def grid(self) -> int:
        """RK8 steps per planned period."""
        return self.feedback.grid


class Phase:
    """A phase of the walk (module docstring). Subclasses are frozen dataclasses: a phase is a
    value, made by the walk's start or by the reset before it. The defaults are those of a single
    support: the stance foot on the ground, its reaction by the ballistic model's inverse
    dynamics, a push's velocity jump with the stance tip held."""

    kind = SINGLE_SUPPORT
    friction = math.inf
    """The friction coefficient the samples' contact forces are checked against (with the engine's
    own): inf for a single support, whose friction the plan judges; a phase whose feet the
    planner's model holds checks the parameter set's."""

    def first_state(self, aim) -> tuple[np.ndarray, np.ndarray]:
        """(q, qd) where a walk that begins with this phase starts, aiming at ``aim``
        (``state.Aim``): the start of its gait's step."""
        return np.asarray(aim.orbit.q0), np.asarray(aim.orbit.qd_a)

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion | None:
        """What the engine integrates from ``state``; None: the phase is instantaneous."""
        raise NotImplementedError

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        """What ends the phase started in ``state`` (a phase with motion)."""
        raise NotImplementedError

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        """The transition out of the phase, which started in ``state`` and ended as ``end``;
        ``events.Fall`` if the robot falls there."""
        raise NotImplementedError

    def pushed(self, ctx: WalkContext, state: WalkState, t: float, q: np.ndarray, qd: np.ndarray) -> "Phase":
        """The phase to go on with after a push at ``t`` (s in the step) left the state (``q``,
        ``qd``): itself, or one whose guard is planned again (its motion stays)."""
        return self

    def push_jump(self, ctx: WalkContext, state: WalkState, q: np.ndarray, impulse: np.ndarray) -> np.ndarray:
        """The velocity jump (rad/s) of ``impulse`` (N s, world axes) on the trunk at ``q``."""
        return ctx.trunk_push.velocity_jump(q, impulse, state.axes)

    def feet(self, state: WalkState) -> tuple[Foot, ...]:
        """The feet on the ground, the step's stance foot first."""
        return (Foot(state.stance_side, state.stance_foot),)

    def evaluate(self, ctx: WalkContext, q: np.ndarray, qd: np.ndarray,
                 torques: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """At the samples (``q``, ``qd``: rows; ``torques``, N m, the joint torques that act there,
        rows of q's size): the contact force [Fx, Fy, Fz, Mz] at each foot on the ground (n x feet x
        4, N, N m; an engine that measures them gives its own) and the height of the lowest knee,
        hip, shoulder or hand (n, m)."""
        evaluated = ctx.hybrid.samples.dynamics(q, qd)
        return evaluated.grf[:, None, :], evaluated.lowest_link
