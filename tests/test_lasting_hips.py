"""The lasting double support with lateral hip joints (aoustin2013-hips, core/gait/lasting.py,
docs/model.md section 14): the periodic cycle at d = 0.1 s checked through Pinocchio, the model's
own leg exchange and the planner's flow, independently of the program's symbols; the CLI; and the
cycle walked by the hybrid engine. Then the swing actuated at its two ends for the same set
(core/gait/actuated_swing.py, docs/model.md section 15), started from that cycle, checked the same
way."""

from __future__ import annotations

import contextlib
import io
import math

import numpy as np
import pinocchio as pin
import pytest

from biped_gait.cli import main as cli_main
from biped_gait.core.gait.actuated_swing import ActuatedSwingPlanner, SwingRequest
from biped_gait.core.gait.lasting import LastingRequest
from biped_gait.core.gait.lasting_support import IMPULSE_TIME
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.model.biped import STANCE_SPIN, BipedModel
from biped_gait.core.model.exchange import MIRROR
from biped_gait.core.model.mjcf import TORSIONAL_FRICTION
from biped_gait.core.walking.held_support import lasting_orbit
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker

from .lasting_steps import check_lasting_step

DEFAULT = GaitRequest(0.45, 0.45, math.radians(23.5))
SOLVER = 1e-6  # as tests/test_lasting.py: a thousand times IPOPT's 1e-9 in the unknowns' units
STEP = 1e-6  # rad, m: the heading's central differences (their error about 1e-12 rad per unit)
TAU = 0.1  # s, each actuated end of the swing


@pytest.fixture(scope="module")
def planned():
    """``biped-gait plan --params aoustin2013-hips --double-support 0.1`` run in this process: its
    exit status and printout, and the planner, gait and cycle its ``GaitPlanner.lasting_cycle``
    returned (recorded on their way through, unchanged). The module's one solve of the cycle: the
    tests below check the very cycle the command summed up."""
    made = []
    lasting_cycle = GaitPlanner.lasting_cycle

    def recorded(planner, gait, request):
        support, limit = lasting_cycle(planner, gait, request)
        made.append((planner, gait, request, support))
        return support, limit

    printed = io.StringIO()
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stdout(printed):
        patch.setattr(GaitPlanner, "lasting_cycle", recorded)
        status = cli_main(["plan", "--params", "aoustin2013-hips", "--double-support", "0.1"])
    [(planner, gait, request, cycle)] = made
    # the command's defaults are the paper's gait (DEFAULT), normal, its request the walkable cycle's
    assert (gait.params, gait.mode.value, gait.step_length, gait.period) == ("aoustin2013-hips", "normal", 0.45, 0.45)
    assert gait.arm_amplitude == pytest.approx(DEFAULT.arm_amplitude, abs=1e-15)
    assert request == LastingRequest.walkable(0.1)
    return status, printed.getvalue(), planner, gait, cycle


@pytest.fixture(scope="module")
def planner(planned) -> GaitPlanner:
    return planned[2]


@pytest.fixture(scope="module")
def gait(planned):
    return planned[3]


@pytest.fixture(scope="module")
def cycle(planned):
    return planned[4]


def _heading(bm: BipedModel, x: np.ndarray) -> float:
    """The new stance shin's heading (rad) at X through Pinocchio: its mirror image's z angle in the
    zxy decomposition (as ``KinematicExchange._landing``)."""
    data = bm.double_support.createData()
    pin.forwardKinematics(bm.double_support, data, x)
    landing = MIRROR @ data.oMi[bm.double_support.getJointId(bm.names[bm.index("knee", "swing")])].rotation @ MIRROR
    return math.atan2(-landing[0, 1], landing[1, 1])


def _heading_row(bm: BipedModel, x: np.ndarray) -> np.ndarray:
    eye = np.eye(len(x))
    return np.array([(_heading(bm, x + STEP * e) - _heading(bm, x - STEP * e)) / (2 * STEP) for e in eye])


