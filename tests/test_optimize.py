"""The arm amplitude of least effort: an interior minimum refined inside its bracket, an end
point reported as an end point, bad ranges refused."""

from __future__ import annotations

import math

import pytest

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.gait.arm_optimum import END_POINT, INTERIOR, NoAdmissibleGait, optimal_arm_amplitude
from biped_gait.studies.mode_comparison import compare_modes
from biped_gait.core.model.params import load_params

pytestmark = pytest.mark.studies

COARSE = math.radians(5.0)  # rad: a coarse bracket keeps these tests fast


@pytest.fixture(scope="module")
def optimum(planner):
    return optimal_arm_amplitude(planner, 0.45, 0.45, "normal", coarse_step=COARSE)


def test_interior_minimum_is_a_local_minimum_of_w(planner, optimum):
    assert optimum.where == INTERIOR and optimum.interior
    assert optimum.gait.converged and optimum.gait.admissible
    assert 15 < math.degrees(optimum.alpha) < 35
    # W at alpha* is no larger than at alpha* +/- 0.2 deg (W is continuous with kinks: 1e-9 N m s).
    for delta in (-0.2, 0.2):
        near = planner.plan(GaitRequest(0.45, 0.45, optimum.alpha + math.radians(delta), "normal"))
        assert optimum.W <= near.W + 1e-9
    # The refinement is no worse than the coarse grid around it.
    for alpha_deg in (25.0, 30.0):
        assert optimum.W <= planner.plan(GaitRequest(0.45, 0.45, math.radians(alpha_deg), "normal")).W + 1e-9
    assert optimum.evaluations > 10  # 10 coarse points, then the refinement
    assert optimum.gait.figures.samples is not None  # the full gait, for Fig. 5


def test_the_optimum_does_not_depend_on_the_coarse_step(planner, optimum):
    fine = optimal_arm_amplitude(planner, 0.45, 0.45, "normal", coarse_step=math.radians(3.0))
    assert fine.interior
    assert math.degrees(fine.alpha) == pytest.approx(math.degrees(optimum.alpha), abs=0.05)
    assert fine.W == pytest.approx(optimum.W, abs=1e-4)


def test_describe_says_it_is_an_optimum(optimum):
    text = optimum.describe()
    assert text.startswith(f"optimal arm amplitude alpha* = {math.degrees(optimum.alpha):.3f} deg")
    assert "an interior minimum of W on [0, 45] deg" in text and "N m s" in text


def test_table_inertia_gives_an_end_point_not_an_optimum():
    planner = GaitPlanner("aoustin2013-table")
    result = optimal_arm_amplitude(planner, 0.45, 0.45, "normal", coarse_step=COARSE)
    assert result.where == END_POINT and not result.interior
    assert result.alpha == 0.0
    assert result.evaluations == 10  # no refinement
    text = result.describe()
    assert "has no interior minimum on [0, 45] deg" in text and "end point alpha = 0.000 deg" in text
    assert "This is not an optimum." in text


def test_mode_comparison_solves_the_anti_normal_gait_at_the_normal_optimum(optimum):
    comparison = compare_modes(load_params(), 0.45, 0.45, coarse_step=COARSE)
    assert comparison.optimum.alpha == pytest.approx(optimum.alpha, abs=DEFAULTS.arm_tolerance)
    anti = comparison.other
    assert anti.mode == "anti-normal" and anti.arm_amplitude == comparison.optimum.alpha
    assert anti.admissible and anti.figures.samples is not None


@pytest.mark.parametrize(
    "alpha_range, step, message",
    [
        ((0.5, 0.5), COARSE, "arm amplitude range is empty or inverted: [28.6479, 28.6479] deg"),
        ((0.5, 0.1), COARSE, "empty or inverted"),
        ((0.0, 0.5), 0.0, "arm amplitude range step must be positive"),
        ((0.0, 1.7), COARSE, "arm amplitude must be in [0, 90) deg"),
    ],
)
def test_bad_ranges_are_refused(planner, alpha_range, step, message):
    with pytest.raises(ValueError) as err:
        optimal_arm_amplitude(planner, 0.45, 0.45, "normal", alpha_range, step)
    assert message in str(err.value)


def test_no_admissible_gait_is_said_plainly(planner):
    with pytest.raises(NoAdmissibleGait, match=r"no admissible normal gait at L = 0.45 m, T = 1.5 s on \[0, 45\] deg"):
        optimal_arm_amplitude(planner, 0.45, 1.5, "normal", coarse_step=math.radians(45))
