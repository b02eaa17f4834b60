"""Whether a gait can be walked: the verdict on a solved gait (docs/model.md section 4, the
conditions checked a posteriori) and the reasons when it cannot.

Margins: a figure counts as positive when above them (vertical ground reaction in N, swing-tip
height in m); the human-like branch has swing-knee flexion q9 >= -KNEE_TOLERANCE (rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .bvp import BvpSolution
from .impulses import ImpulseSolution
from .reports import StepFigures

GRF_MARGIN = 0.0  # N
HEIGHT_MARGIN = 0.0  # m
KNEE_TOLERANCE = 1e-9  # rad: q9 >= -this is the human-like branch


@dataclass(frozen=True)
class Verdict:
    """``admissible``, and otherwise the reasons (one line each)."""

    admissible: bool
    reasons: tuple[str, ...]


def failure_message(step: BvpSolution, impulses: ImpulseSolution | None) -> str:
    """What failed in the solve ("" when nothing did): the BVP, else the impulse problem."""
    if not step.converged:
        return f"ballistic BVP: {step.message}"
    if impulses is not None and not impulses.success:
        return impulses.message
    return ""


def judge(step: BvpSolution, impulses: ImpulseSolution | None, figures: StepFigures | None) -> Verdict:
    """The verdict on a gait from its ballistic step, its double support's impulses and its
    step figures (the last two None when the BVP did not converge)."""
    reasons = []
    message = failure_message(step, impulses)
    if not step.converged:
        reasons.append(message or "the ballistic BVP did not converge")
    elif impulses is None or not math.isfinite(impulses.W):
        reasons.append(message or "the impulse problem has no solution")
    else:
        if not figures.min_grf_z > GRF_MARGIN:
            reasons.append(f"vertical ground reaction not positive (min {figures.min_grf_z:.3g} N)")
        if not figures.min_swing_height > HEIGHT_MARGIN:
            reasons.append(f"swing tip touches or enters the ground (min height {figures.min_swing_height:.3g} m)")
        if not figures.q9_min >= -KNEE_TOLERANCE:
            reasons.append(f"swing knee bends backwards (min q9 {math.degrees(figures.q9_min):.3g} deg)")
    return Verdict(not reasons, tuple(reasons))
