"""The double support that lasts, walked (core/walking/phases/lasting.py, docs/model.md section
14.1): the hybrid engine from the plan's lift-off, I^- that lands the phase nearest the plan's start, the held touchdown, the
tracked phase with both feet down, the re-aimed lift-off."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.walking.events import DOUBLE_SUPPORT, CouldNotStart, Finished, Sample
from biped_gait.core.gait.lasting import WALK_LEAST_NORMAL_FORCE, WALK_PUSH_OFF, LastingRequest
from biped_gait.core.walking.held_support import lasting_orbit
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.walk import Walk

from .lasting_steps import check_lasting_step

DURATION = 0.1  # s
RATE = 100.0  # samples per second
STEPS = 20


@pytest.fixture(scope="module")
def walked():
    planner = GaitPlanner(modes=("normal",))
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5)))
    support, _ = planner.lasting_cycle(gait, LastingRequest.walkable(DURATION))  # kept for the other tests' nodes
    assert support.success, support.message
    orbit = lasting_orbit(PlannedOrbit.of(gait), support, planner.hybrid)
    walker = Walker(planner.hybrid, orbit, RATE)
    return support, orbit, [walker.walk_step() for _ in range(STEPS)]


def test_the_walked_plan_keeps_its_margins(walked):
    """The plan to walk keeps each foot pressing by the margin, the reactions within mu - 0.1, and
    the old foot pushing off at I^+ by at least the margin, within mu - 0.1."""
    support, _, _ = walked
    assert support.contact_forces[..., 2].min() >= WALK_LEAST_NORMAL_FORCE - 1e-6 * 500
    assert support.friction_used <= 0.4 + 1e-6
    push = support.push_off
    assert push[2] >= WALK_PUSH_OFF - 1e-6 * 50 and np.hypot(push[0], push[1]) <= 0.4 * push[2] + 1e-6 * 50


def test_the_walked_plan_resolves_its_phase(walked):
    """Between its collocation points the plan's reference is a motion of the closed chain with both
    feet pressing (docs/model.md 14.1, held_support's resolution): the least vertical reaction along
    it, every millisecond, 44.3 N where its points keep the 50 N margin; at least half the margin,
    the rest being the mesh's error, which a plan on coarser intervals exceeds (the stop's and the
    start's, -1.4 to -2.0 kN, tests/test_lasting.py)."""
    _, orbit, _ = walked
    assert orbit.double_support.least_normal_force() > WALK_LEAST_NORMAL_FORCE / 2


def test_the_first_steps_walk_with_both_feet_down(walked):
    """Started on the plan, the first touchdown is the plan's (its own flow: to the re-aim's
    tolerance), the landing soft; twenty steps each last about T + d, their double supports have
    both feet on the ground in every sample, pressing (the runner checks the cone: a sample out of
    it is a fall), their torques within the joints' 200 N m; the walk settles on a nearby cycle
    (docs/model.md 14.1: its touchdowns 0.15 rad/s from the plan's velocity, their distance
    changing by less than 1 mrad/s a step by the twentieth)."""
    support, orbit, outcomes = walked
    for k, outcome in enumerate(outcomes):
        check_lasting_step(k, outcome, orbit.period + DURATION, DURATION, RATE)
        report = outcome.touchdown.double_support
        assert report.duration == DURATION
        assert report.held_old[2] >= -1e-6 and report.held_new[2] >= -1e-6  # pressing, to HiGHS's tolerance
    errors = [outcome.touchdown.state_error for outcome in outcomes]
    assert max(errors) < 0.25 and abs(errors[-1] - errors[-2]) < 1e-3
    first = outcomes[0].touchdown.double_support
    assert first.state_error < 1e-8
    assert np.abs(first.i_minus - first.i_minus_planned).sum() < 1e-6
    assert np.abs(first.held_old).max() < 1e-6 and np.abs(first.held_new).max() < 1e-6  # the soft landing


def test_the_walk_walks_it_and_refuses_what_cannot(walked):
    """``Walk`` (what the simulator runs) walks the orbit's double support in the hybrid engine, its
    samples in the double support with both feet; MuJoCo and the momentum steering are refused with
    their reasons."""
    _, orbit, _ = walked
    items = list(Walk(orbit, RATE, steps=2))
    assert isinstance(items[-1], Finished), items[-1]
    double = [item for item in items if isinstance(item, Sample) and item.phase == DOUBLE_SUPPORT]
    assert double and all(len(sample.feet_on_ground) == 2 for sample in double)
    for kwargs, words in (({"engine": "mujoco"}, "hybrid engine only"), ({"momentum_rate": 0.5}, "duration re-aim")):
        refused = list(Walk(orbit, RATE, steps=2, **kwargs))
        assert len(refused) == 1 and isinstance(refused[0], CouldNotStart) and words in refused[0].reason
