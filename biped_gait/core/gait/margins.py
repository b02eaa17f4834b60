"""Margins a request asks beyond the limits (docs/model.md section 4.2): a least swing clearance
(m) and a friction margin (the step's ground reaction and the double support's reaction impulses
within mu - margin; the impulse problem takes the cone at mu - margin itself, and the joint-rate
bound, ``EffortOptions.rate_bound``).

A gait that meets the limits but not the margins is not admissible: its verdict has no limit's
condition (``Verdict.limits`` is 0, which the limits' verdict never is when it refuses) and a
reason per missed margin, each saying that the limits are met; ``MarginVerdict.margins`` holds
which margins it misses. With no margins the verdict is the limits' alone (``admissibility``),
to the bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..dynamics.impulses import ImpulseSolution
from .admissibility import Limit, Verdict, figure_limits
from .figures import StepFigures

PREFIX = "meets the limits but not the margins: "


@dataclass(frozen=True)
class Margins:
    """The swing tip's least height on (0.05 T, 0.95 T) (``clearance``, m; the limit is 0) and
    the friction left unused (``friction``: the step's ground reaction and the double support's
    impulses within mu - this). Zero: none."""

    clearance: float = 0.0
    friction: float = 0.0

    def __bool__(self) -> bool:
        return bool(self.clearance or self.friction)

    def text(self, rate_bound: float = math.inf) -> str:
        """These margins and the joint-rate bound (rad/s) in words ('' if none)."""
        parts = []
        if self.clearance:
            parts.append(f"swing clearance > {self.clearance * 1000:g} mm")
        if self.friction:
            parts.append(f"friction within mu - {self.friction:g}")
        if math.isfinite(rate_bound):
            parts.append(f"joint rates <= {rate_bound:g} rad/s")
        return ", ".join(parts)


@dataclass(frozen=True)
class MarginVerdict(Verdict):
    """A verdict within the limits that misses the margins ``margins`` (``NO_IMPULSES``: none
    within them, ``CLEARANCE``, ``FRICTION``)."""

    margins: Limit = Limit(0)


def missed(figures: StepFigures, friction: float, margins: Margins) -> Limit:
    """The margins a step misses, from its figures and the friction coefficient: ``CLEARANCE``
    at or below ``margins.clearance``, ``FRICTION`` above mu - ``margins.friction``."""
    out = Limit(0)
    if not figures.min_swing_height > margins.clearance:
        out |= Limit.CLEARANCE
    if not figures.max_friction_ratio <= friction - margins.friction:
        out |= Limit.FRICTION
    return out


def describe(misses: Limit, figures: StepFigures, friction: float, margins: Margins, impulses_message: str = "") -> list[str]:
    """One line per missed margin, each saying that the limits are met."""
    lines = []
    if Limit.NO_IMPULSES in misses:
        lines.append(f"no impulses within the margins ({impulses_message})")
    if Limit.CLEARANCE in misses:
        lines.append(f"swing clearance {figures.min_swing_height * 1000:.3g} mm, the margin asks more than "
                     f"{margins.clearance * 1000:.3g} mm")
    if Limit.FRICTION in misses:
        lines.append(f"friction ratio {figures.max_friction_ratio:.3g}, the margin asks at most "
                     f"{friction - margins.friction:.3g} (mu {friction:g} - {margins.friction:g})")
    return [PREFIX + line for line in lines]


def with_margins(verdict: Verdict, impulses: ImpulseSolution | None, figures: StepFigures | None, friction: float,
                 margins: Margins, within_limits: ImpulseSolution | None = None) -> Verdict:
    """The verdict of the limits (``verdict``, from ``admissibility.judge``) with the margins:
    an admissible gait missing a margin, or a gait whose impulses have no solution within the
    margins but do within the limits alone (``within_limits``, solved only then), becomes a
    ``MarginVerdict``; any other verdict is returned as it is."""
    if figures is None:
        return verdict
    limits_met = verdict.admissible
    if not limits_met and verdict.limits == Limit.NO_IMPULSES and impulses is not None and within_limits is not None:
        values = (figures.min_grf_z, figures.min_swing_height, figures.q9_min, figures.max_friction_ratio, friction,
                  figures.min_late_swing_height, figures.swing_arrival_speed)
        limits_met = within_limits.success and not figure_limits(*values)
    if not limits_met:
        return verdict
    misses = missed(figures, friction, margins)
    if not verdict.admissible:
        misses |= Limit.NO_IMPULSES
    if not misses:
        return verdict
    return MarginVerdict(False, tuple(describe(misses, figures, friction, margins, impulses.message if impulses else "")),
                         margins=misses)
