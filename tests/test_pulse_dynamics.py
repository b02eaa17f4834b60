"""A torque pulse (core/walking/phases/pulse_dynamics.py, docs/model.md section 10): over a short
time it is the impulse it spreads, and the passive impact's reaction presses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.dynamics.hybrid import HybridStep, passive_impact
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.walking.phases.pulse_dynamics import cone_rows, pulse

pytestmark = pytest.mark.core


@pytest.fixture(scope="module")
def planned():
    planner = GaitPlanner("aoustin2013", modes=("normal",))
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5), "normal"))
    return gait, HybridStep(planner.model)


def test_a_short_pulse_is_the_impulse(planned):
    """The pre-impact pulse of I^- over a short time gives the LP's Xd^- and its reaction impulse."""
    gait, hybrid = planned
    impulses, half = gait.double_support.impulses, 5e-6
    torque = np.zeros(hybrid.bm.nq)
    torque[hybrid.bm.actuated] = impulses.i_minus / half
    _, qd, forces = pulse(hybrid, gait.step.q_target, gait.step.qd_b, torque, half)
    assert np.max(np.abs(qd - impulses.xd_minus[3:])) < 1e-3 * np.max(np.abs(impulses.xd_minus))
    assert np.mean(forces, axis=0) * half == pytest.approx(impulses.ir1_minus, rel=1e-3)


def test_the_passive_impact_presses_and_lets_the_old_foot_go(planned):
    """Eqs. (8)-(9) from the LP's Xd^- (after I^-): the new foot's reaction presses within the
    floor's cone, the old foot leaves, and the velocity is the LP's Xd^+."""
    gait, hybrid = planned
    impulses = gait.double_support.impulses
    landing = passive_impact(hybrid.impact(gait.step.q_target), impulses.xd_minus[3:])
    assert np.all(cone_rows(landing.reaction, hybrid.bm.params.friction) <= 1e-9)
    assert landing.old_foot_vz >= -1e-9
    assert np.max(np.abs(landing.xd_plus - impulses.xd_plus)) < 1e-9 * max(1.0, np.max(np.abs(impulses.xd_plus)))
