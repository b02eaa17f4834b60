"""The swing actuated at its two ends, walked in the hybrid engine (core/walking/phases/actuated.py,
core/walking/swing_ends.py, docs/model.md section 15.1): the reference of each actuated end resolved
between its collocation points, the actuated start tracked from the plan's lift-off, the first step
landed, held and lifted off with the state continuous; and where the walk does not hold yet (the
second step's flight, open loop, amplifies the tracked start's error beyond what the actuated end's
torques and the floor's friction can take).

The plan is solved once (tau, d) = (0.1, 0.1) s at the default gait with the walk's margins on the
reactions (50 N, friction within mu - 0.1): about 40 s on the project's 2-core machine."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.gait.actuated_swing import ActuatedSwingPlanner, SwingRequest
from biped_gait.core.gait.lasting import WALK_FRICTION_MARGIN, WALK_LEAST_NORMAL_FORCE, LastingRequest
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.walking.events import DOUBLE_SUPPORT
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.phases.actuated import ActuatedStart, ContinuousLiftOff
from biped_gait.core.walking.phases.phase import AT, End
from biped_gait.core.walking.phases.pulse_dynamics import cone_rows, friction_ratio
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.swing_ends import actuated_orbit

TAU = DURATION = 0.1  # s
RATE = 1000.0  # samples per second: every RK4 step
LIMIT = 200.0  # N m, the joint table's effort


@pytest.fixture(scope="module")
def planned():
    planner = GaitPlanner(modes=("normal",))
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5)))
    support = LastingRequest(DURATION, least_normal_force=WALK_LEAST_NORMAL_FORCE, friction_margin=WALK_FRICTION_MARGIN)
    cycle = ActuatedSwingPlanner(planner.lasting).cycle(gait, SwingRequest(TAU, support))
    assert cycle.success, cycle.message
    return planner, cycle, actuated_orbit(PlannedOrbit.of(gait), cycle, planner.hybrid)


def walker(planned) -> Walker:
    planner, _, orbit = planned
    return Walker(planner.hybrid, orbit, RATE, phase=ActuatedStart(orbit.swing_ends.start, 0.0))


def test_the_reference_resolves_the_swing_ends(planned):
    """Along each actuated end's reference, every millisecond, the single support's forward dynamics
    under the plan's torques (``PinnedTip``) give the plan's own reactions at its collocation points
    (within 1e-6 m g: the program's tolerance) and between them press within the floor's pyramid:
    measured 175.6 N (start) and 128.5 N (end) at the least, friction ratios 0.385 and 0.4025 against
    the plan's 0.4 at its points (Hermite-Simpson's ringing between them: 0.6 %). The double
    support's reference keeps 48.0 N (its points 50 N)."""
    planner, cycle, orbit = planned
    bm = planner.model
    weight = bm.total_mass * bm.params.gravity
    for which, least in (("start", 170.0), ("end", 120.0)):
        t, forces = orbit.swing_ends.reactions(which)
        planned_end = getattr(cycle, which)
        points = np.searchsorted(t, planned_end.t - planned_end.t[0] - 1e-9)
        assert np.max(np.abs(forces[points] - planned_end.contact_forces)) < 1e-6 * weight
        assert forces[:, 2].min() > least
        assert friction_ratio(forces) < 0.41 and np.max(cone_rows(forces, bm.params.friction)) < 0.0
    assert orbit.double_support.least_normal_force() > 0.9 * WALK_LEAST_NORMAL_FORCE


def test_the_actuated_start_tracks_the_plan(planned):
    """From the plan's lift-off the actuated start, the plan's torques and the LQR, stays within
    3 mrad and 0.2 rad/s of the plan (measured 2.4 mrad and 0.16 rad/s, where the bang-bang torques
    switch; 0.68 mrad and 0.010 rad/s at its end), every torque within 200 N m (the plan's at the
    limit: the feedback clipped there), the stance tip's reaction within the pyramid at every sample."""
    _, _, orbit = planned
    start = orbit.swing_ends.start
    run = walker(planned).run_phase()
    assert not run.fall and len(run.samples) == round(TAU * RATE) + 1
    for sample in run.samples:
        q_ref, qd_ref, _ = start.reference(sample.t_step)
        assert np.max(np.abs(sample.q - q_ref)) < 3e-3 and np.max(np.abs(sample.qd - qd_ref)) < 0.2
        assert np.max(np.abs(sample.torque)) <= LIMIT + 1e-9
        assert np.max(cone_rows(sample.forces[0, :3], 0.5)) < 0.0


