"""One periodic gait end to end: BVP, closure, impact equations, LP certificate, the ground
reaction two ways, periodicity through the leg exchange, warm starts, options."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy.optimize import linprog

from biped_gait.core.gait import views
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.gait.bvp import StepProblem, solve_bvp
from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.dynamics import impulses
from biped_gait.core.dynamics.impulses import solve_impulses
from biped_gait.core.gait.figures import ground_reaction_momentum
from biped_gait.core.dynamics.samples import ground_reaction_inverse_dynamics

from .conftest import DEFAULT_REQUEST, impact_problem

pytestmark = pytest.mark.core


def test_default_gait_is_converged_admissible_and_human_like(default_gait):
    g = default_gait
    assert g.converged and g.admissible, g.reasons
    assert g.figures.min_grf_z > 0 and g.figures.min_swing_height > 0
    assert g.figures.q9_min >= -1e-9  # swing knee flexes forward: the human-like branch
    assert abs(math.degrees(g.theta)) < 1.0  # "a fraction of a degree"
    assert max(abs(v) for v in g.figures.q3_range) < math.radians(1.0)  # stance leg nearly straight


def test_bvp_and_closure_residuals(default_gait):
    assert default_gait.step.end_residual < 1e-10
    assert abs(default_gait.double_support.impulses.closure_residual) < 1e-9


@pytest.fixture(scope="module")
def paper_lp_gait(planner):
    """The default gait with the paper's LP: no friction cone on the reaction impulses."""
    return planner.plan(dataclasses.replace(DEFAULT_REQUEST, friction=math.inf))


def test_impact_equations_hold_and_feet_are_at_rest(planner, paper_lp_gait):
    default_gait = paper_lp_gait
    problem = impact_problem(planner, default_gait)
    a, b = problem.equations()
    sol = solve_impulses(problem, "l1")
    assert np.max(np.abs(a @ sol.x - b)) < 1e-9
    assert np.linalg.matrix_rank(a, tol=1e-8) == 41  # the rank deficiency of docs/model.md section 4
    assert abs(problem.left_null_vector() @ b) < 1e-9
    j1, j2 = problem.j1, problem.j2
    assert np.abs(j1 @ sol.xd_minus).max() < 1e-9  # old stance tip still at rest before the impact
    assert np.abs(j2 @ sol.xd_plus).max() < 1e-9  # new stance tip at rest after the passive impact
    assert np.abs(j2 @ np.array(default_gait.double_support.xd_a)).max() < 1e-12  # and at the start of the next step
    assert j2[2] @ sol.xd_minus <= 1e-12 and j1[2] @ sol.xd_plus >= -1e-12  # sign constraints
    for reaction in (sol.ir1_minus, sol.ir2, sol.ir2_plus):
        assert reaction[2] >= -1e-12
    assert sol.W == pytest.approx(default_gait.W, rel=1e-12)


def test_lp_optimum_is_certified_two_ways(planner, paper_lp_gait):
    """The dual certificate from HiGHS, and the same LP solved by HiGHS's interior point."""
    default_gait = paper_lp_gait
    assert default_gait.double_support.impulses.duality_gap < 1e-9
    problem = impact_problem(planner, default_gait)
    a, b = problem.equations()
    keep = np.arange(42) != int(np.argmax(np.abs(problem.left_null_vector())))
    # The LP in the form W = sum(p + m), I = p - m, p, m >= 0: another formulation, another algorithm.
    n = 47
    lay = problem.layout
    idx = np.r_[np.arange(lay.i_minus.start, lay.i_minus.stop), np.arange(lay.i_plus.start, lay.i_plus.stop)]
    k = idx.size
    a_eq = np.hstack([a[keep], np.zeros((41, 2 * k))])
    a_eq[:, idx] = 0.0
    a_eq[:, n : n + k] = a[keep][:, idx]
    a_eq[:, n + k :] = -a[keep][:, idx]
    c = np.concatenate([np.zeros(n), np.ones(2 * k)])
    bounds = [(None, None)] * n + [(0, None)] * (2 * k)
    for i in idx:
        bounds[i] = (0, 0)
    for sl_end in (22, 37, 47):
        bounds[sl_end - 1] = (0, None)
    a_ub = np.zeros((2, n + 2 * k))
    a_ub[0, 0:12] = problem.j2[2]
    a_ub[1, 22:34] = -problem.j1[2]
    res = linprog(c, A_ub=a_ub, b_ub=np.zeros(2), A_eq=a_eq, b_eq=b[keep], bounds=bounds, method="highs-ipm")
    assert res.status == 0
    assert res.fun == pytest.approx(default_gait.W, rel=1e-7)