def test_the_hips_cycle_holds_its_physics(planner, gait, cycle):
    """At every sample: the double-support model's inverse dynamics (Pinocchio) equal the torques and
    both feet's reactions, each a force at its tip and a spin moment (the old foot's on its spin
    coordinate, the new one's on its heading), within 1e-6 of m g; the new tip held in x, y, z and
    its heading; the old foot not spinning; both forces pressing within the friction pyramid (the
    walkable margins: 50 N, mu - 0.1), both spin moments within the torsional friction (the held
    impact's too); every torque within its limit."""
    assert cycle.success, cycle.message
    bm = planner.model
    weight = bm.total_mass * bm.params.gravity
    spin = bm.ds_names.index(STANCE_SPIN)
    at = np.asarray(bm.ds_of_single)
    q_t = gait.step.q_target
    x_t = bm.ds_state(q_t)
    tip, heading = bm.swing_tip(q_t), _heading(bm, x_t)
    limits = np.array([bm.coordinates[k].spec.limits.effort for k in bm.actuated])
    mu = bm.params.friction - 0.1
    moments_old, moments_new = cycle.spin_moments[0][:, 0], cycle.spin_moments[0][:, 1]
    assert len(cycle.t) >= 21 and cycle.t[-1] == pytest.approx(0.1)
    for k, (x, xd, xdd, torque, forces) in enumerate(zip(cycle.x, cycle.xd, cycle.xdd, cycle.torques,
                                                          cycle.contact_forces)):
        assert x[spin] == 0.0 and xd[spin] == 0.0 and xdd[spin] == 0.0
        generalized = pin.rnea(bm.double_support, bm.double_support_data, x, xd, xdd)
        j1, j2 = bm.tip_jacobians(x[at])
        applied = j1.T @ forces[0] + j2.T @ forces[1] + _heading_row(bm, x) * moments_new[k]
        applied[spin] += moments_old[k]
        applied[bm.ds_actuated] += torque
        assert np.max(np.abs(generalized - applied)) < 1e-6 * weight
        # Held at the acceleration: the rule's error (measured 2.6e-5 m and 3.5e-8 rad at most).
        assert np.abs(bm.swing_tip(x[at]) - tip).max() < 1e-4
        assert abs(_heading(bm, x) - heading) < 1e-6
        assert np.all(forces[:, 2] >= 50.0 - SOLVER * weight)
        assert np.all(np.hypot(forces[:, 0], forces[:, 1]) <= mu * forces[:, 2] + SOLVER * weight)
        assert np.all(np.abs(torque) <= limits + SOLVER * 100)
        spin_moments = np.array([moments_old[k], moments_new[k]])
        assert np.all(np.abs(spin_moments) <= TORSIONAL_FRICTION * forces[:, 2] + SOLVER * weight)
    assert cycle.friction_used <= mu + 1e-6
    held = cycle.held_impact_impulses
    assert np.all(np.abs(cycle.spin_moments[1]) <= TORSIONAL_FRICTION * held[:, 2] + SOLVER * weight * IMPULSE_TIME)


def test_the_hips_cycle_is_periodic_and_straight(planner, gait, cycle):
    """The next step, from the lift-off posture through the model's kinematic leg exchange and the
    cycle's next start velocity, flown by the planner's shooting flow, lands on the touchdown
    posture in T; the exchange turns the next step's frame by nothing (a straight walk), and the
    velocity after I^+ is the exchange's image of the next start (the new tip at rest)."""
    bm, exchange = planner.model, planner.hybrid.exchange
    at = np.asarray(bm.ds_of_single)
    q_lift = cycle.x[-1][at]
    assert abs(exchange.heading(q_lift)) < 1e-6  # held at the acceleration: the rule's error (3e-8 measured)
    res = planner.flow.propagate(exchange.configuration(q_lift), cycle.next_start_velocity, gait.problem.period)
    assert np.max(np.abs(res.q - gait.step.q_target)) < 1e-7
    assert np.max(np.abs(q_lift - gait.step.q_target)) > 1e-3  # the lift-off posture is not the touchdown's
    _, j2 = bm.tip_jacobians(q_lift)
    xd_a = exchange.next_velocity(q_lift, j2, cycle.next_start_velocity)
    assert np.max(np.abs(j2 @ xd_a)) < 1e-7 and abs(exchange.spin_row(q_lift) @ xd_a) < 1e-7
    assert np.max(np.abs(exchange.velocity(q_lift, xd_a) - cycle.next_start_velocity)) < 1e-7


def test_the_plan_answers_for_the_hips(planned):
    """``biped-gait plan --double-support 0.1`` for the 13-joint set: the lasting cycle's summary."""
    status, printed = planned[:2]
    assert status == 0, printed
    assert "double support of 0.1 s: E = " in printed, printed


