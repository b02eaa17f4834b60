"""The closed chain of a double support that lasts (core/dynamics/closed_chain.py): both tips stay
held, the forward dynamics and the double-support model's inverse dynamics agree, the chain keeps
its energy without torque, and the passive impact with both tips held; at the paper's touchdown it
would pull the old stance foot."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.dynamics.closed_chain import ClosedChain
from biped_gait.core.gait.planner import GaitRequest

pytestmark = pytest.mark.core


@pytest.fixture(scope="module", params=["aoustin2013", "aoustin2013-hips"])
def setting(request, planner, hips):
    chosen = planner if request.param == "aoustin2013" else hips
    alpha = 23.5 if request.param == "aoustin2013" else 20.0
    gait = chosen.plan(GaitRequest(0.45, 0.45, math.radians(alpha), "normal"))
    return chosen, ClosedChain(chosen.model, chosen.hybrid.exchange), gait


def _energy(chain: ClosedChain, q: np.ndarray, qd: np.ndarray) -> float:
    model, data = chain.ds, chain.ds_data
    x, xd = chain.bm.ds_state(q), chain.bm.embed(qd)
    return pin.computeKineticEnergy(model, data, x, xd) + pin.computePotentialEnergy(model, data, x)


def _passive(chain: ClosedChain, q: np.ndarray, qd: np.ndarray, duration: float, steps: int):
    """RK4 of the closed chain without torque."""
    zero = np.zeros(len(chain.actuated))
    h = duration / steps
    for _ in range(steps):
        k1 = qd, chain.forward(q, qd, zero)[0]
        k2 = qd + h / 2 * k1[1], chain.forward(q + h / 2 * k1[0], qd + h / 2 * k1[1], zero)[0]
        k3 = qd + h / 2 * k2[1], chain.forward(q + h / 2 * k2[0], qd + h / 2 * k2[1], zero)[0]
        k4 = qd + h * k3[1], chain.forward(q + h * k3[0], qd + h * k3[1], zero)[0]
        q = q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        qd = qd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    return q, qd


def test_the_passive_chain_holds_both_tips_and_keeps_its_energy(setting):
    """From the touchdown, after the held impact, 50 ms without torque (RK4, 0.5 ms steps): the new
    tip moves by less than 1e-9 m in its held directions, its held velocity stays zero, and the
    energy drifts by less than 1e-8 of the kinetic energy (the contacts do no work)."""
    _, chain, gait = setting
    q, qd = gait.step.q_target, chain.impact(gait.step.q_target, gait.step.qd_b).qd
    start_tip, start_energy = chain.bm.swing_tip(q), _energy(chain, q, qd)
    kinetic = start_energy - _energy(chain, q, np.zeros_like(qd))
    q1, qd1 = _passive(chain, q, qd, 0.05, 100)
    held = [0, 2] if chain.lateral_free else [0, 1, 2]
    assert np.max(np.abs((chain.bm.swing_tip(q1) - start_tip)[held])) < 1e-9
    assert np.max(np.abs(chain.rows_of(q1) @ qd1)) < 1e-9
    assert abs(_energy(chain, q1, qd1) - start_energy) < 1e-8 * kinetic


def test_forward_dynamics_and_the_double_support_model_agree(setting):
    """qdd and the new tip's reaction from the forward dynamics satisfy the double-support model's
    inverse dynamics in every joint row (a second path through Pinocchio's RNEA) to 1e-9 of the
    body's weight, under a torque of the joints' own size."""
    _, chain, gait = setting
    rng = np.random.default_rng(3)
    q, qd = gait.step.q_target, 0.5 * rng.standard_normal(chain.n)
    qd = qd - np.linalg.pinv(chain.rows_of(q)) @ (chain.rows_of(q) @ qd)  # a velocity the tips allow
    torque = 50.0 * rng.standard_normal(len(chain.actuated))
    qdd, held = chain.forward(q, qd, torque)
    new = chain.full_force(held)
    x, xd, xdd = chain.bm.ds_state(q), chain.bm.embed(qd), chain.bm.embed(qdd)
    tau = pin.rnea(chain.ds, chain.ds_data, x, xd, xdd) - chain.new_tip(q).T @ new
    weight = chain.bm.total_mass * chain.bm.params.gravity
    assert np.max(np.abs(tau[chain.at] - chain.selection @ torque)) < 1e-9 * weight


def test_the_held_impact_is_inelastic_and_holds_both_tips(setting):
    _, chain, gait = setting
    q, qd = gait.step.q_target, gait.step.qd_b
    impact = chain.impact(q, qd)
    assert np.max(np.abs(chain.rows_of(q) @ impact.qd)) < 1e-12
    before, after = (_energy(chain, q, v) - _energy(chain, q, np.zeros_like(v)) for v in (qd, impact.qd))
    assert after < before
    # the impulses are the momentum's change: the linear momentum changes by their sum
    p_before = chain.bm.momentum(q, chain.bm.embed(qd))[0]
    p_after = chain.bm.momentum(q, chain.bm.embed(impact.qd))[0]
    assert np.allclose(p_after - p_before, impact.old[:3] + impact.new[:3], atol=1e-9)


def test_at_the_papers_touchdown_a_held_impact_would_pull_the_old_stance_foot(planner, default_gait):
    """The paper's gait lands on straight legs: held on the ground, its old stance foot would need
    the ground to pull it down (a vertical impulse of -57.8 N s), which is why the paper's old foot
    leaves the ground at the impact (docs/model.md section 12)."""
    chain = ClosedChain(planner.model, planner.hybrid.exchange)
    impact = chain.impact(default_gait.step.q_target, default_gait.step.qd_b)
    assert impact.old[2] == pytest.approx(-57.84, abs=0.01)
    assert impact.new[2] > 0


@pytest.mark.parametrize("which", ["aoustin2013", "aoustin2013-hips"])
def test_every_gait_of_the_family_would_pull_its_old_stance_foot_held(which, planner, hips):
    """The evidence behind docs/model.md section 12.1 (i): over the gaits' range (L 0.3 to 0.6 m,
    T 0.4 to 0.6 s, both modes, alpha 20 deg), the passive impact with both feet held needs the
    ground to pull the old stance foot down by 38 to 68 N s: a double support that lasts cannot begin
    with a passive touchdown of these gaits. Measured: -49.2 to -67.5 N s (aoustin2013), -38.6 to
    -46.9 N s (aoustin2013-hips); far from 0, so a bound of -30 N s holds on any machine."""
    chosen = planner if which == "aoustin2013" else hips
    chain = ClosedChain(chosen.model, chosen.hybrid.exchange)
    pulls = []
    for length in (0.3, 0.4, 0.5, 0.6):
        for period in (0.4, 0.5, 0.6):
            for mode in ("normal", "anti-normal"):
                gait = chosen.plan(GaitRequest(length, period, math.radians(20.0), mode))
                impact = chain.impact(gait.step.q_target, gait.step.qd_b)
                assert impact.new[2] > 0
                pulls.append(impact.old[2])
    print(f"\n{which}: the old stance foot's vertical impulse, held, from {min(pulls):.1f} to {max(pulls):.1f} N s")
    assert len(pulls) == 24 and max(pulls) < -30.0