def test_lp_started_from_a_nearby_basis_finds_the_same_optimum(planner, default_gait):
    """The LP of a nearby double support (the gait of alpha 2 deg larger) started from the default
    gait's optimal basis: the same optimum as started cold (W and the impulses to rounding), and
    the basis it ends on is the cold start's."""
    near = planner.plan(dataclasses.replace(DEFAULT_REQUEST, arm_amplitude=DEFAULT_REQUEST.arm_amplitude + math.radians(2)))
    problem, options = impact_problem(planner, near), near.problem.impulse_options
    cold = solve_impulses(problem, "l1", options)
    warm = solve_impulses(problem, "l1", options, start=default_gait.double_support.impulses.basis)
    assert cold.success and warm.success and warm.duality_gap < 1e-9
    assert warm.W == pytest.approx(cold.W, rel=1e-12)
    assert np.max(np.abs(warm.x - cold.x)) <= 1e-12 * np.max(np.abs(cold.x))
    assert all(np.array_equal(a, b) for a, b in zip(warm.basis, cold.basis))
    other_shape = tuple(status[:-1] for status in default_gait.double_support.impulses.basis)
    assert solve_impulses(problem, "l1", options, start=other_shape).W == pytest.approx(cold.W, rel=1e-12)  # ignored


def test_an_lp_on_an_optimal_basis_is_certified_without_the_simplex(planner, default_gait):
    """Started from a basis, the LP is solved on it by one linear system when the basis is optimal
    there (its solution feasible and its multipliers of an optimum's signs, ``impulses._on_basis``):
    at the gait's own double support that is HiGHS's optimum to rounding (1e-12), certified to
    ``CERTIFIED``. A far gait's basis (alpha 5 deg, 40 deg, the other mode) is refused there, and
    HiGHS, started from it, finds the optimum of a cold start."""
    problem = impact_problem(planner, default_gait)
    basis = default_gait.double_support.impulses.basis
    options = default_gait.problem.impulse_options  # the friction cone's
    lp = impulses._l1_program(problem, problem.equations(), options)
    x, gap = impulses._on_basis(lp, basis)
    cold = solve_impulses(problem, "l1", options)
    assert gap <= impulses.CERTIFIED
    assert np.max(np.abs(x[: problem.layout.unknowns] - cold.x)) <= 1e-12 * np.max(np.abs(cold.x))
    for alpha, mode in ((5.0, "normal"), (40.0, "normal"), (23.5, "anti-normal")):
        far = impact_problem(planner, planner.plan(GaitRequest(0.45, 0.45, math.radians(alpha), mode)))
        assert impulses._on_basis(impulses._l1_program(far, far.equations(), options), basis) is None
        warm, cold = solve_impulses(far, "l1", options, start=basis), solve_impulses(far, "l1", options)
        assert warm.success and warm.W == pytest.approx(cold.W, rel=1e-12)


def test_a_gait_without_samples_keeps_its_figures_not_its_grids(default_gait):
    """What a study keeps of a gait: its figures, neither its nodes nor its step on the coarse grid."""
    assert default_gait.step.coarse is not None and default_gait.step.nodes is not None
    slim = default_gait.without_samples()
    assert slim.step.nodes is None and slim.step.coarse is None
    assert slim.W == default_gait.W and slim.accuracy == default_gait.accuracy


def test_ground_reaction_two_ways(planner, default_gait):
    samples = default_gait.figures.samples
    flow = planner.flow
    for i in range(0, len(samples.t), 9):
        q, qd = samples.q[i], samples.qd[i]
        qdd = flow.acceleration(q, qd)
        by_rnea = ground_reaction_inverse_dynamics(planner.model, q, qd, qdd)
        by_momentum = ground_reaction_momentum(planner.model, q, qd, qdd)
        assert np.allclose(by_rnea, by_momentum, rtol=1e-9, atol=1e-8)
        assert by_rnea[2] > 0


