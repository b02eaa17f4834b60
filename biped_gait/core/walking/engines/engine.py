"""What integrates the walk's phases: an engine, and what it is asked to integrate (``Motion``).

Engines only integrate, as SciPy's ODE solvers only step while one driver samples and locates
the events: the runner (``runner.Walker``) owns the walk's state, its samples, pushes and falls
and the phases' order; an engine advances a workspace one integration step at a time. After
Pinocchio's Model/Data split, an engine holds what is fixed for a walk (its model) and
``workspace()`` makes the mutable rest (the state being integrated); every call takes the
workspace. The engines: ``hybrid`` (the planner's own model, ``engines/hybrid.py``) and
``mujoco`` (MuJoCo on the exported stance tree, ``engines/mujoco.py``).

Times are in the step (s after its start, the ``origin`` in the walk that ``begin`` is given);
states in the step's model coordinates (q, qd of the single-support tree). Units SI, rad.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ...dynamics.closed_chain import ClosedChain


@dataclass(frozen=True, eq=False)
class Pulse:
    """Constant joint torques ``torque`` (N m, nq: zero on the passive joints) from ``start`` to
    ``end`` (s in the step; inf: until the phase ends)."""

    torque: np.ndarray
    start: float
    end: float


@dataclass(frozen=True, eq=False)
class Held:
    """The foot tips ``chain`` holds (both: the closed chain, core/dynamics/closed_chain.py; the
    stance tip alone: the single support driven by joint torques, ``phases.pulse_dynamics.PinnedTip``),
    the actuated joints driven by the feedback law ``law(t, q, qd)`` (N m; t in the step, s)."""

    chain: ClosedChain
    law: Callable[[float, np.ndarray, np.ndarray], np.ndarray]

    def acceleration(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """qdd (rad/s^2) of the chain at ``t`` (s in the step) in (``q``, ``qd``) under the law's
        torques."""
        return self.chain.forward(q, qd, self.law(t, q, qd))[0]


@dataclass(frozen=True, eq=False)
class Motion:
    """What the engine integrates in a phase: the single-support tree (the stance tip held, the
    paper's model) driven by ``pulses`` (none: ballistic, as the paper's single support), or with
    ``held`` the tips its chain holds and the joints driven by its law; ``h`` (s) the integration step of the
    planner's model (its RK8 grid in a single support: the aimed period over the walk's steps per
    period)."""

    h: float
    pulses: tuple[Pulse, ...] = ()
    held: Held | None = None

    def torques(self, q: np.ndarray, qd: np.ndarray, taus: np.ndarray) -> np.ndarray:
        """The joint torques (N m, rows of q's size, zero on the passive joints) that act at the
        instants ``taus`` (s in the step) in the states (``q``, ``qd``: rows): the pulses on then
        (a pulse acts from its start to before its end, as the engines apply it), and the held
        law's torques at each state; zero in a ballistic motion."""
        q, taus = np.atleast_2d(q), np.asarray(taus, dtype=float)
        out = np.zeros(q.shape)
        for pulse in self.pulses:
            out[(pulse.start <= taus) & (taus < pulse.end)] += pulse.torque
        if self.held is not None:
            actuated = self.held.chain.actuated
            for k in range(len(q)):
                out[k, actuated] += self.held.law(taus[k], q[k], qd[k])
        return out


@dataclass(frozen=True, eq=False)
class Contacts:
    """What an engine measures of the feet on the ground at the samples (n of them): the contact
    force [Fx, Fy, Fz, Mz] at each (n x feet x 4: N, N m, the step's model axes, the stance foot
    first), and how far each tip has moved from where it was put down (n x feet x 3, m, the step's
    model axes; None: the engine holds it there)."""

    forces: np.ndarray
    moved: np.ndarray | None = None


class Segment(Protocol):
    """One integration step, as ``Engine.advance`` reports it."""

    t: float  # where it ended (s in the step): its end, or the touchdown it located
    touchdown: bool  # whether the swing foot touched down in it (the workspace is then at the touchdown)


class Engine(Protocol):
    """An integrator of the walk's phases (module docstring)."""

    contact_friction: float
    """The friction coefficient the samples' contact forces are checked against (the engine
    measures them and the contacts are checked, not simulated); inf: not checked."""

    def workspace(self):
        """A fresh workspace: the mutable state of one walk in this engine."""

    def begin(self, ws, motion: Motion, origin: float, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        """A phase with ``motion`` starts at ``t`` s into the step that began at ``origin`` (s in the
        walk) in the state (``q``, ``qd``); the workspace keeps its own state if it is that one."""

    def advance(self, ws, motion: Motion, t_stop: float, touchdown_after: float) -> Segment:
        """One integration step, ending at ``t_stop`` (s in the step) at the latest; the swing
        foot's touchdown located in it if it comes once ``touchdown_after`` has passed."""

    def state(self, ws) -> tuple[np.ndarray, np.ndarray]:
        """The state (q, qd) the workspace is in."""

    def set_velocity(self, ws, qd: np.ndarray) -> None:
        """Give the state the velocity ``qd`` (a push's jump), the configuration kept."""

    def sample(self, ws, segments: list[Segment], taus: list[float],
               jumps: list[float]) -> tuple[np.ndarray, np.ndarray, Contacts | None]:
        """The states (q, qd: rows) at ``taus`` (s in the step) in the phase's ``segments``, the
        velocity jumping at the instants ``jumps``; and the feet's contacts if the engine measures
        them, else None."""

    def passive_impact(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The next step's initial velocity (its coordinates, rad/s) after the passive impact of
        the swing foot at ``q`` from ``qd`` (eqs. 8-9) and the leg exchange, in this engine's model."""
