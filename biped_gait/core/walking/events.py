"""What a walk yields, as values (docs/model.md section 8): the samples of its phases, with the
feet on the ground and their contact forces, the touchdowns, a fall, the end. The runner
(``runner.Walker``) makes them; the phases' resets return the touchdowns.

Everything is in the model's coordinates of the step (stance leg 1 on the right); ``stance_side``
says which physical foot that is, and ``stance_foot`` where it is in the world (m). Units SI, rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .push import AppliedPush
from .world import WorldPictures, WorldState

SINGLE_SUPPORT = "single_support"
DOUBLE_SUPPORT = "double_support"
STANDING = "standing"
STOPPING = "stopping"
STARTING = "starting"
PHASE_KINDS = (SINGLE_SUPPORT, DOUBLE_SUPPORT, STANDING, STOPPING, STARTING)
"""What a phase is to a user (the gait phase topic): one foot on the ground, both while the robot
walks, both while it stands, both while it comes to rest from a walk, both while it sets off from
standing."""


class Fall(Exception):
    """The robot fell, or its next step cannot be made: the message says why."""


@dataclass(frozen=True, eq=False)
class Foot:
    """A foot on the ground: which physical foot (``right``, ``left``) and where (m, world)."""

    side: str
    position: np.ndarray


@dataclass(frozen=True, eq=False)
class Sample:
    """The state at one publishing instant: time in the walk (s) and in the step, q, qd (the step's
    model coordinates), the contact force [Fx, Fy, Fz, Mz] (N, N m, the step's model axes) at each
    foot on the ground (one row per foot of ``feet``, the step's stance foot first), the joint
    torques that act (N m, q's coordinates, zero on the passive ones: zero in a ballistic single
    support, the balance controller's while standing, a pulse's in a double support that lasts),
    the step, the kind of its phase (``PHASE_KINDS``), and the robot in world terms (``Walk`` fills
    it)."""

    t: float
    t_step: float
    q: np.ndarray
    qd: np.ndarray
    forces: np.ndarray
    torque: np.ndarray
    feet: tuple[Foot, ...]
    step: int = 0
    phase: str = SINGLE_SUPPORT
    world: WorldState | None = None

    @property
    def grf(self) -> np.ndarray:
        """The ground reaction [Fx, Fy, Fz, Mz] at the stance tip (N, N m)."""
        return self.forces[0]

    @property
    def stance_side(self) -> str:
        """The physical foot of the step's stance leg (the model's leg 1)."""
        return self.feet[0].side

    @property
    def stance_foot(self) -> np.ndarray:
        """Where the stance foot is (m, world)."""
        return self.feet[0].position

    @property
    def feet_on_ground(self) -> tuple[str, ...]:
        """The physical feet on the ground (``right``, ``left``): one in a single support, two in a
        double support."""
        return tuple(foot.side for foot in self.feet)


@dataclass(frozen=True, eq=False)
class StepSamples:
    """Samples of one phase as ``Walk.batches`` yields them (all of a step's phase, or those on one
    side of a push): each ``Sample`` (without its ``world``), and the robot in world terms at
    their instants, one row each."""

    samples: list[Sample]
    world: WorldPictures

    @property
    def t(self) -> np.ndarray:
        """The samples' times in the walk (s)."""
        return np.array([sample.t for sample in self.samples])


@dataclass(frozen=True, eq=False)
class Touchdown:
    """The end of one step: when, the double support applied, and the distance to the plan;
    ``double_support``: what a double support that lasts did (e.g. ``phases.pulses.PulsedTouchdown``),
    None for the impulsive one."""

    step: int
    t: float  # time in the walk (s)
    t_step: float  # duration of the step (s)
    i_minus: np.ndarray
    i_plus: np.ndarray
    W: float
    state_error: float  # max |(q, qd) at touchdown - the plan's (q_T, qd_b)| (rad, rad/s)
    velocity_miss: float  # |s|: how far the plan's post-impact velocity is from reachable (rad/s)
    correction: float  # max |re-aimed post-impact velocity - the plan's| (rad/s), 0 without re-aiming
    equation_residual: float
    next_stance_side: str = ""
    double_support: object = None


@dataclass(frozen=True)
class Fell:
    """The walk ended with a fall in ``step``: at ``t`` (s in the walk), ``time_in_step`` (s)."""

    step: int
    t: float
    time_in_step: float
    stance_side: str
    reason: str


@dataclass(frozen=True)
class Finished:
    """The walk made all its steps: ``steps`` done by ``t`` (s); the next stance side."""

    steps: int
    t: float
    stance_side: str


@dataclass(frozen=True)
class CouldNotStart:
    """The plan cannot be walked (not converged, unknown parameters): the reason."""

    reason: str


@dataclass(frozen=True, eq=False)
class StepOutcome:
    """One step (``runner.Walker.walk_step``): its samples, and its touchdown or the reason the
    robot fell; the pushes that acted in it."""

    samples: list[Sample]
    touchdown: Touchdown | None
    fall: str = ""
    pushes: tuple[AppliedPush, ...] = ()
