"""The reaction guard of the actuated swing's walk (core/walking/reaction_guard.py, docs/model.md
15.1): torques that would tip a held foot's reaction out of the friction pyramid, or unload it, are
replaced by the nearest torques (each joint weighed by its effort limit) that keep it within reach,
checked against the walk's own fall test and against an independent solver (SciPy's SLSQP) of the
same program; torques already within reach pass unchanged. Both chains: the closed chain (both feet
held, standing's posture) and the single support driven by joint torques (the stance tip pinned)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from biped_gait.core.dynamics.closed_chain import ClosedChain
from biped_gait.core.walking.balance import effort_limits, standing_pose
from biped_gait.core.walking.phases.pulse_dynamics import PinnedTip, friction_ratio
from biped_gait.core.walking.reaction_guard import GUARD_LEAST_NORMAL_FORCE, guarded_torque, within_reach


@pytest.fixture(scope="module")
def standing(planner):
    chain = ClosedChain(planner.model, planner.hybrid.exchange)
    return chain, standing_pose(chain)


def _reference(chain, q, qd, torque, limits):
    """The guard's program solved by SLSQP from the clipped torque: least sum ((v - torque) / limit)^2
    over the torques v (and the free lateral share) within the guard's constraints (``within_reach``)
    and the limits."""
    a, bound = within_reach(chain, q, qd, len(torque))
    n = len(torque)
    free = a.shape[1] - n
    bounds = [(-lim, lim) for lim in limits] + [(None, None)] * free
    result = minimize(lambda v: float(np.sum(((v[:n] - torque) / limits) ** 2)),
                      np.concatenate([np.clip(torque, -limits, limits), np.zeros(free)]),
                      jac=lambda v: np.concatenate([2 * (v[:n] - torque) / limits ** 2, np.zeros(free)]),
                      constraints=[{"type": "ineq", "fun": lambda v: bound - a @ v, "jac": lambda v: -a}],
                      bounds=bounds, method="SLSQP", options={"ftol": 1e-14, "maxiter": 500})
    assert result.success, result.message
    return result.x[:n]


def test_torques_within_reach_pass_unchanged(standing, planner):
    """Standing's static torques keep both feet pressing well within the cone: the guard returns them
    (the closed chain's lateral share is solved for, so to the program's tolerance: 1e-4 N m, half a
    millionth of a limit); the single support's zero torques in standing's posture (the front foot
    lifted) likewise, exactly (its check needs no program)."""
    chain, pose = standing
    limits = effort_limits(chain)
    kept = guarded_torque(chain, pose.q, np.zeros_like(pose.q), pose.torque, limits)
    assert np.max(np.abs(kept - pose.torque)) < 1e-4
    pinned = PinnedTip(planner.model)
    q = pose.q  # the back foot's stance, the front foot lifted, every joint free
    torque = np.zeros(len(pinned.actuated))
    forces = pinned.forward(q, np.zeros_like(q), torque)[1]
    assert forces[2] > GUARD_LEAST_NORMAL_FORCE and friction_ratio(forces[None]) < 0.3
    assert np.array_equal(guarded_torque(pinned, q, np.zeros_like(q), torque, limits), torque)


@pytest.mark.parametrize("joint, push", [(0, 150.0), (1, -120.0), (4, 170.0)])
def test_torques_that_would_slip_are_moved_to_the_nearest_that_hold(standing, joint, push):
    """Standing's torques with one joint pushed by 120 to 170 N m tip a foot out of the cone (its
    friction ratio above mu = 0.5 or its load below the guard's least); the guard's torques keep
    both feet pressing within the cone (the walk's own test: the best lateral share, ``shared_wrenches``),
    within the limits, and are SLSQP's answer to the same program within 1e-4 of each limit."""
    chain, pose = standing
    limits = effort_limits(chain)
    qd = np.zeros_like(pose.q)
    torque = pose.torque.copy()
    torque[joint] += push

    def wrenches(u):
        qdd, held = chain.forward(pose.q, qd, u)
        return chain.shared_wrenches(pose.q, qd, qdd, held)[:, :3]

    before = wrenches(torque)
    assert friction_ratio(before) > 0.5 or before[:, 2].min() < GUARD_LEAST_NORMAL_FORCE
    kept = guarded_torque(chain, pose.q, qd, torque, limits)
    after = wrenches(kept)
    assert after[:, 2].min() >= GUARD_LEAST_NORMAL_FORCE - 1e-3
    assert friction_ratio(after) <= 0.5
    assert np.all(np.abs(kept) <= limits)
    assert np.max(np.abs(kept - _reference(chain, pose.q, qd, torque, limits)) / limits) < 1e-4
