"""The swing actuated at its two ends, walked in the hybrid engine (core/walking/phases/actuated.py,
core/walking/swing_ends.py, core/walking/reaction_guard.py, docs/model.md section 15.1): the
reference of each actuated end resolved between its collocation points and flown by MuJoCo through
its motors, their control ranges enforced, as by the planner's model; the actuated start tracked
from the plan's lift-off, the first step landed, held and lifted off with the state continuous,
twenty steps walked; and what in the plan keeps its timing from being freed (the swing tip comes
down on the ground twice in the actuated end, tangentially; the passive ankle's pitch peaks before
the touchdown).

The plan (``SwingRequest.walkable``: 20 intervals over each end, the torques within their limits
between the points, the double support's margins) is solved once, (tau, d) = (0.1, 0.1) s at the
default gait: about 55 s on the project's 2-core machine; the twenty steps take about 45 s."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from biped_gait.core.gait.actuated_swing import SwingRequest
from biped_gait.core.gait.lasting import WALK_LEAST_NORMAL_FORCE
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.model.mjcf import make_mjcf
from biped_gait.core.walking.events import DOUBLE_SUPPORT
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.phases.actuated import ActuatedStart, ContinuousLiftOff
from biped_gait.core.walking.phases.phase import AT, End
from biped_gait.core.walking.phases.pulse_dynamics import cone_rows, friction_ratio
from biped_gait.core.walking.reaction_guard import GUARD_LEAST_NORMAL_FORCE
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.swing_ends import actuated_orbit

TAU = DURATION = 0.1  # s
RATE = 1000.0  # samples per second: every RK4 step
LIMIT = 200.0  # N m, the joint table's effort


@pytest.fixture(scope="module")
def planned():
    planner = GaitPlanner(modes=("normal",))
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5)))
    cycle = planner.swing_cycle(gait, SwingRequest.walkable(TAU, DURATION))  # kept for the simulator's test
    assert cycle.success, cycle.message
    return planner, cycle, actuated_orbit(PlannedOrbit.of(gait), cycle, planner.hybrid)


def walker(planned) -> Walker:
    planner, _, orbit = planned
    return Walker(planner.hybrid, orbit, RATE, phase=ActuatedStart(orbit.swing_ends.start, 0.0))


def test_the_reference_resolves_the_swing_ends(planned):
    """Along each actuated end's reference, every millisecond, the single support's forward dynamics
    under the plan's torques (``PinnedTip``; Hermite-Simpson's quadratic torques between the points)
    give the plan's own reactions at its collocation points (within 1e-6 m g: the program's
    tolerance) and between them press within the floor's pyramid: measured 174.0 N (start) and
    127.3 N (end) at the least, friction ratios 0.393 and 0.409 against the plan's 0.4 at its points
    (the ringing between them); the torques within 200 N m between the points too (the plan's
    Bernstein bound). The double support's reference keeps 0.9 of its points' 50 N."""
    planner, cycle, orbit = planned
    bm = planner.model
    weight = bm.total_mass * bm.params.gravity
    for which, least in (("start", 170.0), ("end", 120.0)):
        _, forces = orbit.swing_ends.reactions(which)
        assert forces[:, 2].min() > least
        assert friction_ratio(forces) < 0.42 and np.max(cone_rows(forces, bm.params.friction)) < 0.0
        reference, planned_end = getattr(orbit.swing_ends, which), getattr(cycle, which)
        for t, force in zip(reference.t, planned_end.contact_forces):
            q, qd, torque = reference.reference(t)
            assert np.max(np.abs(reference.chain.forward(q, qd, torque)[1] - force)) < 1e-6 * weight
        assert max(np.abs(reference.torque(t)).max() for t in np.linspace(0.0, TAU, 1001)) <= LIMIT + 1e-6 * 100
    assert orbit.double_support.least_normal_force() > 0.9 * WALK_LEAST_NORMAL_FORCE


def test_mujoco_flies_each_actuated_end_with_its_motors_within_their_limits(planned):
    """Each actuated end flown open loop from the plan's first state under the plan's torques
    (Hermite-Simpson's quadratics) by two engines: MuJoCo's RK4 on the exported stance tree, the
    torques through its motors, whose control ranges (200 N m) are enforced (the joint ranges off,
    as the planner's), held over each 10 us step at its midpoint; and SciPy's DOP853 on the
    planner's model (``PinnedTip``). Measured: 4.9e-7 rad and 5.0e-6 rad/s apart at the start's
    end, 2.0e-7 and 6.6e-6 at the end's (the hold's error, a hundredth of what 100 us steps give);
    no control clipped by more than 1e-7 N m (the plan's bound is kept to IPOPT's tolerance); the
    plan itself 4e-5 rad and 1.1e-3 rad/s from both (its mesh)."""
    planner, _, orbit = planned
    bm = planner.model
    model = mujoco.MjModel.from_xml_string(make_mjcf(bm.params, "stance"))
    assert [model.actuator(i).name for i in range(model.nu)] == list(bm.actuated_names)
    assert model.actuator_ctrllimited.all() and np.all(model.actuator_ctrlrange == [-LIMIT, LIMIT])
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    model.opt.timestep = h = 1e-5  # s
    n = bm.nq
    for which in ("start", "end"):
        reference = getattr(orbit.swing_ends, which)
        q0, qd0, _ = reference.reference(0.0)
        data = mujoco.MjData(model)
        data.qpos[:], data.qvel[:] = q0, qd0
        clipped = 0.0
        for k in range(round(reference.duration / h)):
            data.ctrl[:] = torque = reference.torque((k + 0.5) * h)
            mujoco.mj_step(model, data)
            clipped = max(clipped, np.abs(data.actuator_force - torque).max())

        def flow(t, y, reference=reference):
            return np.concatenate([y[n:], reference.chain.forward(y[:n], y[n:], reference.torque(t))[0]])

        y = solve_ivp(flow, (0.0, reference.duration), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-11,
                      atol=1e-12).y[:, -1]
        assert np.abs(data.qpos - y[:n]).max() < 1e-5 and np.abs(data.qvel - y[n:]).max() < 1e-4
        assert clipped < 1e-6
        q_plan, qd_plan, _ = reference.reference(reference.duration)
        assert np.abs(y[:n] - q_plan).max() < 1e-4 and np.abs(y[n:] - qd_plan).max() < 3e-3


def test_the_actuated_start_tracks_the_plan(planned):
    """From the plan's lift-off the actuated start, the plan's torques and the swing's LQR (guarded),
    stays within 1 mrad and 0.02 rad/s of the plan (measured 0.22 mrad and 3.5 mrad/s; 1.4e-5 rad and
    6e-5 rad/s at its end), every torque within 200 N m, the stance tip's reaction within the
    pyramid at every sample."""
    _, _, orbit = planned
    start = orbit.swing_ends.start
    run = walker(planned).run_phase()
    assert not run.fall and len(run.samples) == round(TAU * RATE) + 1
    for sample in run.samples:
        q_ref, qd_ref, _ = start.reference(sample.t_step)
        assert np.max(np.abs(sample.q - q_ref)) < 1e-3 and np.max(np.abs(sample.qd - qd_ref)) < 0.02
        assert np.max(np.abs(sample.torque)) <= LIMIT + 1e-9
        assert np.max(cone_rows(sample.forces[0, :3], 0.5)) < 0.0
    q_ref, qd_ref, _ = start.reference(TAU)
    assert np.max(np.abs(run.samples[-1].q - q_ref)) < 1e-4 and np.max(np.abs(run.samples[-1].qd - qd_ref)) < 1e-3


def test_the_first_step_lands_and_lifts_off(planned):
    """The first step, from the plan's lift-off: the flight, the actuated end to the planned
    touchdown at T, within 0.01 rad/s of the plan's state (measured 0.0042), the held landing with
    both tips pressing (the walk's I^- 0.014 N m s in all: what 200 N m gives in 0.07 ms), d seconds
    with both feet pressing (44.8 N at the least against the plan's 50), every torque within
    200 N m. The lift-off keeps the state: the next step starts in the phase's end state, legs
    exchanged, no impulse."""
    planner, _, orbit = planned
    w = walker(planned)
    outcome = w.walk_step()
    assert not outcome.fall, outcome.fall
    touchdown = outcome.touchdown
    assert touchdown.t_step == pytest.approx(orbit.period + DURATION, abs=1e-9)
    report = touchdown.double_support
    assert np.abs(report.i_minus).sum() < 0.1 and touchdown.W == pytest.approx(np.abs(report.i_minus).sum())
    assert not np.any(touchdown.i_plus)
    assert report.held_old[2] >= -1e-6 and report.held_new[2] >= -1e-6
    assert touchdown.state_error < 0.01
    double = [s for s in outcome.samples if s.phase == DOUBLE_SUPPORT]
    assert len(double) >= round(DURATION * RATE) - 1
    for sample in outcome.samples:
        assert np.max(np.abs(sample.torque)) <= LIMIT + 1e-9
        assert np.all(sample.forces[:, 2] > 0.0)
    assert min(s.forces[:, 2].min() for s in double) > 40.0
    # The lift-off's reset from the last double-support sample: the state mirrored, no impulse.
    last = double[-1]
    phase = ContinuousLiftOff(orbit.double_support, orbit.period, report, ActuatedStart(orbit.swing_ends.start, 0.0))
    matrix = planner.hybrid.exchange.matrix
    state = w.state  # the next step's start; its step's state stands in for the lifted-off one
    lifted = phase.reset(w.context, state, End(AT, last.t_step, last.q, last.qd))
    assert np.max(np.abs(lifted.state.q - matrix @ last.q)) < 1e-12
    assert np.max(np.abs(lifted.state.qd - matrix @ last.qd)) < 1e-12
    assert isinstance(lifted.phase, ActuatedStart) and lifted.state.t_step == 0.0


def test_the_planned_touchdown_gives_no_clock_to_free_the_timing(planned):
    """Why the walk's timing cannot simply be freed on this plan (docs/model.md 15.1, what was
    tried): along the actuated end's reference (every 0.1 ms) the swing tip comes down onto the
    ground a first time in the end's middle (measured 5.9 um below it between the points near
    0.036 s, on it at the point 0.035 s: the plan's non-penetration is held at the points only),
    rises again (1.77 mm near 0.07 s) and comes down tangentially (on the ground at 0.095 s and at
    T), so a touchdown located where the tip reaches the ground fires mid-end or at an
    ill-conditioned instant; and the passive stance ankle's pitch, the phase variable of hybrid
    zero dynamics, peaks before T (0.2516 rad at 0.093 s) and falls back (0.2507 at T), so it
    orders no instant of the last 7 ms."""
    planner, _, orbit = planned
    bm, end = planner.model, orbit.swing_ends.end
    t = np.linspace(0.0, TAU, 1001)
    states = [end.reference(s)[0] for s in t]
    height = np.array([bm.swing_tip(q)[2] for q in states])
    middle, rise = (t > 0.03) & (t < 0.045), (t > 0.05) & (t < 0.09)
    assert -2e-5 < height[middle].min() < 1e-5 and height[rise].max() > 1.5e-3
    assert abs(height[950]) < 1e-6 and abs(height[-1]) < 1e-6  # t = 0.095 s and T
    pitch = np.array([q[bm.index("ankle_pitch")] for q in states])
    assert 0.085 < t[np.argmax(pitch)] < TAU - 0.003 and pitch.max() - pitch[-1] > 5e-4


def test_twenty_steps_walk(planned):
    """The walk holds (docs/model.md 15.1): 20 steps from the plan's lift-off, (tau, d) = (0.1, 0.1)
    s, in the hybrid engine, without a fall (every held tip pressing within the floor's pyramid at
    every sample, the swing tip within 1 mm of the ground at each planned touchdown, no link below
    it), every torque within its limit. Measured: the tip at most 0.041 mm from the ground at the
    touchdowns, each touchdown within 0.042 rad/s of the plan's state, the landing's I^- at most
    0.20 N m s, friction ratios up to 0.464, each foot's vertical reaction at least the reaction
    guard's 20 N (the guard holds it there). What holds it: the swing's LQR weighs the swing tip's
    height and velocity at the touchdown (``swing_ends.TIP_HEIGHT``, ``TIP_SPEED``), and the reaction
    guard keeps the LQR's torques where the floor holds the feet; without them the walk fell in its
    fourth step (the tip 2.35 mm above the ground), with the tip's terms alone in its 15th (a foot
    slipping). It falls in its 33rd (17.95 s: the swing foot down before its actuated end), the
    errors growing from the 20th: no feedback yet acts on the cycle as a whole."""
    planner, _, orbit = planned
    bm = planner.model
    w = walker(planned)
    heights, errors, landings = [], [], []
    for _ in range(20):
        outcome = w.walk_step()
        assert not outcome.fall, outcome.fall
        swing = [s for s in outcome.samples if s.phase != DOUBLE_SUPPORT]
        heights.append(bm.swing_tip(swing[-1].q)[2])
        errors.append(outcome.touchdown.state_error)
        landings.append(np.abs(outcome.touchdown.double_support.i_minus).sum())
        for sample in outcome.samples:
            assert np.max(np.abs(sample.torque)) <= LIMIT + 1e-9
            assert sample.forces[:, 2].min() > GUARD_LEAST_NORMAL_FORCE - 1e-3
    assert w.state.t == pytest.approx(20 * (orbit.period + DURATION), abs=1e-9)
    assert np.max(np.abs(heights)) < 0.3e-3 and max(errors) < 0.2 and max(landings) < 1.0