def _apply_impulses(problem, sol):
    """Forward path: apply I^-, the passive impact, I^+ as impacts and return Xd^a.

    Each sub-phase solves D_e dXd = B_e I + J^T I_R with the contact J Xd = 0 (or J dXd = 0):
    an independent computation of what the LP's equations claim.
    """
    d, j1, j2 = problem.mass_matrix, problem.j1, problem.j2
    b_e = np.vstack([np.zeros((5, 7)), np.eye(7)])

    def impact(xd, impulse, jac, target_rest):
        kkt = np.block([[d, -jac.T], [jac, np.zeros((3, 3))]])
        rhs = np.concatenate([d @ xd + b_e @ impulse, np.zeros(3) if target_rest else jac @ xd])
        return np.linalg.solve(kkt, rhs)[:12]

    xd_minus = impact(problem.xd_b, sol.i_minus, j1, target_rest=False)
    xd_plus = impact(xd_minus, np.zeros(7), j2, target_rest=True)
    return xd_minus, xd_plus, impact(xd_plus, sol.i_plus, j2, target_rest=True)


def test_gait_is_periodic_through_the_leg_exchange(planner, default_gait):
    problem = impact_problem(planner, default_gait)
    sol = solve_impulses(problem, "l1")
    xd_minus, xd_plus, xd_a = _apply_impulses(problem, sol)
    assert np.allclose(xd_minus, sol.xd_minus, atol=1e-9)
    assert np.allclose(xd_plus, sol.xd_plus, atol=1e-9)
    assert np.allclose(xd_a, default_gait.double_support.xd_a, atol=1e-9)
    # In the next step's coordinates the state is again (q(0), qd(0)): an exact periodic orbit.
    p = planner.hybrid.exchange.matrix
    assert np.allclose(p @ np.array(default_gait.step.q_target), default_gait.step.q0, atol=1e-14)
    assert np.allclose(p @ xd_a[3:], default_gait.qd_a, atol=1e-9)
    # Two steps walked with the flow return to the same state (step 2 starts from the map).
    run = planner.flow.propagate(p @ np.array(default_gait.step.q_target), p @ xd_a[3:], default_gait.period)
    assert np.allclose(run.q, default_gait.step.q_target, atol=1e-9)
    assert np.allclose(run.qd, default_gait.step.qd_b, atol=1e-8)


def test_angular_momentum_is_conserved_about_the_feet_line(planner, default_gait):
    bm = planner.model
    q_t = np.array(default_gait.step.q_target)
    axis = np.array(default_gait.double_support.new_stance_foot) / np.linalg.norm(default_gait.double_support.new_stance_foot)
    before = bm.momentum(q_t, np.array(default_gait.double_support.xd_b))[1] @ axis
    after = bm.momentum(q_t, np.array(default_gait.double_support.xd_a))[1] @ axis
    assert after == pytest.approx(before, abs=1e-9)
    # The yaw momentum at T+ about the new foot is that about the old one shifted by r x p.
    assert default_gait.double_support.h_t_plus[0] != pytest.approx(default_gait.double_support.h_t_plus[1], abs=1e-3)


def test_warm_start_reproduces_the_cold_solution_faster(planner, default_gait):
    warm = planner.plan(DEFAULT_REQUEST, guess=(np.array(default_gait.qd_a), default_gait.theta))
    assert warm.step.iterations == 0
    near = planner.plan(
        dataclasses.replace(DEFAULT_REQUEST, arm_amplitude=DEFAULT_REQUEST.arm_amplitude + math.radians(1)),
        guess=(np.array(default_gait.qd_a), default_gait.theta),
    )
    cold = planner.plan(dataclasses.replace(DEFAULT_REQUEST, arm_amplitude=DEFAULT_REQUEST.arm_amplitude + math.radians(1)),
                        cold=True)
    assert near.converged and near.step.iterations <= 4
    assert near.step.evaluations < cold.step.evaluations
    assert near.theta == pytest.approx(cold.theta, abs=1e-10)
    assert np.allclose(near.qd_a, cold.qd_a, atol=1e-9)
    assert near.W == pytest.approx(cold.W, rel=1e-9)


