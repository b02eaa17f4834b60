"""The 13-DOF biped (``aoustin2013-hips``: a yaw, a roll and a pitch joint in each hip): its
straight gaits by the same BVP and closure, the double support over all eleven actuated joints,
the step width, and its walk."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from biped_gait.core.gait import views
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.walking.events import StepSamples
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.walk import Walk

pytestmark = pytest.mark.core

HIPS = "aoustin2013-hips"


@pytest.fixture(scope="module")
def gait(hips):
    return hips.plan(GaitRequest(0.45, 0.45, math.radians(20.0), "normal"))


def test_the_straight_gait_is_an_exact_periodic_orbit(hips, gait):
    assert gait.converged and gait.admissible, gait.reasons
    assert len(gait.qd_a) == 13 and len(gait.double_support.impulses.i_minus) == 11
    assert gait.step.end_residual < 1e-12 and abs(gait.step.closure_gap) < 1e-11
    assert gait.double_support.impulses.equation_residual < 1e-9  # eqs. (6)-(10), all 59 rows
    assert gait.figures.energy_drift < 1e-12  # the ballistic flow conserves energy
    # The next step starts where this one began: P q(T) = q(0), the exchanged velocity = qd(0).
    exchange = hips.hybrid.exchange
    q_t, xd_a = gait.step.q_target, gait.double_support.xd_a
    assert np.allclose(exchange.configuration(q_t), gait.step.q0, atol=1e-14)
    assert np.allclose(exchange.velocity(q_t, xd_a), gait.qd_a, atol=1e-10)
    assert abs(exchange.heading(q_t)) < 1e-14  # straight ahead
    # the hips' lateral joints move in the step and are back at zero at its end
    q = gait.figures.samples.q
    roll = hips.model.index("hip_roll", "swing")
    assert np.abs(q[:, roll]).max() > math.radians(3.0) and abs(q[-1, roll]) < 1e-12


def test_the_lp_uses_the_hips_joints(gait):
    impulses = gait.double_support.impulses
    names = gait.names.actuated
    lateral = [k for k, name in enumerate(names) if "hip_roll" in name or "hip_yaw" in name]
    assert len(lateral) == 4
    assert np.abs(np.concatenate([impulses.i_minus[lateral], impulses.i_plus[lateral]])).max() > 0.1
    assert gait.double_support.impulse_friction_ratios.max() <= 0.5 + 1e-9  # the cone, as for the nine joints
    assert len(impulses.spin_impulses) == 3
    data = views.to_dict(gait)
    assert data["actuated_joints"] == list(names) and len(data["I_minus"]) == 11 and len(data["Xd_a"]) == 17
    assert data["double_support_coordinates"][5] == "stance_ankle_spin"


@pytest.mark.parametrize("mode", ["normal", "anti-normal"])
def test_the_bvp_converges_over_the_arm_amplitudes(hips, mode):
    """L = T = 0.45 s, alpha 0 to 45 deg: from the atlas (or continuation) on the branch, admissible."""
    for alpha in range(0, 46, 5):
        gait = hips.plan(GaitRequest(0.45, 0.45, math.radians(alpha), mode))
        assert gait.converged and gait.admissible and gait.found in ("atlas", "continuation"), (alpha, gait.reasons)
        assert gait.double_support.impulses.equation_residual < 1e-9


@pytest.mark.parametrize("width", [0.3, 0.5])
def test_another_step_width(hips, gait, width):
    """Feet 0.3 or 0.5 m apart at T = 0.5 s: the legs lean, the gait still closes; the new foot
    lands at (L, w). (At T = 0.45 s these widths bend the swing knee backwards, 4 and 10 deg, once
    the closure matches what the leaning legs' spin moments do: docs/model.md section 5.)"""
    other = hips.plan(GaitRequest(0.45, 0.5, math.radians(20.0), "normal", step_width=width))
    assert other.converged and other.admissible, other.reasons
    assert np.allclose(other.double_support.new_stance_foot, [0.45, width, 0.0], atol=1e-12)
    ds = other.double_support  # the closure matched to what the leaning legs' spin moments do
    assert abs(other.step.closure_gap + ds.foot_line_moment) < 1e-11 and ds.impulses.equation_residual < 1e-9
    assert other.step.q_target[0] != 0.0  # the stance ankle rolls
    assert views.to_dict(other)["step_width"] == width


def test_a_step_width_out_of_range_is_refused_with_one_line(hips):
    with pytest.raises(ValueError, match=r"step width must be in \[0.2, 0.6\] m for parameter set aoustin2013-hips"):
        hips.plan(GaitRequest(0.45, 0.45, 0.3, "normal", step_width=0.9))
    with pytest.raises(ValueError, match="needs hip roll and yaw joints"):
        GaitPlanner("aoustin2013").plan(GaitRequest(0.45, 0.45, 0.3, "normal", step_width=0.3))
    run = subprocess.run([sys.executable, "-m", "biped_gait.cli", "plan", "--params", HIPS, "--step-width", "0.05"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and run.stdout == "" and len(run.stderr.strip().splitlines()) == 1, run.stderr


def test_twenty_steps_land_on_the_plan(hips, gait):
    walker = Walker(hips.hybrid, PlannedOrbit.of(gait), rate=100.0, momentum_rate=0.25)
    errors = []
    for _ in range(20):
        outcome = walker.walk_step()
        assert outcome.touchdown is not None, outcome.fall
        errors.append(outcome.touchdown.state_error)
    assert max(errors) < 1e-9
    assert np.allclose(walker.state.stance_foot, [20 * 0.45, -0.2, 0.0], atol=1e-9)
    assert abs(walker.state.heading) < 1e-12


def test_the_left_step_is_the_mirror_image_of_the_right(hips, gait):
    """Walked: the second step (left foot) is the first (right foot) seen in the mirror y -> -y
    about the walking line, L further on: the URDF's joints swap sides and the lateral ones
    change sign, the pelvis mirrors."""
    walk = Walk(PlannedOrbit.of(gait), rate=200.0, steps=2)
    steps = [item for item in walk.batches() if isinstance(item, StepSamples)]
    first, second = steps[0], steps[1]
    n = min(len(first.samples), len(second.samples)) - 1
    names = list(first.world.joint_names)
    lateral = {"torso_yaw"} | {name for name in names if "hip_roll" in name or "hip_yaw" in name}
    swap = [names.index(name.replace("right", "@").replace("left", "right").replace("@", "left")) for name in names]
    sign = np.array([-1.0 if name in lateral else 1.0 for name in names])
    a, b = first.world.joint_positions[1:n], second.world.joint_positions[1:n]
    assert np.allclose(b, a[:, swap] * sign, atol=1e-8)
    pa, pb = first.world.pelvis_position[1:n], second.world.pelvis_position[1:n]
    assert np.allclose(pb, pa * [1.0, -1.0, 1.0] + [0.45, 0.0, 0.0], atol=1e-8)
