"""The paper's claims (docs/model.md section 7), computed on a coarse grid with the default parameter
set and asserted; nothing here is a stored number, and a claim that stops holding fails.

At T = 0.45 s and L = 0.40, 0.45, 0.50 m, the normal gait's W(alpha) is bracketed on a 5 deg
continuation sweep over [0, 45] deg and refined (``mode_comparison.compare_modes``); the anti-normal
gait is solved at the normal gait's optimal alpha.

The yaw angular-momentum jump at the double support is |H(T+) - H(T-)| about the vertical
through the *new* stance foot: the same fixed axis before and after, so the jump is only what
the impulses of the double support change (about two different feet the difference would
mostly be the change of reference point).
"""

from __future__ import annotations

import math

import pytest

from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.gait.arm_optimum import ALPHA_RANGE
from biped_gait.studies.mode_comparison import compare_modes
from biped_gait.core.model.params import load_params

pytestmark = pytest.mark.studies

STEP_LENGTHS = (0.40, 0.45, 0.50)  # m
PERIOD = 0.45  # s
COARSE = math.radians(5.0)  # rad


@pytest.fixture(scope="module")
def comparisons():
    params = load_params()
    return [compare_modes(params, length, PERIOD, coarse_step=COARSE) for length in STEP_LENGTHS]


def jump(gait) -> float:
    """The module docstring's definition (kg m^2/s)."""
    return abs(gait.double_support.h_t_plus[1] - gait.double_support.h_t_minus[1])


@pytest.mark.parametrize("index", range(len(STEP_LENGTHS)))
def test_w_has_an_interior_minimum(planner, comparisons, index):
    optimum = comparisons[index].optimum
    assert optimum.interior, optimum.describe()
    for end in ALPHA_RANGE:
        at_end = planner.plan(GaitRequest(STEP_LENGTHS[index], PERIOD, end, "normal"))
        assert at_end.admissible and optimum.W < at_end.W - 0.1  # N m s: clearly below both ends


def test_optimal_alpha_grows_with_step_length(comparisons):
    alphas = [c.optimum.alpha for c in comparisons]
    assert all(b - a > 10 * DEFAULTS.arm_tolerance for a, b in zip(alphas, alphas[1:])), [math.degrees(a) for a in alphas]


def test_effort_grows_with_step_length(comparisons):
    efforts = [c.optimum.W for c in comparisons]
    assert all(b > a for a, b in zip(efforts, efforts[1:])), efforts


@pytest.mark.parametrize("index", range(len(STEP_LENGTHS)))
def test_anti_normal_costs_more_at_the_normal_optimum(comparisons, index):
    normal, anti = comparisons[index].optimum.gait, comparisons[index].other
    assert anti.admissible and anti.arm_amplitude == normal.arm_amplitude
    assert anti.W > normal.W, (anti.W, normal.W)


@pytest.mark.parametrize("index", range(len(STEP_LENGTHS)))
def test_momentum_jump_is_smaller_for_the_normal_gait(comparisons, index):
    normal, anti = comparisons[index].optimum.gait, comparisons[index].other
    assert jump(normal) < jump(anti), (jump(normal), jump(anti))
    assert normal.double_support.yaw_momentum_jump == jump(normal)  # the results page uses the same definition
