"""The arm amplitude alpha (rad) that minimizes the effort W (N m s) of a gait (the planner
node's optimize action, ``biped-gait optimize-arms``, the studies).

W(alpha) has kinks where the impulse LP changes its active set, so the minimum is bracketed
on a coarse continuation sweep and refined with ``scipy.optimize.minimize_scalar``
(``method="bounded"``) inside the bracket. When the least W of the sweep is at an end of the
range (or next to gaits that fail), W has no interior minimum there and the point is
reported as such, not as an optimum.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..dynamics.settings import DEFAULTS
from .chains import inclusive_range, solve_chain, solve_near
from .configurations import GaitMode
from .gait import Gait
from .planner import GaitPlanner, GaitRequest, validate_request

ALPHA_RANGE = DEFAULTS.arm_range  # rad: the paper's Fig. 4 range
COARSE_STEP = DEFAULTS.arm_coarse_step  # rad: 31 points on the range
TYPICAL_REFINE_SOLVES = 20  # bounded Brent to DEFAULTS.arm_tolerance in a 3 deg bracket: 14-18 solves seen

INTERIOR = "interior minimum"
END_POINT = "end point"
ADMISSIBILITY_EDGE = "edge of the admissible gaits"


class Canceled(Exception):
    """Raised by an ``on_result`` hook to end a search early."""


class NoAdmissibleGait(RuntimeError):
    """No gait of the coarse sweep converged to an admissible gait: there is nothing to minimize."""


@dataclass(frozen=True, eq=False)
class ArmOptimum:
    """The least effort over an arm-amplitude range ``alpha_range`` (rad) for one gait problem.

    ``gait`` is the full gait (with its trajectory) at the least W found. It is the minimizer
    when ``where`` is ``INTERIOR``; otherwise it is the coarse point of least W, at an end of
    the range (``END_POINT``) or next to gaits that fail (``ADMISSIBILITY_EDGE``).
    ``evaluations`` counts the arm amplitudes solved.
    """

    gait: Gait
    alpha_range: tuple[float, float]
    where: str
    evaluations: int

    @property
    def interior(self) -> bool:
        return self.where == INTERIOR

    @property
    def alpha(self) -> float:
        """Arm amplitude (rad) of the least W."""
        return self.gait.arm_amplitude

    @property
    def W(self) -> float:
        """Its effort (N m s)."""
        return self.gait.W

    def describe(self) -> str:
        """One or two plain sentences (degrees), saying whether this is an optimum."""
        deg = math.degrees
        g = self.gait
        low, high = (f"{deg(a):g}" for a in self.alpha_range)
        case = f"{g.mode} gait, L = {g.step_length:g} m, T = {g.period:g} s, params {g.params}"
        figures = f"W = {g.W:.4f} N m s, theta = {deg(g.theta):.4f} deg"
        if self.interior:
            return (
                f"optimal arm amplitude alpha* = {deg(self.alpha):.3f} deg ({case}): {figures}; "
                f"an interior minimum of W on [{low}, {high}] deg."
            )
        return (
            f"W(alpha) has no interior minimum on [{low}, {high}] deg ({case}): its least value is at the "
            f"{self.where} alpha = {deg(self.alpha):.3f} deg ({figures}). This is not an optimum."
        )


def expected_solves(alpha_range: tuple[float, float], coarse_step: float = COARSE_STEP) -> int:
    """About how many gaits ``optimal_arm_amplitude`` solves on ``alpha_range`` (rad): the
    coarse sweep and a typical refinement (for progress reports, not a bound)."""
    low, high = alpha_range
    return 1 + round((high - low) / coarse_step) + TYPICAL_REFINE_SOLVES


def optimal_arm_amplitude(
    planner: GaitPlanner,
    step_length: float,
    period: float,
    mode: GaitMode | str = GaitMode.NORMAL,
    alpha_range: tuple[float, float] = ALPHA_RANGE,
    coarse_step: float = COARSE_STEP,
    on_result: Callable[[Gait], None] | None = None,
    options: Mapping[str, object] | None = None,
) -> ArmOptimum:
    """Minimize W over alpha in ``alpha_range`` (rad, the coarse sweep every ``coarse_step``
    rad and the upper end) for L (m), T (s), ``mode``, the sweep a continuation chain
    (``chains.solve_chain``) from the gait the planner finds first. ``on_result`` sees every gait
    solved, coarse and refining, as it comes (progress reports; an exception it raises, such
    as ``Canceled``, ends the search). ``options``: further ``GaitRequest`` fields (friction,
    rate_bound, effort_coordinates).

    Raises ``ValueError`` for an empty or inverted range, a step that is not positive, or an
    invalid gait request; ``NoAdmissibleGait`` if no coarse gait is admissible.
    """
    low, high = alpha_range
    if not high > low:
        bounds = f"[{math.degrees(low):g}, {math.degrees(high):g}] deg"
        raise ValueError(f"arm amplitude range is empty or inverted: {bounds}")
    for alpha in alpha_range:
        validate_request(GaitRequest(step_length, period, alpha, mode, **(options or {})), planner.params)
    alphas = inclusive_range(low, high, coarse_step, "arm amplitude")
    if alphas[-1] < high - 1e-12:
        alphas = (*alphas, high)
    mode_name = GaitMode.parse(mode).value
    coarse = solve_chain(planner, step_length, period, mode_name, alphas, on_result, options)
    solved = dict(zip(alphas, coarse))
    values = np.array([r.W if r.usable else np.nan for r in coarse])
    if np.all(np.isnan(values)):
        raise NoAdmissibleGait(
            f"no admissible {mode_name} gait at L = {step_length:g} m, T = {period:g} s on "
            f"[{math.degrees(low):g}, {math.degrees(high):g}] deg: {coarse[0].reasons[0]}"
        )
    best = int(np.nanargmin(values))
    if best in (0, len(alphas) - 1):
        where = END_POINT
    elif np.isnan(values[best - 1]) or np.isnan(values[best + 1]):
        where = ADMISSIBILITY_EDGE
    else:
        where = INTERIOR
        _refine(planner, step_length, period, mode_name, (alphas[best - 1], alphas[best + 1]), solved, on_result,
                options)
    alpha = min((a for a, r in solved.items() if r.usable), key=lambda a: solved[a].W)
    return ArmOptimum(gait=solved[alpha], alpha_range=(low, high), where=where, evaluations=len(solved))


def _refine(
    planner: GaitPlanner,
    step_length: float,
    period: float,
    mode: str,
    bracket: tuple[float, float],
    solved: dict[float, Gait],
    on_result: Callable[[Gait], None] | None = None,
    options: Mapping[str, object] | None = None,
) -> None:
    """Bounded scalar minimization of W over alpha inside ``bracket`` (rad), each solve
    warm-started from the nearest gait solved so far; every gait solved is added to ``solved``
    and shown to ``on_result``."""
    from scipy.optimize import minimize_scalar  # here, not with the module: it takes a plan process's time to import

    def effort(alpha: float) -> float:
        nearest = min(solved, key=lambda a: abs(a - alpha))
        request = GaitRequest(step_length, period, alpha, mode, **(options or {}))
        result = solve_near(planner, request, solved[nearest].warm_start())
        solved[alpha] = result
        if on_result is not None:
            on_result(result)
        return result.W if result.usable else math.inf

    minimize_scalar(effort, bounds=bracket, method="bounded", options={"xatol": DEFAULTS.arm_tolerance})
