"""The RK8 grids a plan is solved on (docs/model.md sections 4.8 and 4.11)."""

from __future__ import annotations

from dataclasses import dataclass

from ..dynamics.flow import BallisticFlow
from ..dynamics.hybrid import HybridStep
from .monodromy import BackgroundVariationalFlow


@dataclass(frozen=True, eq=False)
class PlanGrids:
    """A plan's grids: its own (``flow``, ``steps`` RK8 steps per T); the coarse one Newton's
    iterations run on (``coarse``; None: on the plan's own); the one its integration error is
    estimated against (``estimate``: the coarse one, else half as many steps); and the
    background flow of its multipliers' variational equations, on the plan's grid."""

    flow: BallisticFlow
    coarse: BallisticFlow | None
    estimate: BallisticFlow
    background: BackgroundVariationalFlow

    @classmethod
    def of(cls, hybrid: HybridStep, steps: int, coarse_steps: int) -> "PlanGrids":
        """The grids of ``steps`` per T (at least 2) with Newton on ``coarse_steps`` (if fewer)."""
        if steps < 2:
            raise ValueError(f"a plan's grid needs at least 2 steps (its error is estimated on half as many), got {steps}")
        coarse = hybrid.flow(coarse_steps) if coarse_steps < steps else None
        return cls(hybrid.flow(steps), coarse, coarse or hybrid.flow(steps // 2),
                   BackgroundVariationalFlow(BallisticFlow(hybrid.bm.single, steps)))

    @property
    def steps(self) -> int:
        return self.flow.steps

    @property
    def ratio(self) -> float:
        """How many times finer the plan's grid is than the estimate's."""
        return self.steps / self.estimate.steps
