"""The swing actuated at its two ends, walked in the hybrid engine (core/walking/phases/actuated.py,
core/walking/swing_ends.py, docs/model.md section 15.1): the reference of each actuated end resolved
between its collocation points, the actuated start tracked from the plan's lift-off, the first step
landed, held and lifted off with the state continuous; and where the walk does not hold yet (the
actuated end, its torques clipped at the limit where Hermite-Simpson's exceed it between the
points, lands off the plan, and the third touchdown misses the ground).

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
    under the plan's torques (``PinnedTip``; Hermite-Simpson's quadratic torques between the points)
    give the plan's own reactions at its collocation points (within 1e-6 m g: the program's
    tolerance) and between them press within the floor's pyramid: measured 175.6 N (start) and
    124.8 N (end) at the least, friction ratios 0.385 and 0.409 against the plan's 0.4 at its points
    (the ringing between them). The double support's reference keeps 48.0 N (its points 50 N). The
    rule's torques, though, leave the limit between the points: 225 N m at the start, 250 N m at the
    end's last half-interval (the swing hip), where the plan's points are at 200 (docs/model.md 15.1)."""
    planner, cycle, orbit = planned
    bm = planner.model
    weight = bm.total_mass * bm.params.gravity
    for which, least, most in (("start", 170.0, 220.0), ("end", 120.0, 240.0)):
        t, forces = orbit.swing_ends.reactions(which)
        planned_end = getattr(cycle, which)
        points = np.searchsorted(t, planned_end.t - planned_end.t[0] - 1e-9)
        assert np.max(np.abs(forces[points] - planned_end.contact_forces)) < 1e-6 * weight
        assert forces[:, 2].min() > least
        assert friction_ratio(forces) < 0.42 and np.max(cone_rows(forces, bm.params.friction)) < 0.0
        reference = getattr(orbit.swing_ends, which)
        assert np.max(np.abs(reference.torques)) <= LIMIT + 1e-6 * 100
        assert max(np.abs(reference.torque(t)).max() for t in np.linspace(0.0, TAU, 1001)) > most
    assert orbit.double_support.least_normal_force() > 0.9 * WALK_LEAST_NORMAL_FORCE


def test_the_actuated_start_tracks_the_plan(planned):
    """From the plan's lift-off the actuated start, the plan's torques and the swing's LQR, stays
    within 3 mrad and 0.2 rad/s of the plan (measured 1.8 mrad and 0.14 rad/s, where the bang-bang
    torques switch and the limit clips the rule's; 0.43 mrad and 0.0023 rad/s at its end), every
    torque within 200 N m, the stance tip's reaction within the pyramid at every sample."""
    _, _, orbit = planned
    start = orbit.swing_ends.start
    run = walker(planned).run_phase()
    assert not run.fall and len(run.samples) == round(TAU * RATE) + 1
    for sample in run.samples:
        q_ref, qd_ref, _ = start.reference(sample.t_step)
        assert np.max(np.abs(sample.q - q_ref)) < 3e-3 and np.max(np.abs(sample.qd - qd_ref)) < 0.2
        assert np.max(np.abs(sample.torque)) <= LIMIT + 1e-9
        assert np.max(cone_rows(sample.forces[0, :3], 0.5)) < 0.0
    q_ref, qd_ref, _ = start.reference(TAU)
    assert np.max(np.abs(run.samples[-1].q - q_ref)) < 1e-3 and np.max(np.abs(run.samples[-1].qd - qd_ref)) < 1e-2


def test_the_first_step_lands_and_lifts_off(planned):
    """The first step, from the plan's lift-off: the flight, the actuated end to the planned
    touchdown at T, the held landing (both tips pressing; the passive impact alone would leave the
    old tip pulling: the walk's I^- corrects it, 0.25 N m s in all measured, what 200 N m gives in
    1.3 ms), d seconds with both feet pressing (33 N at the least against the plan's 50), every
    torque within 200 N m; the touchdown 0.090 rad/s from the plan's state. The lift-off keeps the
    state: the next step starts in the phase's end state, legs exchanged."""
    planner, _, orbit = planned
    w = walker(planned)
    outcome = w.walk_step()
    assert not outcome.fall, outcome.fall
    touchdown = outcome.touchdown
    assert touchdown.t_step == pytest.approx(orbit.period + DURATION, abs=1e-9)
    report = touchdown.double_support
    assert 0.0 < np.abs(report.i_minus).sum() < 0.5 and touchdown.W == pytest.approx(np.abs(report.i_minus).sum())
    assert not np.any(touchdown.i_plus)
    assert report.held_old[2] >= -1e-6 and report.held_new[2] >= -1e-6
    assert 0.05 < touchdown.state_error < 0.15
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


def test_the_third_touchdown_misses_the_ground(planned):
    """Where the walk stands (docs/model.md 15.1): the swing's LQR carries the flight (its end 3e-3
    rad/s off the plan, where the start's frozen gains left 0.31), but the actuated end, its
    torques clipped to 200 N m where the rule's reach 250, lands each step about 0.09 rad/s off
    the plan's velocity; two steps walk, and at the third planned touchdown the swing tip is still
    1.07 mm above the ground (the walk's 1 mm). A walk that holds changes this test with 15.1."""
    _, _, orbit = planned
    ends = orbit.swing_ends
    w = walker(planned)
    for _ in range(2):
        outcome = w.walk_step()
        assert not outcome.fall, outcome.fall
        assert 0.05 < outcome.touchdown.state_error < 0.15
        flight_end = [s for s in outcome.samples if s.t_step <= orbit.period - TAU + 1e-9][-1]
        assert np.max(np.abs(flight_end.qd - ends.end.reference(0.0)[1])) < 1e-2
    outcome = w.walk_step()
    assert "above the ground" in outcome.fall
    assert outcome.samples[-1].t_step == pytest.approx(orbit.period - 1.0 / RATE, abs=1e-9)
