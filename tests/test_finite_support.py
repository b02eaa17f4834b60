"""The planned double support of duration d (docs/model.md section 10): exactly periodic, its
contacts admissible over the whole phase, and its effort tending to the impulsive W as d -> 0."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.dynamics.hybrid import HybridStep
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.walking.finite_support import (SLACK, TOLERANCE, _Periodic, passive_impact,
                                                     plan_finite_support, pulse)

pytestmark = pytest.mark.core


@pytest.fixture(scope="module")
def planned():
    planner = GaitPlanner("aoustin2013")
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5), "normal"))
    hybrid = HybridStep(planner.model)
    return gait, hybrid, {d: plan_finite_support(hybrid, gait, d) for d in (1e-4, 2.5e-4)}


def test_a_short_pulse_is_the_impulse(planned):
    """The pre-impact pulse of I^- over a short time gives the LP's Xd^- and its reaction impulse."""
    gait, hybrid, _ = planned
    impulses, half = gait.double_support.impulses, 5e-6
    torque = np.zeros(hybrid.bm.nq)
    torque[hybrid.bm.actuated] = impulses.i_minus / half
    _, qd, forces = pulse(hybrid, gait.step.q_target, gait.step.qd_b, torque, half)
    assert np.max(np.abs(qd - impulses.xd_minus[3:])) < 1e-3 * np.max(np.abs(impulses.xd_minus))
    assert np.mean(forces, axis=0) * half == pytest.approx(impulses.ir1_minus, rel=1e-3)


def test_the_finite_double_support_is_periodic_and_admissible(planned):
    gait, hybrid, plans = planned
    for d, plan in plans.items():
        assert plan.residual < TOLERANCE
        eq = _Periodic(hybrid, gait, d)
        z = np.concatenate([plan.v0, [plan.theta], plan.u_plus, plan.u_minus])
        residual, constraints, _ = eq.evaluate(z)
        assert np.max(np.abs(residual)) < TOLERANCE
        assert np.max(constraints) <= 1e-9  # cones, normal forces, the old foot leaving, the swing foot arriving
        assert plan.friction_needed <= hybrid.bm.params.friction + 1e-9
        landing = passive_impact(hybrid.impact(plan.q_t), plan.qd_t)
        assert landing.reaction[2] > 0 and landing.old_foot_vz >= -1e-9


def test_the_effort_tends_to_w(planned):
    """E(d) -> W: within 1e-4 of W at 0.1 ms, and the gap shrinking with d."""
    gait, _, plans = planned
    gaps = {d: abs(plan.effort - gait.W) for d, plan in plans.items()}
    assert gaps[1e-4] < 1e-4 * gait.W
    assert gaps[1e-4] < gaps[2.5e-4]
    # the torques are the impulses spread over d / 2: large, and falling as 1 / d
    assert plans[1e-4].peak_torque > 1e5 and plans[1e-4].peak_torque > 2 * plans[2.5e-4].peak_torque


def test_a_millisecond_double_support_is_planned_where_the_linear_programs_stall(planned):
    """At d = 1 ms the sequential LPs stall; Gauss-Newton finds the periodic phase and the descent
    along the periodic phases brings its effort to within 1 % of W (measured 32.94 after 4 steps,
    32.90 after 8, against W = 32.78 N m s)."""
    gait, hybrid, _ = planned
    plan = plan_finite_support(hybrid, gait, 1e-3, descent_steps=4)
    assert not plan.minimized and plan.residual < TOLERANCE
    eq = _Periodic(hybrid, gait, 1e-3)
    _, constraints, _ = eq.evaluate(np.concatenate([plan.v0, [plan.theta], plan.u_plus, plan.u_minus]))
    assert np.max(constraints) <= SLACK
    assert gait.W < plan.effort < 1.01 * gait.W
    assert plan.friction_needed <= hybrid.bm.params.friction + 1e-6
