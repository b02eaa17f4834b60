"""The double support's options a reviewer would check: the friction cone holds on every
reaction impulse (and without it the paper's LP and its W return), a joint-rate bound is
respected, and the effort read on absolute link angles gives the paper's optimal amplitudes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.dynamics.impulses import friction_ratios
from biped_gait.core.model.params import load_params
from biped_gait.studies.mode_comparison import compare_modes

from .conftest import DEFAULT_REQUEST

pytestmark = pytest.mark.core


@pytest.mark.parametrize("mode", list(GaitMode))
@pytest.mark.parametrize("mu", [0.5, 0.3])
def test_the_friction_cone_holds_on_every_reaction_impulse(planner, mode, mu):
    gait = planner.plan(dataclasses.replace(DEFAULT_REQUEST, mode=mode, friction=mu))
    assert gait.converged and gait.double_support.impulses.success
    ratios = friction_ratios(gait.double_support.impulses)
    assert np.all(ratios <= mu + 1e-9), ratios
    assert np.array_equal(ratios, gait.double_support.impulse_friction_ratios)
    free = planner.plan(dataclasses.replace(DEFAULT_REQUEST, mode=mode, friction=math.inf))
    assert free.W <= gait.W + 1e-9  # the cone can only cost
    assert free.W == pytest.approx(31.58084 if mode is GaitMode.NORMAL else 32.6076, rel=1e-5)  # the paper's LP


def test_a_joint_rate_bound_is_respected_and_costs_effort(planner, default_gait):
    assert default_gait.double_support.max_intermediate_joint_rate > 12.0
    bounded = planner.plan(dataclasses.replace(DEFAULT_REQUEST, rate_bound=12.0))
    impulses = bounded.double_support.impulses
    rates = np.concatenate([impulses.xd_minus[5:], impulses.xd_plus[5:]])
    assert np.max(np.abs(rates)) <= 12.0 + 1e-9 and bounded.double_support.max_intermediate_joint_rate <= 12.0 + 1e-9
    assert bounded.W > default_gait.W
    assert not planner.plan(dataclasses.replace(DEFAULT_REQUEST, rate_bound=5.0)).admissible  # no solution


@pytest.mark.parametrize("length, paper", [(0.40, 21.1), (0.45, 23.5), (0.50, 25.76)])
def test_the_absolute_reading_gives_the_papers_optimal_amplitudes(length, paper):
    comparison = compare_modes(load_params(), length, 0.45,
                               options={"effort_coordinates": "absolute", "friction": math.inf})
    assert comparison.optimum.interior
    assert abs(math.degrees(comparison.optimum.alpha) - paper) < 1.0
    assert comparison.other.W > comparison.optimum.W
