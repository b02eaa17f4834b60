"""The walk as a sequence of phases (core/walking/runner.py, phases/, engines/): the phase runner
walks today's gaits with the figures the walker gave before it (tests/phase_walks.py), a phase
slots in without touching the runner, a sample says which feet are on the ground, and the engines
know nothing of the walk."""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import dataclass, replace

import numpy as np
import pytest

from biped_gait.core.walking.engines.engine import Motion
from biped_gait.core.walking.events import SINGLE_SUPPORT, StepSamples, Touchdown
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.phases.impulsive import ImpulsiveDoubleSupport, SingleSupport
from biped_gait.core.walking.phases.phase import End, Guard, Phase, Transition, WalkContext
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.state import WalkState
from tests import phase_walks

pytestmark = pytest.mark.core

# How precisely the stored figures are known: a shove of 1e-10 rad/s on every joint at the start
# (10^5 times a rounding error of the state) moves them by at most 1.4e-6 in the planner's model
# and 8.9e-6 in MuJoCo (a state after 6 steps; impulses and W in N m s; the touchdown times by
# 1e-8 s). The tolerances are ten times that: another machine's last digits, or the planner's,
# stay far inside; a phase walked otherwise (a push at another instant, another order) does not.
TOLERANCE = {"hybrid": 1e-5, "mujoco": 1e-4}  # rad, rad/s, m, N m s
TIME_TOLERANCE = 1e-7  # s


@pytest.fixture(scope="module")
def walks():
    return phase_walks.walks(phase_walks.stored_orbits())


@pytest.mark.parametrize("name", ["steered", "plain", "transition", "circle", "mujoco"])
def test_the_phase_runner_walks_todays_gaits_with_todays_figures(walks, name):
    orbit, options, before = walks[name]
    now = phase_walks.walk_figures(orbit, options, before)
    tolerance = TOLERANCE[options.get("engine", "hybrid")]
    with np.load(phase_walks.DATA / "walks.npz") as stored:
        gaps = {key: float(np.max(np.abs(now[key] - stored[f"{name}/{key}"]))) for key in now}
    print(f"\n{name}: largest differences from the stored walk {gaps}")
    assert gaps["times"] < TIME_TOLERANCE
    assert all(gap < tolerance for key, gap in gaps.items() if key != "times"), gaps


@dataclass(frozen=True, eq=False)
class FirstHalf(Phase):
    """A phase added without touching the runner: the ballistic single support cut at mid-step (an
    instant guard), then the single support to the touchdown."""

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return Motion(state.aim.period / ctx.grid)

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return Guard(at=0.5 * state.aim.period)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        return Transition(SingleSupport(next=HalvedDoubleSupport()), state.moved(end.t, end.q, end.qd))


@dataclass(frozen=True, eq=False)
class HalvedDoubleSupport(ImpulsiveDoubleSupport):
    """The impulsive double support, followed by a step cut in two."""

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        return replace(super().reset(ctx, state, end), phase=FirstHalf())


def test_a_phase_slots_in_without_touching_the_runner(planner, default_gait):
    """Every step cut into two phases at mid-step: the same figures to the integration's
    rounding (the RK8 step cut at T / 2), every instant k / rate sampled once, the samples saying
    their phase and the one foot on the ground."""
    orbit = PlannedOrbit.of(default_gait)
    whole = Walker(planner.hybrid, orbit, rate=200.0, momentum_rate=0.25)
    halved = Walker(planner.hybrid, orbit, rate=200.0, momentum_rate=0.25, phase=FirstHalf())
    samples, sides = [], []
    for _ in range(6):
        a, b = whole.walk_step(), halved.walk_step()
        assert a.touchdown is not None and b.touchdown is not None, b.fall
        assert b.touchdown.t == pytest.approx(a.touchdown.t, abs=1e-9)
        assert np.allclose(b.touchdown.i_minus, a.touchdown.i_minus, atol=1e-6)
        assert np.allclose(halved.state.qd, whole.state.qd, atol=1e-6)
        assert abs(len(b.samples) - len(a.samples)) <= 1  # an instant within rounding of a touchdown: either side
        samples += b.samples
        sides.append({s.stance_side for s in b.samples})
    times = np.array([s.t for s in samples])
    assert np.allclose(np.diff(times), 1 / 200.0, atol=1e-12) and times[0] == 0.0
    assert {s.phase for s in samples} == {SINGLE_SUPPORT}
    assert all(s.feet_on_ground == (s.stance_side,) and s.forces.shape == (1, 4) for s in samples)
    assert sides == [{"right"}, {"left"}] * 3


def test_the_walk_gives_each_phase_as_it_ends(default_gait):
    """``Walk.batches`` in MuJoCo: each phase's samples as one batch (the pulsed double support's
    phases: the coast to the decision, the pre-impact pulse, the post-impact pulse), every instant
    once, the touchdown between the steps with what the pulses did."""
    from biped_gait.core.walking.walk import Walk

    items = list(Walk(PlannedOrbit.of(default_gait), 100.0, 2, engine="mujoco", momentum_rate=0.25).batches())
    kinds = "".join("S" if isinstance(item, StepSamples) else type(item).__name__[0] for item in items)
    assert re.fullmatch("S{2,}TS{2,}TF", kinds), kinds
    times = np.concatenate([item.t for item in items if isinstance(item, StepSamples)])
    assert np.allclose(np.diff(times), 0.01, atol=1e-12) and times[0] == 0.0
    touchdowns = [item for item in items if isinstance(item, Touchdown)]
    assert all(td.double_support is not None and td.W == td.double_support.effort for td in touchdowns)


def test_the_engines_know_nothing_of_the_walk():
    """The engines import neither the runner, the walk nor the phases (the import circle is gone):
    they integrate a model and a workspace."""
    code = ("import sys, biped_gait.core.walking.engines.hybrid, biped_gait.core.walking.engines.mujoco\n"
            "walk = [m for m in sys.modules if m.startswith('biped_gait.core.walking.') and m.split('.')[3] in "
            "('runner', 'walk', 'phases', 'state', 'feedback', 'events')]\n"
            "print(walk); sys.exit(1 if walk else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr
