"""The 13-DOF biped (aoustin2013-hips) at commanded speeds (core/walking/speed.py, transitions.py,
docs/model.md section 8.8): its walkable gaits keep the momentum steering's pitch authority, and
the walk holds the envelope its follower publishes, from the plan up to the fastest speed and
down to the slowest (what the /cmd_vel timeout asks), each change spread over the steps the
steering can follow."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.gait.atlas import Atlas, atlas_path
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.walking.feedback import Feedback
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.speed import MIN_AUTHORITY, walkable_nodes
from biped_gait.core.walking.steering import DEFAULT_RATE
from biped_gait.core.walking.transitions import follower_for

pytestmark = pytest.mark.core

HIPS = "aoustin2013-hips"
ALPHA = 0.349  # rad: the tutorial's arm amplitude for the hips (docs/tutorial.md section 5)


def authority(hips, step_length: float, period: float) -> float:
    """The steering's pitch authority a + b c (kg m^2/s per rad) on the hips' straight gait (L, T)."""
    orbit = PlannedOrbit.of(hips.plan(GaitRequest(step_length, period, ALPHA, "normal")))
    return Feedback(hips.hybrid, momentum_rate=DEFAULT_RATE).aim((orbit,)).step.steering.ref.authority


def test_the_pitch_loses_its_authority_at_long_periods_and_those_gaits_are_not_walkable(hips):
    """At L = 0.45 m the authority falls from about 6.5 at T = 0.45 s through 0 near T = 0.6 s
    (-4 at T = 0.625 s): the least effort per metre walked the slow speeds at T = 0.6 to 0.65 s
    and every walk that slowed down fell there. The shipped atlas's walkable nodes stop short of
    it: at L = 0.45 m those to T = 0.45 s are walkable, none from T = 0.6 s; on each step length
    whose shortest period is walkable, the walkable periods are one run from it."""
    assert authority(hips, 0.45, 0.45) > 2 * MIN_AUTHORITY
    assert authority(hips, 0.45, 0.625) < 0.0
    atlas = Atlas.load(atlas_path(hips.params, GaitMode.NORMAL), hips.params, HIPS)
    walkable = walkable_nodes(atlas, ALPHA, hips.hybrid, DEFAULTS.walk_steps)
    periods = atlas.grid.periods
    i = int(np.argmin(np.abs(atlas.grid.step_lengths - 0.45)))
    assert walkable[i, periods <= 0.45 + 1e-9].all() and not walkable[i, periods >= 0.6 - 1e-9].any()
    for row in walkable[walkable[:, 0]]:
        assert not np.any(np.diff(row.astype(int)) > 0)


def test_the_hips_walk_holds_its_envelope_up_and_down(hips):
    """From the plan (L = T = 0.45 m/s, the simulator's default) at 0.9 m/s (a walk that fell in
    step 19), then the envelope's fastest speed, then a command of 0 (the /cmd_vel timeout's),
    which the follower clamps to the slowest: 235 steps (about 90 s of simulated time) without a
    fall and without a transition that fails; at the end of each hold the walker is at the
    commanded speed (the stance foot's advance over the step's duration, within 1 %). The ramps
    take about 90 steps up and 100 down: most transitions are shrunk to what the steering follows,
    or wait for the walker to catch up."""
    walker = Walker(hips.hybrid, PlannedOrbit.of(hips.plan(GaitRequest(0.45, 0.45, ALPHA, "normal"))), rate=20.0,
                    momentum_rate=DEFAULT_RATE)
    follower, note = follower_for(walker, DEFAULTS, source=HIPS)
    assert note == ""
    low, high = follower.envelope.low, follower.envelope.high
    print(f"\nenvelope {follower.envelope.describe()}")
    assert 0.5 < low < 0.7 and high > 2.0
    holds = [(0.9, 20), (high, 100), (0.0, 115)]
    walked, speeds = 0, []
    for command, steps in holds:
        follower.command(command)
        for _ in range(steps):
            transition = follower.before_step(walker)
            assert transition is None or not transition.failure, transition.failure
            start = walker.state.stance_foot.copy()
            outcome = walker.walk_step()
            assert outcome.touchdown is not None, f"step {walker.state.step}: {outcome.fall}"
            heading = walker.state.heading
            advance = (walker.state.stance_foot - start) @ [math.cos(heading), math.sin(heading), 0.0]
            speeds.append(advance / outcome.touchdown.t_step)
        walked += steps
        target = max(command, low)
        print(f"command {command:.3f} m/s: after {walked} steps ({walker.state.t:.1f} s) aimed at "
              f"{follower.speed:.3f} m/s, walking {np.mean(speeds[-2:]):.3f} m/s")
        assert follower.speed == pytest.approx(target, abs=1e-9)
        assert np.mean(speeds[-2:]) == pytest.approx(target, rel=0.01)  # a stride of two steps
    assert walker.state.t > 80.0