def test_slack_closure_keeps_theta_zero_and_reports_s(planner):
    g = planner.plan(dataclasses.replace(DEFAULT_REQUEST, closure="slack"))
    assert g.converged and g.admissible
    assert g.theta == 0.0
    assert 0 < abs(g.double_support.slack) < 0.01  # rad/s: a small correction along z_d
    assert abs(g.double_support.impulses.closure_residual) < 1e-9
    assert g.double_support.impulses.equation_residual < 1e-9


def test_quadratic_effort_by_osqp(planner, default_gait):
    g = planner.plan(dataclasses.replace(DEFAULT_REQUEST, effort="l2"))
    assert g.converged and g.admissible
    assert g.double_support.impulses.equation_residual < 1e-9
    assert g.W >= default_gait.W - 1e-9  # the L1 optimum is the least W of all solutions
    assert g.theta == pytest.approx(default_gait.theta, abs=1e-12)  # closure does not depend on effort


def test_anti_normal_mode_and_table_parameters_also_solve(planner, default_gait):
    anti = planner.plan(dataclasses.replace(DEFAULT_REQUEST, mode="anti-normal"))
    assert anti.converged and anti.admissible
    assert anti.step.q0[5] == pytest.approx(-DEFAULT_REQUEST.arm_amplitude)
    table = GaitPlanner("aoustin2013-table").plan(dataclasses.replace(DEFAULT_REQUEST, params="aoustin2013-table"))
    assert table.converged and table.params == "aoustin2013-table"
    assert table.W != pytest.approx(default_gait.W, rel=1e-3)  # the arm inertia matters
    with pytest.raises(ValueError, match="this planner holds parameter set"):
        planner.plan(dataclasses.replace(DEFAULT_REQUEST, params="aoustin2013-table"))


def test_a_solve_that_cannot_converge_says_so(planner):
    bvp = solve_bvp(planner.hybrid, planner.flow, StepProblem(0.45, 0.45, 0.4, GaitMode.NORMAL),
                    settings=dataclasses.replace(DEFAULTS, max_iterations=1))
    assert not bvp.converged and "no convergence in 1 Newton iterations" in bvp.message
    extreme = planner.plan(GaitRequest(step_length=1.7, period=0.05, arm_amplitude=1.5, mode="normal"))
    assert not extreme.admissible and extreme.reasons
    json.loads(views.to_json(extreme))  # still serializable


REQUIRED_KEYS = """step_length period arm_amplitude mode converged admissible theta W I_minus I_plus IR1_minus IR2
IR2_plus Xd_minus Xd_plus Xd_a Xd_b qd_a qd_b q0 qT min_grf_z min_swing_height max_friction_ratio H_Tminus H_Tplus
closure_residual solve_time_s""".split()


def test_json_has_the_documented_keys(default_gait):
    data = json.loads(views.to_json(default_gait))
    missing = [k for k in REQUIRED_KEYS if k not in data]
    assert not missing
    assert len(data["I_minus"]) == 7 and len(data["Xd_a"]) == 12 and len(data["H_Tplus"]) == 2
    assert data["mode"] == "normal" and data["arm_amplitude"] == pytest.approx(math.radians(23.5))


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(step_length=0.0), "step length must be in"),
        (dict(step_length=1.9), "step length must be in"),
        (dict(step_length=float("nan")), "step length must be a finite number"),
        (dict(period=0.0), "period must be positive"),
        (dict(period=float("inf")), "period must be a finite number"),
        (dict(arm_amplitude=math.radians(90)), r"arm amplitude must be in \[0, 90\) deg, got 90 deg"),
        (dict(arm_amplitude=-0.1), "arm amplitude must be in"),
        (dict(arm_amplitude=float("nan")), "arm amplitude must be a finite number"),
        (dict(mode="sideways"), "unknown gait mode 'sideways'"),
        (dict(closure="none"), "unknown closure"),
        (dict(effort="l3"), "unknown effort"),
    ],
)
def test_bad_requests_are_refused(planner, change, message):
    with pytest.raises(ValueError, match=message):
        planner.plan(dataclasses.replace(DEFAULT_REQUEST, **change))


def test_p_inverse_is_the_inverse(planner):
    exchange = planner.hybrid.exchange
    assert np.allclose(exchange.matrix @ exchange.inverse, np.eye(9), atol=1e-15)
