"""Walking a plan step after step (the simulator's core): touchdowns as events, impulses from
the actual state, leg exchange, drift, and falls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.walk import PlannedOrbit, Walker

pytestmark = pytest.mark.core


def walk(walker: Walker, steps: int):
    outcomes = []
    for _ in range(steps):
        outcome = walker.walk_step()
        outcomes.append(outcome)
        if outcome.touchdown is None:
            break
    return outcomes


def test_twenty_steps_land_on_the_plan(planner, default_gait):
    walker = Walker(planner.hybrid, PlannedOrbit.of(default_gait), rate=500.0)
    outcomes = walk(walker, 20)
    assert all(o.touchdown is not None for o in outcomes) and len(outcomes) == 20
    errors = [o.touchdown.state_error for o in outcomes]
    print("\nstate error at each touchdown (rad, rad/s):", " ".join(f"{e:.1e}" for e in errors))
    assert max(errors) < 1e-9  # stated tolerance: the plan is tracked to numerical precision
    for o in outcomes:
        td = o.touchdown
        assert td.t_step == pytest.approx(default_gait.period, abs=1e-9)
        assert td.W == pytest.approx(default_gait.W, rel=1e-7)
        assert td.equation_residual < 1e-9
        assert len(o.samples) in (224, 225, 226)  # 500 Hz over 0.45 s; which step owns an instant at a touchdown is rounding
        assert min(s.grf[2] for s in o.samples) > 0
    # Every instant k / 500 s before the last touchdown was sampled once.
    assert sum(len(o.samples) for o in outcomes) == math.ceil(outcomes[-1].touchdown.t * 500.0 - 1e-6)
    # The stance foot advances by L each step and alternates sides.
    assert walker.state.stance_side == "right" and walker.state.step == 20
    assert np.allclose(walker.state.stance_foot, [20 * 0.45, -0.2, 0.0], atol=1e-9)


def test_open_loop_aiming_is_unstable(planner, default_gait):
    """Aiming only at the plan's post-impact velocity, a small error grows by orders of magnitude
    per step: the reason the walker re-aims (docs/model.md section 8)."""
    walker = Walker(planner.hybrid, PlannedOrbit.of(default_gait), rate=100.0, reaim=False)
    walker.shove(np.full(9, 1e-9))  # rad/s: far above rounding, far below a fall
    outcomes = walk(walker, 4)
    errors = [o.touchdown.state_error for o in outcomes if o.touchdown is not None]
    print("\nopen-loop state error per step:", " ".join(f"{e:.1e}" for e in errors))
    growth = [b / a for a, b in zip(errors, errors[1:])]
    assert len(errors) == 4 and min(growth) > 20


def test_samples_are_on_the_publishing_grid(planner, default_gait):
    walker = Walker(planner.hybrid, PlannedOrbit.of(default_gait), rate=1000.0)
    first, second = walk(walker, 2)
    times = np.array([s.t for s in first.samples + second.samples])
    assert np.allclose(np.diff(times), 1e-3, atol=1e-12)
    assert first.samples[0].t == 0.0
    assert np.allclose(first.samples[0].q, default_gait.step.q0) and np.allclose(first.samples[0].qd, default_gait.qd_a)


def test_a_shove_makes_it_fall_and_the_walker_says_why(planner, default_gait):
    walker = Walker(planner.hybrid, PlannedOrbit.of(default_gait), rate=200.0)
    walk(walker, 2)
    walker.shove(np.array([0.0, -3.0, 0, 0, 0, 0, 0, 0, 0]))  # pitch the stance leg backwards hard
    outcome = walker.walk_step()
    assert outcome.touchdown is None
    assert outcome.fall  # e.g. "a link went below the ground" or "did not land within 2 T"


def test_walker_refuses_a_failed_plan(planner):
    from biped_gait.core.planner import GaitRequest

    failed = planner.plan(GaitRequest(0.45, 5.0, 0.4, "normal"))
    with pytest.raises(ValueError, match="did not converge"):
        Walker(planner.hybrid, PlannedOrbit.of(failed), rate=500.0)
    good = planner.plan(GaitRequest(0.45, 0.45, math.radians(20), "normal"))
    with pytest.raises(ValueError, match="publishing rate must be positive"):
        Walker(planner.hybrid, PlannedOrbit.of(good), rate=0.0)
