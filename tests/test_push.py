"""Pushes on the trunk (core/walking/push.py) and momentum steering (core/walking/steering.py): the velocity jump
is the impulse's, a push splits the step where it acts, the steered re-aim's gains are those of
the plain re-aim's linearization, the steered closed loop contracts at its rate, and a push is
recovered to within 1e-3 of the orbit in 10 steps by steering, not by the plain re-aim."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from biped_gait.core.gait.configurations import boundary_configurations
from biped_gait.core.model.exchange import MIRROR, world_axes
from biped_gait.core.model.biped import cross
from biped_gait.core.walking.push import DIRECTIONS, Push, TrunkPush, horizontal_impulse
from biped_gait.core.gait.stability import closed_loop
from biped_gait.core.walking.steering import DEFAULT_RATE, momentum_row, pelvis_pitch, reference
from biped_gait.core.walking.events import StepSamples
from biped_gait.core.walking.feedback import Feedback
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.walk import Walk

pytestmark = pytest.mark.core


def orbit_start(gait) -> np.ndarray:
    return np.concatenate([gait.step.q0, gait.step.qd_a])


def distance(walker: Walker, gait) -> float:
    """max |(q, qd) - (q0, qd_a)| at the walker's current step start (rad, rad/s)."""
    return float(np.max(np.abs(np.concatenate([walker.state.q, walker.state.qd]) - orbit_start(gait))))


@pytest.mark.parametrize("side", ["right", "left"])
def test_the_velocity_jump_carries_the_impulses_moment(planner, default_gait, side):
    """About the stance tip the ground's impulse has no horizontal moment (the ankle is a free
    roll and pitch pivot; it does take a moment about the vertical, the foot not being allowed
    to spin): the horizontal angular momentum jumps by r_trunk x P (model frame; the world's
    mirror image with the left foot in stance)."""
    bm = planner.model
    q, qd = default_gait.step.q0, default_gait.step.qd_a
    impulse = np.array([3.0, -2.0, 0.5])
    jump = TrunkPush(bm).velocity_jump(q, impulse, world_axes(side))
    _, before, _ = bm.momentum(q, np.concatenate([np.zeros(3), qd]))
    _, after, _ = bm.momentum(q, np.concatenate([np.zeros(3), qd + jump]))
    trunk = TrunkPush(bm)
    trunk.jacobian(q)
    joint = trunk.data.oMi[trunk.joint]
    com = joint.translation + joint.rotation @ trunk.com
    model_impulse = impulse if side == "right" else MIRROR @ impulse
    assert np.allclose((after - before)[:2], cross(com, model_impulse)[:2], atol=1e-10)


def test_a_push_splits_the_step_where_it_acts(planner, default_gait):
    """Mid-step: the walker's touchdown equals an independent integration (another grid) to the
    push, the jump, and on to the walker's touchdown time; the samples jump there."""
    orbit = PlannedOrbit.of(default_gait)
    walker = Walker(planner.hybrid, orbit, rate=1000.0, reaim=False)
    push = Push(horizontal_impulse(0.2, DIRECTIONS["forward"]), 0.2)
    walker.push(push)
    outcome = walker.walk_step()
    [applied] = outcome.pushes
    assert applied.time_in_step == pytest.approx(0.2, abs=1e-12) and applied.step == 0
    fine = planner.hybrid.flow(64)
    mid = fine.propagate(default_gait.step.q0, default_gait.step.qd_a, 0.2)
    jump = TrunkPush(planner.model).velocity_jump(mid.q, push.impulse, world_axes("right"))
    assert np.allclose(jump, applied.delta_qd, atol=1e-12)
    end = fine.propagate(mid.q, mid.qd + jump, outcome.touchdown.t_step - 0.2)
    assert np.allclose(planner.hybrid.exchange.configuration(walker.state.q), end.q, atol=1e-9)
    times = np.array([s.t_step for s in outcome.samples])
    velocities = np.array([s.qd for s in outcome.samples])
    k = int(np.searchsorted(times, 0.2))  # the first sample at or after the push
    smooth = np.max(np.abs(np.diff(velocities[k - 3:k], axis=0)))
    assert np.max(np.abs(velocities[k + 1] - velocities[k - 1])) > 2 * smooth  # the jump between k-1 and k+1
    unpushed = Walker(planner.hybrid, orbit, rate=1000.0, reaim=False).walk_step()
    assert np.allclose([s.qd for s in unpushed.samples[:k - 1]], velocities[:k - 1], atol=1e-9)


