"""The double support that lasts (core/gait/lasting.py, docs/model.md section 14): the CasADi model
against Pinocchio, the impulsive limit E(0+), and the periodic cycle at d = 0.1 s checked through
Pinocchio and the planner's own flow, independently of the program's symbols."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.dynamics.closed_chain import ClosedChain
from biped_gait.core.dynamics.symbolic import SymbolicModel
from biped_gait.core.gait import views
from biped_gait.core.gait.lasting import LastingRequest
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.model.biped import SWING_TIP, BipedModel
from biped_gait.core.model.params import load_params
from biped_gait.core.walking.balance import standing_pose
from biped_gait.core.walking.held_support import held_support

DEFAULT = GaitRequest(0.45, 0.45, math.radians(23.5))
# IPOPT's tolerance is 1e-9 on the scaled equations; what the checks below allow is a thousand times
# that in the units of each (the unknowns' scales: the weight for forces, 100 N m for torques).
SOLVER = 1e-6


@pytest.fixture(scope="module")
def planner() -> GaitPlanner:
    return GaitPlanner(modes=("normal",))


@pytest.fixture(scope="module")
def gait(planner):
    return planner.plan(DEFAULT)


@pytest.fixture(scope="module")
def cycle(planner, gait):
    return planner.lasting.periodic(gait, LastingRequest(0.1))


@pytest.mark.parametrize("name", ["aoustin2013", "aoustin2013-hips"])
def test_the_symbolic_model_is_pinocchios(name):
    """RNEA and the swing tip's position in CasADi's symbols agree with Pinocchio's at random states
    (both sums of the same products: to rounding)."""
    model = BipedModel.from_params(load_params(name)).double_support
    data = model.createData()
    symbolic = SymbolicModel(model)
    q, v, a = ca.SX.sym("q", model.nq), ca.SX.sym("v", model.nv), ca.SX.sym("a", model.nv)
    f = ca.Function("f", [q, v, a], [symbolic.rnea(q, v, a), symbolic.frame_position(q, SWING_TIP)])
    rng = np.random.default_rng(7)
    for _ in range(5):
        x, xd, xdd = rng.normal(size=model.nq), rng.normal(size=model.nv), 5 * rng.normal(size=model.nv)
        tau, tip = (np.array(out).ravel() for out in f(x, xd, xdd))
        expected = pin.rnea(model, data, x, xd, xdd)
        pin.framesForwardKinematics(model, data, x)
        assert np.max(np.abs(tau - expected)) <= 1e-11 * max(1.0, np.max(np.abs(expected)))
        assert np.max(np.abs(tip - data.oMf[model.getFrameId(SWING_TIP)].translation)) <= 1e-13


def test_the_impulsive_limit_lands_softly(planner, gait):
    """d -> 0+: I^-, the held impact, I^+, the held velocity one the closed chain can carry. Its
    optimum makes both held impulses vanish (a soft landing) and its effort E(0+) is the value
    measured (docs/model.md 14: 50.503 N m s; IPOPT's tolerance moves it by less than 1e-6)."""
    limit = planner.lasting.limit(gait)
    assert limit.success, limit.message
    assert limit.effort_total == pytest.approx(50.50267, abs=1e-4)
    assert np.max(np.abs(limit.held_impact_impulses)) < SOLVER
    assert limit.effort_total > gait.W  # the held impact costs beyond the paper's double support


def _pinocchio_residual(bm: BipedModel, q, xd, xdd, torque, forces) -> tuple[float, float]:
    """The closed chain's equations at one sample through Pinocchio (N, N m): the double-support
    model's inverse dynamics less the torques and both tips' forces as section 12 has them (the new
    tip's lateral force internal between the feet: its Jacobian row over q left out); and what that
    row would add, second order in the ankle roll q1 (zero at q1 = 0)."""
    x = bm.ds_state(q)
    generalized = pin.rnea(bm.double_support, bm.double_support_data, x, xd, xdd)
    j1, j2 = bm.tip_jacobians(q)
    lateral = np.abs(j2[1] * forces[1][1])[bm.ds_of_single].max()
    j2 = j2.copy()
    j2[1, bm.ds_of_single] = 0.0
    applied = j1.T @ forces[0] + j2.T @ forces[1]
    applied[bm.ds_actuated] += torque
    return float(np.max(np.abs(generalized - applied))), float(lateral)


def test_the_periodic_cycle_holds_its_physics(planner, gait, cycle):
    """At d = 0.1 s: the closed chain's equations at every sample within 1e-6 of m g (Pinocchio's,
    not the program's symbols), the new tip held, both reactions pressing within the floor's
    friction, every torque within its limit."""
    assert cycle.success, cycle.message
    bm = planner.model
    weight = bm.total_mass * bm.params.gravity
    assert len(cycle.t) >= 21 and cycle.t[0] == 0.0 and cycle.t[-1] == pytest.approx(0.1)
    at = np.asarray(bm.ds_of_single)
    tip = bm.swing_tip(gait.step.q_target)
    limits = np.array([bm.coordinates[k].spec.limits.effort for k in bm.actuated])
    mu = bm.params.friction
    for x, xd, xdd, torque, forces in zip(cycle.x, cycle.xd, cycle.xdd, cycle.torques, cycle.contact_forces):
        q = x[at]
        residual, lateral = _pinocchio_residual(bm, q, xd, xdd, torque, forces)
        assert residual < 1e-6 * weight
        assert lateral < 1e-3 * weight
        assert np.abs(bm.swing_tip(q)[[0, 2]] - tip[[0, 2]]).max() < 1e-5  # Hermite-Simpson's midpoints
        assert abs(bm.swing_tip(q)[1] - tip[1]) < 1e-3  # the lateral row: second order in q1
        assert np.all(forces[:, 2] > -SOLVER * weight)
        assert np.all(np.hypot(forces[:, 0], forces[:, 1]) <= mu * forces[:, 2] + SOLVER * weight)
        assert np.all(np.abs(torque) <= limits + SOLVER * 100)
    assert cycle.friction_used <= mu + 1e-6


def test_the_cycle_is_periodic(planner, gait, cycle):
    """The next step, flown by the planner's own shooting flow from the lift-off posture exchanged
    and the cycle's next start velocity, lands on the touchdown posture in T (the program's
    constraint, 1e-9 rad, checked outside it)."""
    bm, exchange = planner.model, planner.hybrid.exchange
    q_lift = cycle.x[-1][np.asarray(bm.ds_of_single)]
    res = planner.flow.propagate(exchange.configuration(q_lift), cycle.next_start_velocity, gait.problem.period)
    assert np.max(np.abs(res.q - gait.step.q_target)) < 1e-7
    assert np.max(np.abs(q_lift - gait.step.q_target)) > 1e-3  # the lift-off posture is not the touchdown's


def test_a_refused_double_support_says_why(planner, gait):
    """A duration that is not one is refused before solving."""
    with pytest.raises(ValueError, match="duration >= 0"):
        LastingRequest(-0.1)


def test_the_plan_json_carries_the_phase(cycle):
    """The plan's ``double_support_phase`` (views.double_support_phase): the samples in the
    double-support coordinates, both tips' forces, the efforts."""
    phase = views.double_support_phase(cycle, 50.486)
    n = len(phase["t"])
    assert n >= 21 and phase["t"][0] == 0.0
    assert np.shape(phase["X"]) == np.shape(phase["Xd"]) == np.shape(phase["Xdd"]) == (n, 12)
    assert np.shape(phase["torques"]) == (n, 7) and np.shape(phase["contact_forces"]) == (n, 2, 3)
    assert np.shape(phase["held_impact_impulses"]) == (2, 3)
    assert phase["effort_total"] == pytest.approx(sum(map(abs, phase["i_minus"])) + sum(map(abs, phase["i_plus"]))
                                                  + phase["effort_l1"])
    assert phase["effort_impulsive_limit"] == 50.486
    json.dumps(phase, allow_nan=False)


@pytest.mark.parametrize("value", ["-0.1", "nan", "inf"])
def test_a_bad_duration_is_one_line_and_exit_2(value):
    proc = subprocess.run([sys.executable, "-m", "biped_gait.cli", "plan", "--double-support", value],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "double_support must be a duration >= 0 s" in proc.stderr


@pytest.fixture(scope="module")
def rest(planner):
    chain = ClosedChain(planner.model, planner.hybrid.exchange)
    return standing_pose(chain, DEFAULT.step_length).q


@pytest.mark.parametrize("kind", ["stop", "start"])
def test_a_stop_and_a_start_over_one_second(planner, gait, rest, kind):
    """From the gait's touchdown to rest in the standing posture on the same feet, and from it onto
    the gait, each over 1 s: the closed chain's equations through Pinocchio, the reactions pressing
    within the friction pyramid, the torques within their limits, and the phase at rest at its end
    (the stop) or its start (the start)."""
    support = getattr(planner.lasting, kind)(gait, LastingRequest(1.0), rest)
    assert support.success, support.message
    bm = planner.model
    weight = bm.total_mass * bm.params.gravity
    at = np.asarray(bm.ds_of_single)
    still = -1 if kind == "stop" else 0
    assert np.max(np.abs(support.xd[still])) < 1e-9 and np.max(np.abs(support.x[still][at] - rest)) < 1e-9
    limits = np.array([bm.coordinates[k].spec.limits.effort for k in bm.actuated])
    for x, xd, xdd, torque, forces in zip(support.x, support.xd, support.xdd, support.torques, support.contact_forces):
        residual, _ = _pinocchio_residual(bm, x[at], xd, xdd, torque, forces)
        assert residual < 1e-6 * weight
        assert np.all(forces[:, 2] > -SOLVER * weight)
        assert np.all(np.abs(torque) <= limits + SOLVER * 100)
    assert support.friction_used <= bm.params.friction + 1e-6
    # Not yet walkable (docs/model.md 14): 10 intervals of 0.1 s do not resolve the phase, its
    # reactions between the collocation points pull by kilonewtons, and a walk refuses the plan.
    with pytest.raises(ValueError, match="cannot be tracked: its reactions between its collocation points"):
        held_support(ClosedChain(bm, planner.hybrid.exchange), support)