def test_the_first_step_lands_and_lifts_off(planned):
    """The first step, from the plan's lift-off: the flight, the actuated end to the planned
    touchdown at T, the held landing (both tips pressing; the passive impact alone would leave the
    old tip pulling: the walk's I^- corrects it, 0.52 N m s in all measured, what 200 N m gives in
    2.6 ms), d seconds with both feet pressing (33 N at the least against the plan's 50), every
    torque within 200 N m; the touchdown 0.137 rad/s from the plan's state. The lift-off keeps the
    state: the next step starts in the phase's end state, legs exchanged."""
    planner, _, orbit = planned
    w = walker(planned)
    outcome = w.walk_step()
    assert not outcome.fall, outcome.fall
    touchdown = outcome.touchdown
    assert touchdown.t_step == pytest.approx(orbit.period + DURATION, abs=1e-9)
    report = touchdown.double_support
    assert 0.0 < np.abs(report.i_minus).sum() < 1.0 and touchdown.W == pytest.approx(np.abs(report.i_minus).sum())
    assert not np.any(touchdown.i_plus)
    assert report.held_old[2] >= -1e-6 and report.held_new[2] >= -1e-6
    assert 0.05 < touchdown.state_error < 0.3
    double = [s for s in outcome.samples if s.phase == DOUBLE_SUPPORT]
    assert len(double) >= round(DURATION * RATE) - 1
    for sample in outcome.samples:
        assert np.max(np.abs(sample.torque)) <= LIMIT + 1e-9
        assert np.all(sample.forces[:, 2] > 0.0)
    assert min(s.forces[:, 2].min() for s in double) > 20.0
    # The lift-off's reset from the last double-support sample: the state mirrored, no impulse.
    last = double[-1]
    phase = ContinuousLiftOff(orbit.double_support, orbit.period, report, ActuatedStart(orbit.swing_ends.start, 0.0))
    matrix = planner.hybrid.exchange.matrix
    state = w.state  # the next step's start; its step's state stands in for the lifted-off one
    lifted = phase.reset(w.context, state, End(AT, last.t_step, last.q, last.qd))
    assert np.max(np.abs(lifted.state.q - matrix @ last.q)) < 1e-12
    assert np.max(np.abs(lifted.state.qd - matrix @ last.qd)) < 1e-12
    assert isinstance(lifted.phase, ActuatedStart) and lifted.state.t_step == 0.0


def test_the_second_step_falls_where_its_flight_amplifies_the_error(planned):
    """Why the walk does not hold yet (docs/model.md 15.1): the second step's actuated start leaves
    the flight 0.68 mrad and 0.010 rad/s off the plan; the flight, open loop, amplifies that about
    30-fold (20 mrad, 0.31 rad/s at T - tau), and at the actuated end's first instant the feedback's
    torques push the stance tip's reaction out of the friction cone (|F_xy| / F_z = 1.75). A walk
    that holds would change this test with docs/model.md 15.1."""
    _, _, orbit = planned
    ends = orbit.swing_ends
    w = walker(planned)
    assert not w.walk_step().fall
    outcome = w.walk_step()
    assert "slips" in outcome.fall
    end_time = orbit.period - ends.duration
    assert outcome.samples[-1].t_step == pytest.approx(end_time, abs=1e-9)
    start_end = [s for s in outcome.samples if s.t_step <= ends.duration + 1e-9][-1]
    q_ref, qd_ref, _ = ends.start.reference(ends.duration)
    before = np.max(np.abs(start_end.qd - qd_ref))
    after = np.max(np.abs(outcome.samples[-1].qd - ends.end.reference(0.0)[1]))
    assert np.max(np.abs(start_end.q - q_ref)) < 2e-3 and before < 0.03
    assert after > 10 * before
