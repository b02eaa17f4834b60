"""The paper's comparison of the gait modes: the arm amplitude of least effort of one mode
(``core.gait.arm_optimum``) and the other mode's gait at that amplitude, as a study's worker
solves it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from ..core.gait.arm_optimum import ALPHA_RANGE, COARSE_STEP, ArmOptimum, optimal_arm_amplitude
from ..core.gait.chains import solve_chain
from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Gait
from ..core.model.params import BipedParams
from .executors import planner_for


@dataclass(frozen=True, eq=False)
class ModeComparison:
    """The optimum of one mode (``optimum``, the normal gait's in the paper's comparison) and
    the other mode's gait at the same alpha (``other``; full gaits)."""

    optimum: ArmOptimum
    other: Gait


def compare_modes(
    params: BipedParams,
    step_length: float,
    period: float,
    alpha_range: tuple[float, float] = ALPHA_RANGE,
    coarse_step: float = COARSE_STEP,
    options: Mapping[str, object] | None = None,
    mode: GaitMode | str = GaitMode.NORMAL,
) -> ModeComparison:
    """Worker entry: optimize the gait of ``mode`` (default normal) at L (m), T (s), then solve
    the other mode's gait at its alpha (the paper's comparison), with this worker's planner for
    ``params``; ``options``: further ``GaitRequest`` fields of every gait."""
    planner = planner_for(params)
    mode = GaitMode.parse(mode)
    other = GaitMode.ANTI_NORMAL if mode is GaitMode.NORMAL else GaitMode.NORMAL
    optimum = optimal_arm_amplitude(planner, step_length, period, mode, alpha_range, coarse_step, options=options)
    [gait] = solve_chain(planner, step_length, period, other.value, (optimum.alpha,), options=options)
    return ModeComparison(optimum, gait)