def test_a_push_splits_the_walks_sample_batches(planner, default_gait):
    """``Walk.batches``: the samples before the push, the push, the samples at and after it,
    each batch's world pictures those of its own samples; iterating gives the same order."""
    orbit = PlannedOrbit.of(default_gait)
    push = Push(horizontal_impulse(0.2, DIRECTIONS["forward"]), 0.2)

    def walk() -> Walk:
        def push_in_the_first_step(walker: Walker) -> None:
            if walker.state.step == 0:
                walker.push(push)
        return Walk(orbit, 1000.0, steps=2, momentum_rate=DEFAULT_RATE, before_step=push_in_the_first_step)

    items = list(walk().batches())
    kinds = [type(item).__name__ for item in items]
    assert kinds == ["StepSamples", "AppliedPush", "StepSamples", "Touchdown", "StepSamples", "Touchdown", "Finished"]
    before, applied, after = items[:3]
    assert before.t[-1] < applied.t <= after.t[0]
    assert all(len(b.world) == len(b.samples) for b in items if isinstance(b, StepSamples))
    assert np.allclose(after.world.joint_positions[0], after.world.state(0).joint_positions)
    flat = [type(item).__name__ for item in walk()]
    assert flat.index("AppliedPush") == len(before.samples)
    assert flat.count("Sample") == sum(len(b.samples) for b in items if isinstance(b, StepSamples))


def test_a_push_after_the_touchdown_acts_on_the_pre_impact_state(planner, default_gait):
    walker = Walker(planner.hybrid, PlannedOrbit.of(default_gait), rate=100.0)
    walker.push(Push(np.array([0.01, 0.0, 0.0]), 5.0))
    outcome = walker.walk_step()
    [applied] = outcome.pushes
    assert applied.time_in_step == pytest.approx(outcome.touchdown.t_step, abs=1e-12)
    # the step itself is the plan's: the touchdown is off it by the push's velocity jump only
    assert outcome.touchdown.state_error == pytest.approx(np.max(np.abs(applied.delta_qd)), abs=1e-9)


def test_steering_gains_are_the_plain_reaims_linearization(planner, default_gait):
    """a and b from the orbit's sensitivity agree with differences of the plain re-aim (the
    walker without steering) started from the orbit's touchdown with pitch theta_p + d and
    momentum M_p + d."""
    gait = default_gait
    hybrid = planner.hybrid
    ref = reference(hybrid, hybrid.flow(32), gait.step.q0, gait.step.q_target, gait.step.qd_a, gait.step.qd_b, gait.period)
    assert ref.theta == pytest.approx(gait.theta, abs=1e-12) and 0.98 < ref.b < 1.0
    feedback = Feedback(hybrid)  # the plain re-aim
    aim = feedback.aim((PlannedOrbit.of(gait),))

    def next_momentum(d_theta: float, d_momentum: float) -> float:
        q_pre = gait.step.q_target + d_theta * boundary_configurations(hybrid.bm).theta_direction
        impact = hybrid.impact(q_pre)
        row = impact.momentum_row[3:]
        shift = ref.momentum + d_momentum - row @ gait.step.qd_b  # the momentum held at M_p + d_momentum
        xd_b = np.concatenate([np.zeros(3), gait.step.qd_b + shift * row / (row @ row)])
        v, period = feedback.reaim_velocity(aim, hybrid.exchange.configuration(q_pre), impact, xd_b, 0.0)
        end = hybrid.flow(32).propagate(hybrid.exchange.configuration(q_pre), v, period)
        return float(momentum_row(hybrid, end.q) @ end.qd)

    h = 1e-6
    a = (next_momentum(h, 0) - next_momentum(-h, 0)) / (2 * h)
    b = (next_momentum(0, h) - next_momentum(0, -h)) / (2 * h)
    print(f"\na = {ref.a:.6f} (differences {a:.6f}), b = {ref.b:.6f} (differences {b:.6f})")
    assert ref.a == pytest.approx(a, rel=1e-5) and ref.b == pytest.approx(b, rel=1e-5)
    assert pelvis_pitch(planner.model, gait.step.q_target) == pytest.approx(gait.theta, abs=1e-12)


