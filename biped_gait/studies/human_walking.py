"""The model beside human walking (docs/results.md): whole-body angular momentum about the
vertical through the centre of mass, normalized by M V H (mass kg, speed L/T m/s, standing
height m) as Herr and Popovic (2008) normalize it, for the normal arm swing, no arm swing and
the anti-normal swing; and the effort's increase without arm swing and in anti-phase, set
beside Collins, Adamczyk and Kuo (2009)'s metabolic cost increases.

The model's effort W is the impulses of the double support, not a metabolic cost, and its
single support is ballistic: the comparison is of directions and rough magnitudes only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Gait
from ..core.model.params import BipedParams
from ..core.gait.planner import GaitRequest
from ..core.walking.world import WorldView
from .executors import planner_for
from ..core.gait.arm_optimum import COARSE_STEP, optimal_arm_amplitude

# Collins et al. (2009): metabolic cost increase over normal arm swing (%), and the vertical
# angular momentum's increase without arm swing (%).
COLLINS_COST = {"arms bound": 7.0, "arms held": 12.0, "anti-phase": 26.0}
COLLINS_MOMENTUM_WITHOUT_ARMS = 63.0


@dataclass(frozen=True, eq=False)
class SwingCase:
    """One arm swing: its gait, the peak |H_z| about the CoM (kg m^2/s) over the step, and that
    peak normalized by M V H (dimensionless)."""

    label: str
    gait: Gait
    peak_momentum: float
    normalized: float


@dataclass(frozen=True, eq=False)
class HumanComparison:
    """The three arm swings at (L m, T s): normal at its optimal alpha, none (alpha = 0), and
    anti-normal at the normal optimum."""

    step_length: float
    period: float
    height: float
    mass: float
    cases: tuple[SwingCase, SwingCase, SwingCase]

    def effort_increase(self, case: int) -> float:
        """W of ``cases[case]`` over the normal optimum's, minus 1 (%)."""
        return 100.0 * (self.cases[case].gait.W / self.cases[0].gait.W - 1.0)

    def momentum_increase(self, case: int) -> float:
        """Peak vertical momentum of ``cases[case]`` over the normal optimum's, minus 1 (%)."""
        return 100.0 * (self.cases[case].peak_momentum / self.cases[0].peak_momentum - 1.0)


def standing_height(params: BipedParams) -> float:
    """Height (m) of the biped standing straight: leg and trunk (the feet are points)."""
    return params.leg_length + params.trunk.length


def peak_vertical_momentum(view: WorldView, gait: Gait) -> float:
    """max |H_z| (kg m^2/s) about the CoM over the gait's sampled step (right stance foot)."""
    samples = gait.figures.samples
    pictures = view.pictures(samples.q, samples.qd, "right", np.zeros(3))
    return float(np.max(np.abs(pictures.momentum_about_com[:, 2])))


def human_comparison(params: BipedParams, step_length: float = 0.45, period: float = 0.45,
                     coarse_step: float = COARSE_STEP) -> HumanComparison:
    """The comparison at (L m, T s) for ``params`` (the optimum bracketed every ``coarse_step`` rad)."""
    planner = planner_for(params)
    normal = optimal_arm_amplitude(planner, step_length, period, GaitMode.NORMAL, coarse_step=coarse_step).gait
    none = planner.plan(GaitRequest(step_length, period, 0.0, GaitMode.NORMAL))
    anti = planner.plan(GaitRequest(step_length, period, normal.arm_amplitude, GaitMode.ANTI_NORMAL))
    view = WorldView(planner.model)
    height, mass = standing_height(params), params.total_mass
    scale = mass * (step_length / period) * height
    cases = []
    for label, gait in (("normal swing, optimal alpha", normal), ("no arm swing", none),
                        ("anti-normal swing, same alpha", anti)):
        peak = peak_vertical_momentum(view, gait)
        cases.append(SwingCase(label, gait, peak, peak / scale))
    return HumanComparison(step_length, period, height, mass, tuple(cases))


def comparison_lines(c: HumanComparison) -> list[str]:
    """The results page's table and reading of the comparison (Markdown)."""
    lines = [f"At L = {c.step_length:g} m, T = {c.period:g} s (speed {c.step_length / c.period:.2f} m/s; M = "
             f"{c.mass:.1f} kg, standing height H = {c.height:.3f} m):", "",
             "| arm swing | alpha (deg) | W (N m s) | W vs normal | peak vertical H about the CoM (kg m^2/s) | "
             "normalized by M V H |", "|---|---:|---:|---:|---:|---:|"]
    for k, case in enumerate(c.cases):
        change = "-" if k == 0 else f"{c.effort_increase(k):+.1f} %"
        lines.append(f"| {case.label} | {math.degrees(case.gait.arm_amplitude):.2f} | {case.gait.W:.3f} | {change} | "
                     f"{case.peak_momentum:.3f} | {case.normalized:.4f} |")
    lines += ["",
              f"- **Cost without arm swing / in anti-phase.** Collins et al. (2009) measured +{COLLINS_COST['arms bound']:g} % "
              f"metabolic cost with the arms bound, +{COLLINS_COST['arms held']:g} % held, "
              f"+{COLLINS_COST['anti-phase']:g} % in anti-phase. The model's effort rises {c.effort_increase(1):+.1f} % "
              f"without arm swing and {c.effort_increase(2):+.1f} % with the anti-normal swing: "
              + ("the same order (anti-phase costlier than no swing)" if c.effort_increase(2) > c.effort_increase(1) > 0
                 else "not the same order as in people") + ". W counts the double support's impulses only, "
              "not muscle work over the step: the model can say which swing needs the smaller corrections, not "
              "how much energy a person spends.",
              f"- **Vertical angular momentum.** Without arm swing its peak about the CoM changes by "
              f"{c.momentum_increase(1):+.0f} % (Collins et al.: +{COLLINS_MOMENTUM_WITHOUT_ARMS:g} %); with the "
              f"anti-normal swing by {c.momentum_increase(2):+.0f} %. Normalized by M V H the normal swing's peak is "
              f"{c.cases[0].normalized:.4f}, small, as Herr and Popovic (2008) found in people, where the arms "
              "cancel much of the legs' momentum. The model's arms are rigid rods swinging ballistically between "
              "impulses, its single support has no torques, and its feet are points: it reproduces the direction "
              "of these effects, not a person's magnitudes."]
    return lines
