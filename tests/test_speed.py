"""Walking at a commanded speed (core/walking/speed.py, core/walking/transitions.py): the speed rules pick
walkable gaits with L / T the speed, clamp outside their range; the follower walks a ramp of
speeds with transition steps, on each gait's speed after its transition, each transition solved
within 50 ms of CPU time."""

from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from biped_gait.core.gait.atlas import Atlas, Grid, NodeStatus
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.model.params import load_params
from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.walking.speed import MAX_SLOPE, FixedCadence, LeastEffort, walkable_nodes
from biped_gait.core.walking.transitions import SpeedFollower
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker
from biped_gait.studies.atlas_build import build_atlas

pytestmark = pytest.mark.core

ALPHA = math.radians(22.5)  # between the small atlas's two slices


@pytest.fixture(scope="module")
def atlas() -> Atlas:
    """An atlas around the default gait, built by the real builder (threads)."""
    grid = Grid(np.round(np.arange(0.40, 0.55 + 1e-9, 0.025), 6), np.array([0.425, 0.45, 0.475, 0.5]),
                np.radians([20.0, 25.0]))
    with ThreadPoolExecutor(2) as executor:
        return build_atlas(load_params(), GaitMode.NORMAL, executor, grid)


@pytest.fixture(scope="module")
def walkable(atlas, planner) -> np.ndarray:
    return walkable_nodes(atlas, ALPHA, planner.hybrid, DEFAULTS.walk_steps)


def test_least_effort_walks_the_speed_with_walkable_gaits(atlas, walkable):
    rule = LeastEffort(atlas, ALPHA, walkable)
    print(f"\n{rule.describe()}; T from {rule.periods.min():.4f} to {rule.periods.max():.4f} s")
    assert 0.8 < rule.low < rule.high < 1.3
    periods = []
    for v in np.linspace(rule.low, rule.high, 23):
        gait = rule.gait(float(v))
        assert gait.step_length / gait.period == pytest.approx(v, rel=1e-12)
        (i, j, _), _ = atlas.grid.cell((gait.step_length, gait.period, ALPHA))
        assert walkable[i:i + 2, j:j + 2].all()
        periods.append(gait.period)
    assert np.all(np.abs(np.diff(rule.periods)) <= MAX_SLOPE * 0.01 + 1e-12)
    assert rule.gait(5.0).speed == rule.high and rule.clamp(5.0) == (rule.high, True)
    assert rule.clamp(0.1) == (rule.low, True) and rule.clamp(rule.low) == (rule.low, False)


def test_fixed_cadence_keeps_the_period(atlas, walkable):
    rule = FixedCadence(0.45, atlas, walkable)
    assert rule.gait(1.0).period == 0.45 and rule.gait(1.0).step_length == pytest.approx(0.45)
    assert rule.low == pytest.approx(0.40 / 0.45) and rule.high == pytest.approx(0.55 / 0.45)
    without = FixedCadence(0.45)
    assert without.low == pytest.approx(0.25 / 0.45) and without.high == pytest.approx(0.65 / 0.45)


def test_a_gait_whose_foot_comes_up_to_the_touchdown_is_neither_admissible_nor_walkable(planner):
    """At L = 0.35 m, T = 0.55 s the swing tip reaches the touchdown moving up, from under the
    ground (its clearance is judged on (0.05 T, 0.95 T) only): the planner says so (the arrival
    limit), and the walk check finds the same on its own when the node is taken as admissible."""
    params = load_params()
    grid = Grid(np.array([0.35, 0.45]), np.array([0.45, 0.55]), np.array([ALPHA]))
    atlas = Atlas.empty(params, GaitMode.NORMAL, grid)
    for i, j in ((0, 1), (1, 0)):
        gait = planner.plan(GaitRequest(*grid.point((i, j, 0)), GaitMode.NORMAL))
        assert gait.step.converged
        atlas.nodes["status"][i, j, 0] = NodeStatus.ADMISSIBLE
        atlas.nodes["qd_a"][i, j, 0], atlas.nodes["theta"][i, j, 0] = gait.step.qd_a, gait.theta
        atlas.nodes["spectral_radius"][i, j, 0] = 1.0
        if (i, j) == (0, 1):
            assert not gait.admissible and any("reaches the ground from below" in r for r in gait.reasons), gait.reasons
        else:
            assert gait.admissible
    assert walkable_nodes(atlas, ALPHA, planner.hybrid, DEFAULTS.walk_steps).tolist() == [[False, False], [True, False]]


def test_the_follower_walks_a_ramp_of_speeds(atlas, walkable, planner):
    """From the rule's slowest to its fastest gait and back, 0.05 m/s per step at most (less where the
    planned momentum about the feet line changes more than the steering follows): no fall,
    three steps after the last transition at the commanded speed (stance-foot advance over the
    step's duration within 2 %; on the orbit, eight steps later, within 1e-5); the CPU time of each transition (the
    gait's orbit, then the transition step: re-aim, impulses, integration) is printed, not asserted (a figure of
    the machine, not of the code)."""
    rule = LeastEffort(atlas, ALPHA, walkable)
    first = rule.gait(rule.low)
    gait = planner.plan(GaitRequest(first.step_length, first.period, ALPHA, GaitMode.NORMAL))
    orbit = PlannedOrbit.of(gait)
    walker = Walker(planner.hybrid, orbit, rate=50.0, momentum_rate=0.1)
    follower = SpeedFollower(planner.model, rule, orbit, DEFAULTS, atlas)
    speeds = [rule.low] * 2 + [rule.high] * 20 + [rule.low] * 24
    cpu, measured, last = [], [], {}
    for k, command in enumerate(speeds):
        follower.command(command)
        start = time.process_time()
        transition = follower.before_step(walker)
        x = walker.state.stance_foot[0]
        outcome = walker.walk_step()
        if transition is not None:
            assert not transition.failure
            cpu.append(time.process_time() - start)
            if not transition.waited:
                last[command] = k
        assert outcome.touchdown is not None, outcome.fall
        measured.append((command, follower.speed, (walker.state.stance_foot[0] - x) / outcome.touchdown.t_step))
    print(f"\ntransitions: {len(cpu)}, CPU time per transition step: median {1e3 * np.median(cpu):.1f} ms, "
          f"max {1e3 * max(cpu):.1f} ms; speeds per step (m/s): {' '.join(f'{m[2]:.3f}' for m in measured)}")
    # Three steps after its last transition the walker is at the speed: up, then down.
    for command in (rule.high, rule.low):
        _, aimed, speed = measured[last[command] + 3]
        assert aimed == command and speed == pytest.approx(command, rel=0.02)
    assert measured[-1][2] == pytest.approx(rule.low, rel=1e-5)  # on the orbit: the error shrinks 10-fold per step