def test_the_steered_walk_lands_on_the_plan(planner, default_gait):
    walker = Walker(planner.hybrid, PlannedOrbit.of(default_gait), rate=200.0, momentum_rate=DEFAULT_RATE)
    errors = [walker.walk_step().touchdown.state_error for _ in range(10)]
    assert max(errors) < 1e-9


def test_the_steered_closed_loop_contracts_at_the_steering_rate(planner, default_gait):
    """The closed loop's slow multiplier (0.99 with the plain re-aim) becomes the rate rho."""
    orbit = PlannedOrbit.of(default_gait)

    def walker_at(q, qd):
        walker = Walker(planner.hybrid, orbit, rate=1.0, momentum_rate=0.25)
        walker.state = replace(walker.state, q=q, qd=qd)
        return walker

    loop = closed_loop(walker_at, orbit_start(default_gait))
    print(f"\nsteered closed loop (rho = 0.25): |multipliers| {np.round(np.abs(loop.values[:4]), 4)}")
    assert loop.spectral_radius == pytest.approx(0.25, abs=5e-3)


def distances_after_push(planner, gait, rate: float | None, magnitude: float, direction: str) -> list[float]:
    """Distance to the orbit (rad, rad/s) at the start of each step after a push of ``magnitude``
    (N s) in ``direction`` at mid-step, for the pushed step and up to 10 more (fewer: a fall)."""
    walker = Walker(planner.hybrid, PlannedOrbit.of(gait), rate=10.0, momentum_rate=rate)
    walker.push(Push(horizontal_impulse(magnitude, DIRECTIONS[direction]), 0.5 * gait.period))
    out = []
    for _ in range(11):
        if walker.walk_step().touchdown is None:
            break
        out.append(distance(walker, gait))
    return out


@pytest.mark.parametrize("direction", ["forward", "left"])
def test_a_push_is_recovered_by_steering(planner, default_gait, direction):
    """0.1 N s on the trunk at mid-step: back within 1e-3 of the orbit 10 steps after the push."""
    steered = distances_after_push(planner, default_gait, DEFAULT_RATE, 0.1, direction)
    print(f"\n{direction}, 0.1 N s: distance to the orbit {' '.join(f'{d:.0e}' for d in steered)}")
    assert len(steered) == 11 and steered[-1] < 1e-3


def test_the_plain_reaim_recovers_only_slowly_or_falls(planner, default_gait):
    """Without steering, 0.001 N s forward leaves the walker at another cadence, its distance to
    the orbit shrinking about 1 % per step; 0.01 N s and the chord steps from the orbit diverge."""
    small = distances_after_push(planner, default_gait, None, 0.001, "forward")
    print(f"\nplain re-aim, 0.001 N s: distance to the orbit {' '.join(f'{d:.0e}' for d in small)}")
    assert len(small) == 11 and small[-1] > 1e-3 and small[-1] > 0.5 * small[1]
    assert len(distances_after_push(planner, default_gait, None, 0.01, "forward")) < 11
