"""The ballistic flow: energy conservation, agreement with SciPy's adaptive integrator, and
exact sensitivities."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

from biped_gait.core.dynamics.flow import BallisticFlow, hermite_samples

pytestmark = pytest.mark.core


def test_energy_is_conserved_along_the_step(planner, default_gait):
    run = planner.flow.propagate(np.array(default_gait.step.q0), np.array(default_gait.qd_a), default_gait.period, keep_nodes=True)
    energy = planner.hybrid.samples.energy(run.nodes[1], run.nodes[2])
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-9
    assert default_gait.figures.energy_drift < 1e-9


def test_energy_is_conserved_from_a_violent_start(planner):
    """Far from the gait (the straight-line guess of a long fast step), drift stays below 1e-9."""
    q0 = np.array([0.02, -0.3, 0.1, 0.4, 0.05, 0.5, -0.4, 0.2, 0.3])
    qd0 = np.array([0.3, 2.5, -1.0, -2.0, 0.5, -1.5, 2.0, -4.0, 6.0])
    run = planner.flow.propagate(q0, qd0, 0.45, keep_nodes=True)
    energy = planner.hybrid.samples.energy(run.nodes[1], run.nodes[2])
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-9


def test_fixed_grid_agrees_with_adaptive_dop853(planner, default_gait):
    model = planner.model.single
    data = model.createData()
    tau = np.zeros(9)

    def rhs(_t, y):
        return np.concatenate([y[9:], pin.aba(model, data, y[:9], y[9:], tau)])

    q0, qd0 = np.array(default_gait.step.q0), np.array(default_gait.qd_a)
    ref = solve_ivp(rhs, (0, default_gait.period), np.concatenate([q0, qd0]), method="DOP853", rtol=1e-13, atol=1e-13)
    run = planner.flow.propagate(q0, qd0, default_gait.period)
    assert np.max(np.abs(np.concatenate([run.q, run.qd]) - ref.y[:, -1])) < 1e-10


def test_sensitivities_match_central_differences(planner):
    flow = BallisticFlow(planner.model.single, steps=16)
    rng = np.random.default_rng(5)
    q0, qd0 = rng.uniform(-0.3, 0.3, 9), rng.uniform(-1, 1, 9)
    seeds = rng.normal(size=(18, 3))
    run = flow.propagate(q0, qd0, 0.3, seeds)
    h = 1e-6
    for k in range(3):
        plus = flow.propagate(q0 + h * seeds[:9, k], qd0 + h * seeds[9:, k], 0.3)
        minus = flow.propagate(q0 - h * seeds[:9, k], qd0 - h * seeds[9:, k], 0.3)
        fd = (np.concatenate([plus.q, plus.qd]) - np.concatenate([minus.q, minus.qd])) / (2 * h)
        assert np.allclose(run.sens[:, k], fd, rtol=1e-6, atol=1e-7)


def test_hermite_samples_reproduce_the_nodes_and_the_flow(planner, default_gait):
    q0, qd0 = np.array(default_gait.step.q0), np.array(default_gait.qd_a)
    run = planner.flow.propagate(q0, qd0, default_gait.period, keep_nodes=True)
    t = run.nodes[0]
    q, qd = hermite_samples(run.nodes, t)
    assert np.allclose(q, run.nodes[1], atol=1e-14) and np.allclose(qd, run.nodes[2], atol=1e-12)
    mid = 0.5 * (t[3] + t[4])
    qm, qdm = hermite_samples(run.nodes, np.array([mid]))
    direct = planner.flow.propagate(q0, qd0, mid)
    assert np.allclose(qm[0], direct.q, atol=1e-9) and np.allclose(qdm[0], direct.qd, atol=1e-7)


def test_steps_must_be_positive(planner):
    with pytest.raises(ValueError, match="steps must be at least 1"):
        BallisticFlow(planner.model.single, steps=0)


def test_compiled_and_python_flows_agree(planner, default_gait):
    """The compiled twin (built by tools/setup.sh) and the Python loop: same scheme, same
    Pinocchio algorithms, results equal to rounding - states, sensitivities and nodes."""
    compiled = BallisticFlow(planner.model.single, steps=32, native=True)
    python = BallisticFlow(planner.model.single, steps=32, native=False)
    rng = np.random.default_rng(2)
    seeds = rng.normal(size=(18, 10))
    q0, qd0 = np.array(default_gait.step.q0), np.array(default_gait.qd_a)
    a = compiled.propagate(q0, qd0, 0.45, seeds, keep_nodes=True)
    b = python.propagate(q0, qd0, 0.45, seeds, keep_nodes=True)
    assert np.allclose(a.q, b.q, atol=1e-12) and np.allclose(a.qd, b.qd, atol=1e-11)
    # Random seeds grow to ~1e4 over the step: compare relative to the sensitivities' scale.
    assert np.max(np.abs(a.sens - b.sens)) < 1e-11 * np.max(np.abs(b.sens))
    for x, y in zip(a.nodes, b.nodes):
        assert np.allclose(x, y, atol=1e-10)
    assert a.evaluations == b.evaluations
    plain = compiled.propagate(q0, qd0, 0.45)
    assert plain.sens is None and plain.nodes is None and np.allclose(plain.q, b.q, atol=1e-12)
