"""The swing actuated at its two ends (core/gait/actuated_swing.py, docs/model.md section 15): each
end's equations of motion through Pinocchio, its dynamics integrated under its own torques, the
cycle's periodicity through the planner's flow, the torques within the joint table's limits, and the
limit tau -> 0 onto the impulsive cycle."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

from biped_gait.core.gait.actuated_swing import ActuatedSwingPlanner, SwingRequest, cycle_view
from biped_gait.core.gait.lasting import LastingRequest
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest

DEFAULT = GaitRequest(0.45, 0.45, math.radians(23.5))
SOLVER = 1e-6  # a thousand times IPOPT's 1e-9, in the unknowns' scales (the weight, 100 N m)
TAU = 0.1


@pytest.fixture(scope="module")
def planner() -> GaitPlanner:
    return GaitPlanner(modes=("normal",))


@pytest.fixture(scope="module")
def gait(planner):
    return planner.plan(DEFAULT)


@pytest.fixture(scope="module")
def swing(planner):
    return ActuatedSwingPlanner(planner.lasting)


@pytest.fixture(scope="module")
def cycle(swing, gait):
    """(tau, d) = (0.1, 0): the paper's instantaneous double support, its impulses spread over the
    swing's first and last tenth of a second."""
    return swing.cycle(gait, SwingRequest(TAU, LastingRequest(0.0)))


def test_each_actuated_end_holds_its_physics(planner, cycle):
    """At every sample of both ends: the single support's equations through Pinocchio's inverse
    dynamics (the stance tip's reaction on the root rows, the torques on the actuated joints, nothing
    on the others) within 1e-6 of m g; the reaction pressing within the floor's friction; the swing
    tip not below the ground; no torque above the joint table's effort limit."""
    assert cycle.success, cycle.message
    bm = planner.model
    weight, mu = bm.total_mass * bm.params.gravity, bm.params.friction
    limits = np.array([bm.coordinates[k].spec.limits.effort for k in bm.actuated])
    at = np.asarray(bm.ds_of_single)
    for end in (cycle.start, cycle.end):
        assert len(end.t) >= 11 and end.t[-1] - end.t[0] == pytest.approx(TAU)
        for x, xd, xdd, torque, force in zip(end.x, end.xd, end.xdd, end.torques, end.contact_forces):
            applied = np.zeros(bm.double_support.nv)
            applied[:3] = force
            applied[bm.ds_actuated] = torque
            generalized = pin.rnea(bm.double_support, bm.double_support_data, x, xd, xdd)
            assert np.max(np.abs(generalized - applied)) < 1e-6 * weight
            assert force[2] > 0.0 and np.hypot(force[0], force[1]) <= mu * force[2] + SOLVER * weight
            assert bm.swing_tip(x[at])[2] > -1e-9
            assert np.all(np.abs(torque) <= limits + SOLVER * 100)
    assert np.all(cycle.peak_torque <= limits + SOLVER * 100)
    assert cycle.friction_used <= mu + 1e-6


