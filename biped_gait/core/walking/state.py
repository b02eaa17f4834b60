"""The walk's state, a value the phases' transitions return (docs/model.md section 8.1): the
continuous state (q, qd) where the current phase starts, the discrete state (the step, its start
in the walk, its stance foot and heading), and the plan the walk aims at (``Aim``).

Units SI, rad; times in the walk unless said "in the step".
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..model.exchange import world_axes
from .orbit import Cycle, PlannedOrbit
from .steering import MomentumSteering


@dataclass(frozen=True, eq=False)
class AimedStep:
    """One step of the gait aimed at, with what its re-aim needs (computed once,
    ``feedback.Feedback.aim``): the momentum steering towards it, or d q(T) / d qd(0) on it (the
    plain re-aim's chord Jacobian); neither without re-aiming."""

    orbit: PlannedOrbit
    steering: MomentumSteering | None = None
    chord: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Aim:
    """The plan the walk aims at: the steps of its gait (one, or a stride's two), the one the current
    step aims at, the duration the last re-aim found for the next step (s, the next re-aim's warm
    start; the plan's period until then), and another gait to aim at from the current step's
    touchdown on (``pending``, ``retargeted``).

    The steps' ``MomentumSteering`` solvers keep their last solution as the next one's warm start:
    solver memory, not walk state."""

    steps: tuple[AimedStep, ...]
    index: int
    next_period: float
    pending: Cycle | None = None

    @property
    def step(self) -> AimedStep:
        return self.steps[self.index]

    @property
    def orbit(self) -> PlannedOrbit:
        """The plan of the current step."""
        return self.steps[self.index].orbit

    @property
    def period(self) -> float:
        """The current step's planned duration T (s)."""
        return self.orbit.period

    @property
    def cycle(self) -> Cycle:
        """The steps of the gait aimed at (one, or a stride's two)."""
        return tuple(step.orbit for step in self.steps)

    def retargeted(self, cycle: Cycle) -> "Aim":
        """This aim, with ``cycle`` to aim at from the current step's touchdown on."""
        return replace(self, pending=cycle)


@dataclass(frozen=True, eq=False)
class WalkState:
    """Where the walk is: the model state (q, qd) at ``t_step`` s into the current step (0 between
    steps: the step's start), the step, its start ``t`` in the walk, which physical foot is the
    stance foot, that foot's world position (m), the heading (rad) of the step's model frame (its
    axes are the world's turned by it about the vertical, then mirrored for a left stance), and the
    plan aimed at."""

    q: np.ndarray
    qd: np.ndarray
    aim: Aim
    step: int = 0
    t: float = 0.0
    stance_side: str = "right"
    stance_foot: np.ndarray = field(default_factory=lambda: np.array([0.0, -0.2, 0.0]))
    heading: float = 0.0
    t_step: float = 0.0

    @property
    def axes(self) -> np.ndarray:
        """The step's model axes in the world (3 x 3, ``world_axes``)."""
        return world_axes(self.stance_side, self.heading)

    def moved(self, t_step: float, q: np.ndarray, qd: np.ndarray) -> "WalkState":
        """The same step at ``t_step`` s into it, in the state (``q``, ``qd``)."""
        return replace(self, q=q, qd=qd, t_step=t_step)
