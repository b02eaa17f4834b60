"""What a walk needs of a plan (``PlannedOrbit``), and the steps a gait repeats (``Cycle``): one
periodic step, or a stride's two on a circle. Units SI, rad."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.impulses import EffortOptions
from ..gait.configurations import GaitMode


@dataclass(frozen=True, eq=False)
class PlannedOrbit:
    """What a walk needs of a plan: the parameter set (name or file), the gait's L (m), T (s),
    alpha (rad), mode, effort, the boundary configurations q0 and q_t (rad), the velocities
    qd_a at the start and qd_b at the end of the step (rad/s), the plan's verdict, and how its
    impulses are chosen (friction cone, joint-rate bound, the effort's reading), what the
    ground's spin moments change of the momentum about the feet line in the double support that
    ends the step (kg m^2/s; zero but for legs leaning, docs/model.md section 5.2), the trunk
    pitch theta of its touchdown configuration (rad), the radius of the circle it is a step
    of (m, signed; inf: straight), the double support that lasts at its end, to track
    (``held_support.HeldSupport``; None: the paper's instantaneous one), and the actuated ends of
    its swing, to track (``swing_ends.SwingEnds``; None: the paper's ballistic swing)."""

    params: str
    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode
    effort: str
    q0: np.ndarray
    q_t: np.ndarray
    qd_a: np.ndarray
    qd_b: np.ndarray
    converged: bool = True
    admissible: bool = True
    reasons: tuple[str, ...] = ()
    options: EffortOptions = EffortOptions()
    foot_line_moment: float = 0.0
    theta: float = math.nan
    turn_radius: float = math.inf
    double_support: object = None
    swing_ends: object = None

    def touchdown_error(self, q: np.ndarray, qd: np.ndarray) -> float:
        """max |(q, qd) - (q_T, qd_b)| (rad, rad/s): how far a touchdown state is from the plan's."""
        return max(float(np.max(np.abs(q - self.q_t))), float(np.max(np.abs(qd - self.qd_b))))

    @classmethod
    def of(cls, gait) -> "PlannedOrbit":
        """The orbit of a solved ``gait.Gait``."""
        ds = gait.double_support
        return cls(gait.problem.params, gait.step_length, gait.period, gait.arm_amplitude, gait.mode,
                   gait.problem.effort, gait.step.q0, gait.step.q_target, gait.step.qd_a, gait.step.qd_b,
                   gait.converged, gait.admissible, gait.reasons, gait.problem.impulse_options,
                   ds.foot_line_moment if ds is not None else 0.0, gait.theta, gait.problem.turn_radius)


Cycle = tuple[PlannedOrbit, ...]
"""The steps a gait repeats: one for a straight gait, two (right foot, left foot) for a stride on a
circle, each in its own model coordinates."""


def as_cycle(orbit: PlannedOrbit | Cycle) -> Cycle:
    """A gait's steps: ``orbit`` itself, or its steps."""
    return (orbit,) if isinstance(orbit, PlannedOrbit) else tuple(orbit)
