"""Walking on a circle with the 13-DOF set: the stride of two steps (periodic modulo a yaw
rotation of 2 L / R), its mirror image when the turn changes side, its straight limit, the
effort's dependence on the curvature, a circle walked closed loop, and a radius too small."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.model.exchange import next_heading
from biped_gait.core.walking.push import Push
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker

pytestmark = pytest.mark.core

L, T, ALPHA = 0.45, 0.45, math.radians(20.0)
STRIDES = 14  # strides in the circle below
R_CIRCLE = STRIDES * 2 * L / (2 * math.pi)  # m: 14 strides of heading change 2 L / R make a full turn


def request(radius: float) -> GaitRequest:
    return GaitRequest(L, T, ALPHA, "normal", turn_radius=radius)


@pytest.fixture(scope="module")
def strides(hips):
    """Strides by radius (m), and the straight gait at the same (L, T, alpha)."""
    out = {radius: hips.plan_stride(request(radius)) for radius in (R_CIRCLE, -R_CIRCLE, 5.0, 1e4)}
    return out, hips.plan(GaitRequest(L, T, ALPHA, "normal"))


def cycle(stride) -> tuple[PlannedOrbit, ...]:
    return tuple(PlannedOrbit.of(step) for step in stride.steps)


def test_a_stride_is_admissible_and_periodic_modulo_its_rotation(hips, strides):
    stride = strides[0][R_CIRCLE]
    assert stride.converged and stride.admissible, stride.reasons
    assert stride.heading_change == pytest.approx(2 * L / R_CIRCLE, abs=1e-12)
    heading = 0.0  # the world's, after each touchdown: A lands the left foot, B the right
    for step, landing in zip(stride.steps, ("left", "right")):
        heading = next_heading(heading, landing, step.double_support.heading_change)
    assert heading == pytest.approx(2 * L / R_CIRCLE, abs=1e-9)
    assert stride.W == pytest.approx(sum(step.W for step in stride.steps), rel=1e-12)
    for step in stride.steps:
        assert step.step.end_residual < 1e-10
        assert step.double_support.impulses.equation_residual < 1e-9
    # Walked from the plan's start, two strides land on the plan at every touchdown, to 1e-9.
    walker = Walker(hips.hybrid, cycle(stride), rate=50.0)
    for k in range(4):
        outcome = walker.walk_step()
        assert outcome.touchdown is not None, outcome.fall
        assert outcome.touchdown.state_error < 1e-9
        assert outcome.touchdown.W == pytest.approx(stride.steps[k % 2].W, rel=1e-7)
    assert walker.state.heading == pytest.approx(2 * stride.heading_change, abs=1e-9)
    assert np.max(np.abs(walker.state.q - stride.steps[0].step.q0)) < 1e-9
    assert np.max(np.abs(walker.state.qd - stride.steps[0].step.qd_a)) < 1e-9


def test_turning_right_is_the_mirror_image_of_turning_left(strides):
    left, right = strides[0][R_CIRCLE], strides[0][-R_CIRCLE]
    assert right.W == pytest.approx(left.W, rel=1e-10)
    # Each step in its own (mirrored) coordinates: the right turn's step on the right foot is
    # the left turn's step on the left foot.
    for mine, mirrored in ((0, 1), (1, 0)):
        assert np.max(np.abs(right.steps[mine].step.q0 - left.steps[mirrored].step.q0)) < 1e-12
        assert np.max(np.abs(right.steps[mine].qd_a - left.steps[mirrored].qd_a)) < 1e-10


def test_the_effort_is_least_straight_and_the_straight_gait_is_the_limit(strides):
    by_radius, straight = strides
    far = by_radius[1e4]
    assert far.W == pytest.approx(2 * straight.W, rel=1e-8)
    for step in far.steps:
        assert np.max(np.abs(step.qd_a - straight.qd_a)) < 1e-2  # O(1/R) away
    # W(1/R), even in 1/R (the mirror above), grows from its straight value.
    efforts = [2 * straight.W, far.W, by_radius[5.0].W, by_radius[R_CIRCLE].W]
    assert efforts == sorted(efforts)
    assert by_radius[5.0].W > 2 * straight.W * 1.02


def test_a_circle_walked_closes_on_its_start(hips, strides):
    """14 strides of 2 L / R each: back at the start heading and foot, with momentum steering."""
    stride = strides[0][R_CIRCLE]
    walker = Walker(hips.hybrid, cycle(stride), rate=20.0, momentum_rate=0.25)
    start = walker.state.stance_foot.copy()
    for _ in range(2 * STRIDES):
        outcome = walker.walk_step()
        assert outcome.touchdown is not None, outcome.fall
        assert outcome.touchdown.state_error < 1e-8
    assert walker.state.heading == pytest.approx(2 * math.pi, abs=1e-8)
    assert walker.state.stance_side == "right"
    assert np.linalg.norm(walker.state.stance_foot - start) < 1e-6


def test_a_radius_too_small_is_refused_with_the_smallest_radius(hips):
    stride = hips.plan_stride(request(0.8))
    assert not stride.admissible
    assert "smallest turn radius of an admissible stride at L = 0.45 m, T = 0.45 s, alpha = 20 deg" in stride.hint
    smallest = float(stride.hint.rsplit(":", 1)[1].strip().removesuffix(" m"))
    assert 0.8 < smallest < R_CIRCLE
    assert hips.plan_stride(request(smallest * 1.02)).admissible


def test_a_circle_needs_lateral_hips():
    with pytest.raises(ValueError, match="needs hip roll and yaw joints"):
        GaitPlanner("aoustin2013").plan_stride(request(2.0))


def test_pushes_while_turning_are_recovered_or_falls_with_their_reason(hips, strides):
    """On the circle, with momentum steering: 0.5 N s sideways at mid-step is recovered (back
    within 1e-5 of the plan 12 steps later); 1 N s forward is a fall whose reason gives the
    momentum about the feet line against the plan's; 3 N s forward one the double support
    cannot take."""
    stride = strides[0][R_CIRCLE]

    def walk(impulse: list[float]) -> list:
        walker = Walker(hips.hybrid, cycle(stride), rate=20.0, momentum_rate=0.25)
        outcomes = []
        for k in range(16):
            if k == 2:
                walker.push(Push(np.array(impulse), 0.2))
            outcomes.append(walker.walk_step())
            if outcomes[-1].touchdown is None:
                break
        return outcomes

    sideways = walk([0.0, 0.5, 0.0])
    assert all(o.touchdown is not None for o in sideways) and len(sideways) == 16
    assert max(o.touchdown.state_error for o in sideways[2:6]) > 0.1  # pushed off the orbit
    assert max(o.touchdown.state_error for o in sideways[14:]) < 1e-5  # and back on it
    hard = walk([1.0, 0.0, 0.0])[-1]
    assert hard.touchdown is None and "the momentum about the feet line, which no impulse changes, is" in hard.fall
    harder = walk([3.0, 0.0, 0.0])[-1]
    assert harder.touchdown is None and "the double support at t =" in harder.fall and "has no solution" in harder.fall


def test_a_turning_atlas_line_stays_on_the_human_like_branch():
    """L = 0.45 m, T = 0.5 s, alpha = 20 deg, normal: each curvature warm-started from the last
    (as the atlas is built) stays on the branch of the straight gait, admissible to 1/R = 0.9 1/m,
    the swing knees within 2 deg of straight and W of the stride growing with the curvature (warm
    started directly, step B jumped to the twin branch, knee -42 deg, from R = 14 m)."""
    from biped_gait.core.gait.atlas import NodeStatus
    from biped_gait.core.gait.configurations import GaitMode
    from biped_gait.core.gait.turning_atlas import TurningGrid
    from biped_gait.core.model.params import load_params
    from biped_gait.studies.turning_atlas_build import build_turning_slab

    grid = TurningGrid.default()
    line = TurningGrid(np.array([0.45]), np.array([0.5]), np.array([math.radians(20.0)]), grid.curvatures[:10])
    _, nodes = build_turning_slab(load_params("aoustin2013-hips"), GaitMode.NORMAL, line, 0)
    assert np.all(nodes["status"][0, 0] == NodeStatus.ADMISSIBLE), nodes["status"][0, 0]
    assert np.degrees(nodes["q9_min"][0, 0]).min() > -2.0
    assert np.all(np.diff(nodes["W"][0, 0]) > 0)