def test_the_collocation_is_the_dynamics(planner, cycle):
    """The actuated end of the swing integrated by SciPy under its own torques (quadratic through
    each interval's node, midpoint and node, as Hermite-Simpson's rule has them) from its first
    state, with Pinocchio's forward dynamics, ends where the program's end does: within the rule's
    error, 1e-4 rad and 1e-2 rad/s at h = 10 ms (it is fourth order: the error is about h^4 times
    the motion's fifth derivative)."""
    bm = planner.model
    model, data = bm.single, bm.single.createData()
    end = cycle.end
    at = np.asarray(bm.ds_of_single)
    t, torques = end.t, end.torques

    def torque(time: float) -> np.ndarray:
        k = min(int((time - t[0]) / (t[2] - t[0])), len(t) // 2 - 1)
        s = (time - t[2 * k]) / (t[2 * k + 2] - t[2 * k])
        g0, gm, g1 = torques[2 * k], torques[2 * k + 1], torques[2 * k + 2]
        return g0 * (1 - s) * (1 - 2 * s) + gm * 4 * s * (1 - s) + g1 * s * (2 * s - 1)

    def rhs(time, y):
        n = model.nq
        tau = np.zeros(n)
        tau[list(bm.actuated)] = torque(time)
        return np.concatenate([y[n:], pin.aba(model, data, y[:n], y[n:], tau)])

    y0 = np.concatenate([end.x[0, at], end.xd[0, at]])
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", rtol=1e-10, atol=1e-12)
    n = model.nq
    assert np.max(np.abs(sol.y[:n, -1] - end.x[-1, at])) < 1e-4
    assert np.max(np.abs(sol.y[n:, -1] - end.xd[-1, at])) < 1e-2


def test_the_cycle_is_periodic_and_lands_softly(planner, gait, cycle):
    """The ballistic part, flown by the planner's own shooting flow from the actuated start's end
    over T - 2 tau, reaches the actuated end's first state (the program's constraint, checked outside
    it); the next step starts from the double support's end, legs exchanged, state continuous; the
    touchdown is soft (both held impulses vanish: the actuated end brings the foot down at rest
    relative to what the held chain carries) and lands on the touchdown posture."""
    bm, exchange = planner.model, planner.hybrid.exchange
    at = np.asarray(bm.ds_of_single)
    nq = bm.nq
    period = gait.problem.period
    res = planner.flow.propagate(cycle.flow_start[:nq], cycle.flow_start[nq:], period - 2 * TAU)
    assert np.max(np.abs(res.q - cycle.end.x[0, at])) < 1e-7
    assert np.max(np.abs(res.qd - cycle.end.xd[0, at])) < 1e-6
    assert np.max(np.abs(cycle.end.x[-1, at] - gait.step.q_target)) < 1e-9
    assert np.max(np.abs(cycle.start.x[0, at] - exchange.matrix @ cycle.support.x[-1, at])) < 1e-9
    assert np.max(np.abs(cycle.start.xd[0, at] - exchange.matrix @ cycle.support.xd[-1, at])) < 1e-9
    assert np.max(np.abs(cycle.support.held_impact_impulses)) < 1e-6


def test_without_the_limits_the_effort_is_the_impulsive_cycles(planner, swing, gait, cycle):
    """With the effort limits lifted over the swing's ends the torques grow as 1/tau (kN m) and E
    stays within 1 % of the impulsive cycle's E(0+) (50.503 N m s; measured 50.270 to 50.280 from
    tau = 0.1 to 0.03 s, docs/model.md 15): the actuated ends are the impulses spread. Within the
    limits the same swing costs far more (88 N m s at tau = 0.1 s)."""
    limit = planner.lasting.limit(gait)
    free = swing.cycle(gait, SwingRequest(TAU, LastingRequest(0.0), within_limits=False), near=cycle)
    shorter = swing.cycle(gait, SwingRequest(0.085, LastingRequest(0.0), within_limits=False), near=free)
    assert free.success and shorter.success, (free.message, shorter.message)
    for c in (free, shorter):
        assert c.effort_l1 == pytest.approx(limit.effort_total, rel=0.01)
    assert shorter.peak_torque.max() > free.peak_torque.max() > 1000.0
    assert cycle.effort_l1 > 1.5 * free.effort_l1


def test_the_plan_json_carries_the_swing_phases(planner, cycle):
    """``swing_phases`` in the plan's JSON: both ends sampled at 11 instants or more in the plan's
    double-support coordinates; ``peak_torque`` per actuated joint; no NaN."""
    view = cycle_view(cycle)
    bm = planner.model
    for name in ("start", "end"):
        phase = view["swing_phases"][name]
        n = len(phase["t"])
        assert n >= 11
        assert np.shape(phase["X"]) == np.shape(phase["Xd"]) == np.shape(phase["Xdd"]) == (n, bm.double_support.nv)
        assert np.shape(phase["torques"]) == (n, len(bm.actuated)) and np.shape(phase["contact_forces"]) == (n, 3)
    assert view["peak_torque"] == pytest.approx(cycle.peak_torque.tolist())
    assert view["effort_total"] == pytest.approx(cycle.effort_l1)
    json.dumps(view, allow_nan=False)


@pytest.mark.parametrize("value", ["-0.1", "nan", "0.3"])
def test_a_bad_actuated_swing_is_one_line_and_exit_2(value):
    """A duration that is none, or not below half the period, is one line and exit 2."""
    proc = subprocess.run([sys.executable, "-m", "biped_gait.cli", "plan", "--actuated-swing", value],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().count("\n") == 0 and "actuated_swing must be" in proc.stderr
