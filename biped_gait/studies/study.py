"""The paper's arm-swing study, run on an executor: the W(alpha) curves of Fig. 4 and, for
each (L, T) asked, the normal gait's optimal arm amplitude with the anti-normal gait at the
same amplitude (the paper's table and Fig. 5). L in m, T in s, alpha in rad.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field

from matplotlib.figure import Figure
from tqdm import tqdm

from ..core.gait.configurations import GaitMode
from .figures import effort_figure, momentum_figure
from ..core.gait.arm_optimum import ALPHA_RANGE, COARSE_STEP, ArmOptimum
from .mode_comparison import ModeComparison, compare_modes
from ..core.model.params import BipedParams
from ..core.gait.gait import Gait
from ..core.gait.chains import inclusive_range
from .sweep import SweepGrid, run_chain

FIG4_STEP_LENGTHS = (0.40, 0.45, 0.50)  # m
PAPER_PERIOD = 0.45  # s
FIG4_CASES = tuple((length, PAPER_PERIOD) for length in FIG4_STEP_LENGTHS)
FIG5_CASE = (0.45, 0.45)  # (L m, T s)
TABLE_CASES = (*FIG4_CASES, (0.45, 0.48), (0.45, 0.50))


@dataclass
class Study:
    """One parameter set's results: the Fig. 4 sweep (both modes; empty if not asked) and
    the mode comparisons keyed by (L, T)."""

    params: BipedParams
    curves: list[Gait] = field(default_factory=list)
    comparisons: dict[tuple[float, float], ModeComparison] = field(default_factory=dict)

    def fig4_optima(self) -> list[ArmOptimum]:
        """The optimum (of the normal gait, unless another mode was asked) for each Fig. 4 step
        length that was computed."""
        return [self.comparisons[case].optimum for case in FIG4_CASES if case in self.comparisons]

    def fig4(self) -> Figure:
        """Fig. 4: W against alpha for L = 0.40, 0.45, 0.50 m at T = 0.45 s, optima marked."""
        title = f"W against alpha, T = {PAPER_PERIOD:g} s, params {self.params.name}"
        return effort_figure(self.curves, self.fig4_optima(), title)

    def fig5(self) -> Figure:
        """Fig. 5: yaw momentum over two steps at L = T = 0.45, both modes at the optimal alpha
        (of the normal gait, unless another mode was asked)."""
        comparison = self.comparisons[FIG5_CASE]
        return momentum_figure(comparison.optimum.gait, comparison.other)


def fig4_grid(params: BipedParams, coarse_step: float = COARSE_STEP, alpha_range: tuple[float, float] = ALPHA_RANGE,
              options: Mapping[str, object] | None = None) -> SweepGrid:
    """The Fig. 4 sweep: three step lengths, T = 0.45 s, alpha over ``alpha_range`` (rad, 0..45
    deg) every ``coarse_step``, both modes, each gait with the ``GaitRequest`` fields ``options``."""
    alphas = inclusive_range(*alpha_range, coarse_step, "arm amplitude")
    return SweepGrid.build(params, FIG4_STEP_LENGTHS, (PAPER_PERIOD,), alphas, [m.value for m in GaitMode],
                           options=options)


def run_study(
    executor: Executor,
    params_sets: Sequence[BipedParams],
    cases: Sequence[tuple[float, float]] = TABLE_CASES,
    curves: bool = True,
    coarse_step: float = COARSE_STEP,
    alpha_range: tuple[float, float] = ALPHA_RANGE,
    options: Mapping[str, object] | None = None,
    mode: GaitMode | str = GaitMode.NORMAL,
) -> list[Study]:
    """Compute the study for each parameter set, all tasks at once on ``executor``, with a
    progress bar on stderr. ``cases`` are the (L, T) of the mode comparisons (``mode``'s
    optimum, the other mode at its alpha); ``curves`` adds the Fig. 4 sweep; ``alpha_range``
    (rad) is searched with ``coarse_step`` (rad) the alpha spacing of sweeps and brackets;
    ``options`` are further ``GaitRequest`` fields of every gait; every chain starts from the
    gait the planner finds (atlas, continuation)."""
    studies = [Study(params) for params in params_sets]
    tasks = {}
    for study in studies:
        if curves:
            for chain in fig4_grid(study.params, coarse_step, alpha_range, options).chains():
                tasks[executor.submit(run_chain, chain)] = (study, None)
        for case in cases:
            future = executor.submit(compare_modes, study.params, *case, alpha_range, coarse_step, options, mode)
            tasks[future] = (study, case)
    with tqdm(total=len(tasks), unit="task", desc="study", file=sys.stderr) as bar:
        for future in as_completed(tasks):
            study, case = tasks[future]
            if case is None:
                study.curves.extend(future.result())
            else:
                study.comparisons[case] = future.result()
            bar.update()
    for study in studies:
        study.curves.sort(key=lambda r: (r.step_length, r.period, r.mode, r.arm_amplitude))
        study.comparisons = {case: study.comparisons[case] for case in cases}
    return studies