def test_the_hips_cycle_is_walked_twenty_steps(planner, gait, cycle):
    """The walkable cycle walked by the hybrid engine from its lift-off (core/walking/phases/lasting.py,
    the double support tracked with both feet held in x, y, z and heading, the kinematic leg
    exchange at each lift-off): twenty steps without a fall, each lasting T + d, both feet pressing
    in every sample of each double support, every torque within the joints' 200 N m; the touchdowns
    stay near the plan's (docs/model.md 14.1: within 1.2e-3 rad/s over 20 steps on the mesh of
    ``LATERAL_HIPS_PERIODIC``; the bound is a tenth of the 0.14 rad/s the 20-interval plan drifted to
    before its fall, so a plan whose mesh the walk cannot follow fails here)."""
    orbit = lasting_orbit(PlannedOrbit.of(gait), cycle, planner.hybrid)
    walker = Walker(planner.hybrid, orbit, 100.0)
    outcomes = [walker.walk_step() for _ in range(20)]
    for k, outcome in enumerate(outcomes):
        check_lasting_step(k, outcome, gait.problem.period + 0.1, 0.1, 100.0)
    errors = [outcome.touchdown.state_error for outcome in outcomes]
    assert errors[0] < 1e-8 and max(errors) < 0.014


@pytest.fixture(scope="module")
def swing(planner, gait, cycle):
    """(tau, d) = (0.1, 0.1) s at the default gait, the least effort (``plan --actuated-swing 0.1
    --double-support 0.1``'s request), started from the module's lasting cycle: about a minute on
    the project's 2-core machine (docs/model.md 15)."""
    return ActuatedSwingPlanner(planner.lasting).cycle(gait, SwingRequest(TAU, LastingRequest(0.1)), seed=cycle)


def test_the_hips_actuated_swing_holds_its_physics(planner, swing):
    """At every sample of both actuated ends: the single support's equations through Pinocchio's
    inverse dynamics, the stance tip's force applied through its Jacobian and the foot's spin moment
    on its spin coordinate, within 1e-6 of m g; the force pressing within the friction pyramid and the
    spin moment within the torsional friction; the swing tip not below the ground; no torque above
    its limit (N m; at it on most joints: measured 200 on all but the stance hip's yaw, 46, and the
    swing knee, 140)."""
    assert swing.success, swing.message
    bm = planner.model
    weight, mu = bm.total_mass * bm.params.gravity, bm.params.friction
    spin = bm.ds_names.index(STANCE_SPIN)
    at = np.asarray(bm.ds_of_single)
    limits = np.array([bm.coordinates[k].spec.limits.effort for k in bm.actuated])
    for end in (swing.start, swing.end):
        assert len(end.t) >= 11 and end.t[-1] - end.t[0] == pytest.approx(TAU)
        for x, xd, xdd, torque, force, moment in zip(end.x, end.xd, end.xdd, end.torques, end.contact_forces,
                                                     end.spin_moments):
            generalized = pin.rnea(bm.double_support, bm.double_support_data, x, xd, xdd)
            applied = bm.tip_jacobians(x[at])[0].T @ force
            applied[spin] += moment
            applied[bm.ds_actuated] += torque
            assert np.max(np.abs(generalized - applied)) < 1e-6 * weight
            assert force[2] > 0.0 and np.hypot(force[0], force[1]) <= mu * force[2] + SOLVER * weight
            assert abs(moment) <= TORSIONAL_FRICTION * force[2] + SOLVER * weight
            assert bm.swing_tip(x[at])[2] > -1e-9
            assert np.all(np.abs(torque) <= limits + SOLVER * 100)
    assert np.all(swing.peak_torque <= limits + SOLVER * 100)


def test_the_hips_actuated_swing_is_periodic(planner, gait, swing):
    """The ballistic part, flown by the planner's flow from the actuated start's end over T - 2 tau,
    reaches the actuated end's first state; the end lands on the touchdown posture, softly (both held
    impulses vanish); the next step starts from the double support's end through the model's
    kinematic leg exchange (``KinematicExchange``: the joint map and the landing shin's roll and pitch,
    computed apart from the program's symbols), the state continuous."""
    bm, exchange = planner.model, planner.hybrid.exchange
    at, nq = np.asarray(bm.ds_of_single), bm.nq
    period = gait.problem.period
    res = planner.flow.propagate(swing.flow_start[:nq], swing.flow_start[nq:], period - 2 * TAU)
    assert np.max(np.abs(res.q - swing.end.x[0, at])) < 1e-7
    assert np.max(np.abs(res.qd - swing.end.xd[0, at])) < 1e-6
    assert np.max(np.abs(swing.end.x[-1, at] - gait.step.q_target)) < 1e-9
    assert np.max(np.abs(swing.support.held_impact_impulses)) < 1e-6
    lift_off = swing.support.x[-1, at]
    assert np.max(np.abs(swing.start.x[0, at] - exchange.configuration(lift_off))) < 1e-9
    assert np.max(np.abs(swing.start.xd[0, at] - exchange.velocity(lift_off, swing.support.xd[-1]))) < 1e-7
