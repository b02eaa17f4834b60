"""Whether a gait can be walked: the verdict on a solved gait (docs/model.md section 4.2) and the
conditions that limit it, each a bit of a bitmask so that an atlas can store which held.

Conditions, checked a posteriori on the ballistic step (margins: a figure counts as positive
when above them): the vertical ground reaction stays positive (N); the swing tip stays above the
ground on (0.05 T, 0.95 T) (m), and reaches it from above (above it on [0.95 T, T), moving down
or not at all at T); the swing knee never bends backwards beyond the knee's lower limit in the
joint table (q9 >= lower - KNEE_TOLERANCE rad; the paper's sets have 0: negative q9 is a
hyperextended swing knee, the mark of the backward-knee twin); the ground
reaction stays in the friction cone of the parameter set's coefficient (max |F_xy| / F_z <= mu).
Before these: the BVP converged and the double support's impulse problem has a solution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntFlag

from .bvp import BvpSolution
from ..dynamics.impulses import ImpulseSolution
from .figures import StepFigures

GRF_MARGIN = 0.0  # N
HEIGHT_MARGIN = 0.0  # m
KNEE_TOLERANCE = 1e-9  # rad: q9 >= -this is the human-like branch


class Limit(IntFlag):
    """The conditions that make a gait inadmissible (several may hold)."""

    NO_CONVERGENCE = 1  # the ballistic BVP did not converge
    NO_IMPULSES = 2  # the double support's impulse problem has no solution
    GROUND_REACTION = 4  # vertical ground reaction not positive
    CLEARANCE = 8  # the swing tip touches or enters the ground
    KNEE_HYPEREXTENSION = 16  # the swing knee bends backwards (q9 < 0)
    FRICTION = 32  # the ground reaction leaves the friction cone
    ARRIVAL = 64  # the swing tip reaches the ground from below (it went under it before T)


LIMIT_NAMES = {
    Limit.NO_CONVERGENCE: "no convergence",
    Limit.NO_IMPULSES: "no impulses",
    Limit.GROUND_REACTION: "vertical ground reaction",
    Limit.CLEARANCE: "swing clearance",
    Limit.KNEE_HYPEREXTENSION: "knee hyperextension",
    Limit.FRICTION: "friction ratio",
    Limit.ARRIVAL: "arrival from below",
}


@dataclass(frozen=True)
class Verdict:
    """``admissible``, and otherwise the reasons (one line each) and the conditions (``limits``)."""

    admissible: bool
    reasons: tuple[str, ...]
    limits: Limit = Limit(0)


def failure_message(step: BvpSolution, impulses: ImpulseSolution | None) -> str:
    """What failed in the solve ("" when nothing did): the BVP, else the impulse problem."""
    if not step.converged:
        return f"ballistic BVP: {step.message}"
    if impulses is not None and not impulses.success:
        return impulses.message
    return ""


def figure_limits(min_grf_z: float, min_swing_height: float, q9_min: float, max_friction_ratio: float,
                  friction: float, min_late_swing_height: float, swing_arrival_speed: float,
                  knee_lower: float = 0.0) -> Limit:
    """The conditions a solved ballistic step violates, from its figures (N, m, rad, -, m, m/s) and
    the knee's lower limit (rad)."""
    limits = Limit(0)
    if not (min_late_swing_height > HEIGHT_MARGIN and swing_arrival_speed <= 0.0):
        limits |= Limit.ARRIVAL
    if not min_grf_z > GRF_MARGIN:
        limits |= Limit.GROUND_REACTION
    if not min_swing_height > HEIGHT_MARGIN:
        limits |= Limit.CLEARANCE
    if not q9_min >= knee_lower - KNEE_TOLERANCE:
        limits |= Limit.KNEE_HYPEREXTENSION
    if not max_friction_ratio <= friction:
        limits |= Limit.FRICTION
    return limits


def describe(limits: Limit, min_grf_z: float, min_swing_height: float, q9_min: float, max_friction_ratio: float,
             friction: float, min_late_swing_height: float, swing_arrival_speed: float) -> list[str]:
    """One line per violated figure condition of ``limits``, with its value."""
    lines = []
    if Limit.GROUND_REACTION in limits:
        lines.append(f"vertical ground reaction not positive (min {min_grf_z:.3g} N)")
    if Limit.CLEARANCE in limits:
        lines.append(f"swing tip touches or enters the ground (min height {min_swing_height:.3g} m)")
    if Limit.KNEE_HYPEREXTENSION in limits:
        lines.append(f"swing knee bends backwards (min q9 {math.degrees(q9_min):.3g} deg)")
    if Limit.FRICTION in limits:
        lines.append(f"friction ratio {max_friction_ratio:.3g} exceeds the friction coefficient {friction:g}")
    if Limit.ARRIVAL in limits:
        lines.append(f"swing tip reaches the ground from below (height {min_late_swing_height:.3g} m before the "
                     f"touchdown, vertical speed {swing_arrival_speed:.3g} m/s at it)")
    return lines


def judge(step: BvpSolution, impulses: ImpulseSolution | None, figures: StepFigures | None, friction: float,
          knee_lower: float = 0.0) -> Verdict:
    """The verdict on a gait from its ballistic step, its double support's impulses, its step
    figures (the last two None when the BVP did not converge), the friction coefficient and the
    knee's lower limit (rad)."""
    message = failure_message(step, impulses)
    if not step.converged:
        return Verdict(False, (message or "the ballistic BVP did not converge",), Limit.NO_CONVERGENCE)
    if impulses is None or not math.isfinite(impulses.W):
        return Verdict(False, (message or "the impulse problem has no solution",), Limit.NO_IMPULSES)
    values = (figures.min_grf_z, figures.min_swing_height, figures.q9_min, figures.max_friction_ratio, friction,
              figures.min_late_swing_height, figures.swing_arrival_speed)
    limits = figure_limits(*values, knee_lower)
    return Verdict(not limits, tuple(describe(limits, *values)), limits)
