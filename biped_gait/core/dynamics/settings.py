"""The numerical defaults of the project, in one place: the planner, the walker, the nodes and
the studies all take them from here (the nodes' parameters default to these values).

Units: tolerances in rad and kg m^2/s (the BVP's end-point residual and closure gap), angles in
rad, times in s. ``Settings`` is immutable; derive a variant with ``dataclasses.replace``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Settings:
    """Numerical settings of a gait solve, a walk and a study."""

    fine_steps: int = 32
    """RK8 steps per ballistic step of a plan: end state within ~1e-10 of an adaptive solver."""
    coarse_steps: int = 16
    """RK8 steps of Newton's iterations, finished on the fine grid by chord steps."""
    walk_steps: int = 32
    """RK8 steps per period T of the walker (and of its per-step re-aim)."""
    tolerance: float = 1e-12
    """Bound on the BVP's end-point residual (rad) and closure gap (kg m^2/s)."""
    coarse_tolerance: float = 1e-9
    """Where Newton on the coarse grid hands over to the fine grid (rad, kg m^2/s)."""
    max_iterations: int = 30
    """Newton iterations allowed per solve."""
    chord_iterations: int = 6
    """Chord steps on the fine grid after coarse Newton (each must gain a factor 10)."""
    reaim_steps: int = 7
    """Chord steps allowed to the walker's per-step re-aim."""
    samples: int = 91
    """Trajectory samples reported per ballistic step."""
    arm_range: tuple[float, float] = (0.0, math.radians(45.0))
    """Arm amplitudes searched for the optimum (rad): the paper's Fig. 4 range."""
    arm_coarse_step: float = math.radians(1.5)
    """Spacing of the coarse arm-amplitude sweep that brackets the optimum (rad)."""
    arm_tolerance: float = 1e-4
    """xatol of the bounded refinement of the optimal arm amplitude (rad, 0.006 deg)."""
    period_step: float = 0.005
    """Largest change of T between two gaits of a continuation in T (s)."""

    def __post_init__(self) -> None:
        for name in ("fine_steps", "coarse_steps", "walk_steps", "max_iterations", "samples"):
            if getattr(self, name) < (2 if name == "samples" else 1):
                raise ValueError(f"{name} must be at least {2 if name == 'samples' else 1}, got {getattr(self, name)}")
        if not 0 < self.tolerance:
            raise ValueError(f"tolerance must be positive, got {self.tolerance}")


DEFAULTS = Settings()
