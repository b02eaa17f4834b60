"""Standing (core/walking/balance.py, phases/standing.py): the posture balances gravity with its
centre of mass over the feet line, its linearization falls without control and the LQR holds it,
in the planner's model with both feet held; pushes within the measured limits are recovered, a
larger one is a fall with its reason."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.dynamics.closed_chain import ClosedChain
from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.walking.balance import balance, centre_offset, standing_pose, uncontrollable
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.phases.standing import Standing
from biped_gait.core.walking.push import Push
from biped_gait.core.walking.runner import Walker

pytestmark = pytest.mark.core


@pytest.fixture(scope="module", params=["aoustin2013", "aoustin2013-hips"])
def standing(request, planner, hips):
    chosen = planner if request.param == "aoustin2013" else hips
    chain = ClosedChain(chosen.model, chosen.hybrid.exchange)
    gait = chosen.plan(GaitRequest(0.45, 0.45, math.radians(20.0), "normal"))
    return chosen, balance(chain, standing_pose(chain)), PlannedOrbit.of(gait)


def test_the_posture_balances_gravity_over_the_feet_line(standing):
    _, held, _ = standing
    chain, pose = held.chain, held.pose
    assert abs(centre_offset(chain, pose.q)) < 1e-9
    qdd, force = chain.forward(pose.q, np.zeros(chain.n), pose.torque)
    assert np.max(np.abs(qdd)) < 1e-9  # the static torques hold it at rest
    weight = chain.bm.total_mass * chain.bm.params.gravity
    wrenches = chain.wrenches(pose.q, np.zeros(chain.n), qdd, chain.full_force(force))
    assert wrenches[:, 2].sum() == pytest.approx(weight, rel=1e-9)
    assert np.all(wrenches[:, 2] > 0.4 * weight)  # both feet loaded
    assert np.max(np.abs(pose.torque)) < 20.0  # straight legs: small torques


def test_standing_falls_without_control_and_the_lqr_holds_it(standing):
    """The linearization has unstable modes (the fall about the feet line, tenths of a second; the
    knees' buckling, faster), every one controllable (PBH), and the closed loop is stable, its
    fastest mode within what a 1 ms step integrates."""
    _, held, _ = standing
    assert np.max(held.open_loop.real) > 1.0 and held.time_constant < 0.5
    assert np.max(held.closed_loop.real) < -1.0 and np.min(held.closed_loop.real) > -500.0


def _walker(setting, rate: float = 100.0) -> Walker:
    planner, held, orbit = setting
    return Walker(planner.hybrid, orbit, rate, phase=Standing(held))


def _stand(walker: Walker, seconds: float):
    samples = []
    while not samples or samples[-1].t < seconds - 1e-9:
        run = walker.run_phase()
        samples += run.samples
        if run.fall:
            return samples, run.fall
    return samples, ""


def test_standing_holds_for_as_long_as_asked(standing):
    walker = _walker(standing)
    samples, fall = _stand(walker, 5.0)
    assert not fall
    pose = standing[1].pose
    assert max(np.max(np.abs(s.q - pose.q)) for s in samples) < 1e-9
    assert all(len(s.feet) == 2 and s.phase == "standing" for s in samples)
    assert samples[-1].t >= 5.0 - 1e-9 and np.all(np.diff([s.t for s in samples]) > 0)


@pytest.mark.parametrize("impulse", [(0.5, 0.0, 0.0), (-0.5, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)])
def test_a_push_within_the_measured_limit_is_recovered(standing, impulse):
    walker = _walker(standing)
    walker.push(Push(np.array(impulse), 0.2))
    samples, fall = _stand(walker, 2.0)
    assert not fall
    assert np.max(np.abs(samples[-1].q - standing[1].pose.q)) < 5e-3 and np.max(np.abs(samples[-1].qd)) < 1e-2


def test_a_push_well_above_the_limit_is_a_fall_with_its_reason(standing):
    walker = _walker(standing)
    walker.push(Push(np.array([5.0, 0.0, 0.0]), 0.2))
    _, fall = _stand(walker, 2.0)
    assert "slips" in fall or "not positive" in fall


def test_an_uncontrollable_mode_is_found():
    """The PBH test flags an unstable mode no input moves (and none that one moves)."""
    a = np.diag([2.0, -1.0])
    assert uncontrollable(a, np.array([[0.0], [1.0]])) == [2.0]
    assert uncontrollable(a, np.array([[1.0], [1.0]])) == []
