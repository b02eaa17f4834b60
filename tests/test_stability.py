"""Floquet stability of a gait: the open-loop multipliers from the variational equations agree
with finite differences of the Poincare map, a perturbation grows at the predicted rate, and the
walker's closed loop (impulses re-solved, steps re-aimed) decays at its own predicted rate."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.gait.stability import PoincareMap, closed_loop, multipliers_of, open_loop
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker

pytestmark = pytest.mark.core


@pytest.fixture(scope="module")
def poincare(planner, default_gait) -> PoincareMap:
    impulses = default_gait.double_support.impulses
    return PoincareMap(planner.hybrid, planner.flow, default_gait.period, impulses.i_minus, impulses.i_plus)


def start(gait) -> np.ndarray:
    return np.concatenate([gait.step.q0, gait.step.qd_a])


def test_the_gait_is_a_fixed_point_and_its_multipliers_match_finite_differences(poincare, default_gait):
    x0 = start(default_gait)
    assert np.max(np.abs(poincare(x0) - x0)) < 1e-10
    h = 1e-7
    columns = [(poincare(x0 + h * e) - poincare(x0 - h * e)) / (2 * h) for e in np.eye(18)]
    by_differences = multipliers_of(np.column_stack(columns))
    exact = default_gait.stability
    assert exact.spectral_radius == pytest.approx(by_differences.spectral_radius, rel=1e-5)
    assert np.allclose(np.abs(exact.values[:4]), np.abs(by_differences.values[:4]), rtol=1e-5)
    assert not exact.stable and exact.spectral_radius > 100  # open loop: violently unstable
    assert abs(exact.values[-1]) < 1e-8  # the flow direction: removed by the guard


def test_the_planner_s_multipliers_are_those_integrated_in_line(planner, default_gait):
    """The plan integrates the variational flow on its background thread beside the double
    support: the Jacobian and the multipliers are those of the Poincare map integrated in line
    (the same computation on another thread: equal to rounding, 1e-12 of the largest entry)."""
    impulses = default_gait.double_support.impulses
    in_line = open_loop(planner.hybrid, planner.flow, default_gait.period, default_gait.step.q0, default_gait.step.qd_a,
                        impulses.i_minus, impulses.i_plus)
    scale = np.max(np.abs(in_line.jacobian))
    assert np.max(np.abs(in_line.jacobian - default_gait.stability.jacobian)) <= 1e-12 * scale
    assert np.max(np.abs(in_line.values - default_gait.stability.values)) <= 1e-12 * np.max(np.abs(in_line.values))


def test_a_plan_integrates_one_variational_flow_begun_at_its_last_chord_step(planner, monkeypatch):
    """The shooting's fine flow begins the variational flow from each chord step after the
    first: a plan from the atlas ends with that step, and integrates no other (none wasted, none
    begun again after the shooting)."""
    begun = []
    start = planner.grid.background.start
    monkeypatch.setattr(planner.grid.background, "start", lambda *args: begun.append(args) or start(*args))
    for mode in ("normal", "anti-normal"):
        for alpha in (5.0, 20.0, 40.0):
            gait = planner.plan(GaitRequest(0.45, 0.45, np.radians(alpha), mode))
            assert gait.found == "atlas" and gait.stability is not None
            assert len(begun) == 1 and np.array_equal(begun[0][2], gait.step.qd_a)
            begun.clear()


@pytest.mark.parametrize("params", ["aoustin2013", "aoustin2013-hips"])
def test_the_reset_s_analytic_jacobian_matches_differences(params, planner, hips, default_gait):
    """The reset's Jacobian (``ImpactMap.reset_jacobian``: D_e, J1, J2 and the leg exchange
    differentiated analytically) against fourth-order central differences of the reset at a gait's
    touchdown, at two steps: their truncation error, C h^4, falls 81 times from h = 3e-3 to 1e-3 rad
    (measured: about 5e-8 and 1e-9 of the largest entry), so the analytic Jacobian is within 1e-7
    of them at the first and within 1e-8 at the second, and the differences do converge to it."""
    plan = planner if params == "aoustin2013" else hips
    gait = default_gait if params == "aoustin2013" else plan.plan(GaitRequest(0.45, 0.45, np.radians(20.0), "normal"))
    impulses = gait.double_support.impulses
    poincare = PoincareMap(plan.hybrid, plan.flow, gait.period, impulses.i_minus, impulses.i_plus)
    q, qd = gait.step.q_target, gait.step.qd_b
    exact = plan.hybrid.impact(q).reset_jacobian(qd, impulses.i_minus, impulses.i_plus)
    scale = np.max(np.abs(exact))
    errors = []
    for h in (3e-3, 1e-3):
        def reset(shift: np.ndarray) -> np.ndarray:
            return poincare.reset(q + shift, qd)
        columns = [(8 * (reset(h * e) - reset(-h * e)) - (reset(2 * h * e) - reset(-2 * h * e))) / (12 * h)
                   for e in np.eye(len(q))]
        errors.append(np.max(np.abs(np.column_stack(columns) - exact[:, :len(q)])) / scale)
    assert errors[0] <= 1e-7 and errors[1] <= 1e-8 and errors[1] < errors[0] / 20, errors
    velocity = np.column_stack([(poincare.reset(q, qd + e) - poincare.reset(q, qd - e)) / 2 for e in np.eye(len(q))])
    assert np.max(np.abs(velocity - exact[:, len(q):])) <= 1e-13 * scale  # linear in the velocity: exact


def test_a_perturbation_grows_at_the_predicted_rate(poincare, default_gait):
    x0 = start(default_gait)
    values, vectors = np.linalg.eig(default_gait.stability.jacobian)
    dominant = np.real(vectors[:, np.argmax(np.abs(values))] + vectors[:, np.argsort(-np.abs(values))[1]])
    x = x0 + 1e-12 * dominant / np.linalg.norm(dominant)
    deviations = [1e-12]
    for _ in range(3):
        x = poincare(x)
        deviations.append(float(np.linalg.norm(x - x0)))
    rate = (deviations[-1] / deviations[0]) ** (1 / 3)
    print(f"\nopen loop: growth per step {rate:.1f}, predicted {default_gait.stability.spectral_radius:.1f}")
    assert rate == pytest.approx(default_gait.stability.spectral_radius, rel=0.25)


def test_the_closed_loop_decays_at_its_predicted_rate(planner, default_gait):
    orbit = PlannedOrbit.of(default_gait)

    def walker_at(q, qd):
        walker = Walker(planner.hybrid, orbit, rate=1.0)
        walker.state = replace(walker.state, q=q, qd=qd)
        return walker

    x0 = start(default_gait)
    loop = closed_loop(walker_at, x0)
    assert loop.stable and 0.9 < loop.spectral_radius < 1.0
    walker = walker_at(x0[:9], x0[9:] + 1e-6)
    errors = []
    for _ in range(12):
        assert walker.walk_step().touchdown is not None
        errors.append(float(np.linalg.norm(np.concatenate([walker.state.q, walker.state.qd]) - x0)))
    rate = (errors[-1] / errors[2]) ** (1 / 9)  # past the fast modes
    print(f"closed loop: decay per step {rate:.4f}, predicted {loop.spectral_radius:.4f}")
    assert rate == pytest.approx(loop.spectral_radius, abs=2e-3)
