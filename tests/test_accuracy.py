"""The accuracy contract (docs/model.md section 4.11), checked: on a grid of requests, every figure
a plan reports lies within 1e-8 of its converged value (relative to its size) and the exact flow
from its start ends within 1e-9 rad of q_T; the converged values come from plans on a grid of 256
RK8 steps, shown converged by halving its step. Each plan's own estimate of its integration error
bounds the true error; a plan on a grid too coarse for the contract refines it until it meets it."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from biped_gait.core.dynamics.impulses import ZERO_REACTION
from biped_gait.core.dynamics.settings import DEFAULTS
from biped_gait.core.gait.atlas import NodeStatus
from biped_gait.core.gait.bvp import StepProblem, solve_bvp
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.gait import planner as planner_module
from biped_gait.core.gait.accuracy import END_POINT_BOUND, FIGURE_BOUND, FIGURES, SAMPLED, relative_error
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.gait.views import FIELD_BY_KEY

pytestmark = pytest.mark.core

REFERENCE_STEPS = 256  # RK8 steps per T of the converged values
# (parameter set, L m, T s, alpha deg, mode, extra request fields): both modes, both closures, both
# efforts, a long slow step and a short quick one, the 13-DOF set with its legs leaning, and a slow
# gait the planner refines.
REQUESTS = (
    ("aoustin2013", 0.45, 0.45, 23.5, "normal", {}),
    ("aoustin2013", 0.40, 0.45, 21.1, "anti-normal", {}),
    ("aoustin2013", 0.55, 0.48, 15.0, "normal", {}),
    ("aoustin2013", 0.50, 0.50, 30.0, "normal", {"closure": "slack"}),
    ("aoustin2013", 0.35, 0.40, 10.0, "normal", {"effort": "l2"}),
    ("aoustin2013-hips", 0.45, 0.45, 20.0, "normal", {}),
    ("aoustin2013", 0.40, 0.625, 20.0, "normal", {}),  # slow: 32 steps miss the end point's bound
)
SLOW = 6  # the index of the slow request
CONVERGED = 1e-11  # the reference's own change from halving its step, far below the contract
ROUNDING = 1e-12  # what rounding leaves of a figure (relative) or of an end point (rad): below it errors are noise
# A stride's spectral radius: of the product of its two steps' Jacobians, known to about 2e-8 of itself on any
# grid (its strides on 128 and 256 steps differ by 2.3e-8).
STRIDE_RADIUS = 5 * FIGURE_BOUND


def _grid(steps: int) -> object:
    return replace(DEFAULTS, fine_steps=steps, coarse_steps=steps // 2)


@pytest.fixture(scope="module")
def planners(planner, hips):
    """The default planners and, per parameter set, reference planners on 256 and 128 steps."""
    made = {"aoustin2013": planner, "aoustin2013-hips": hips}
    return {params: (plan, {steps: GaitPlanner(params, _grid(steps), atlas=False) for steps in
                            (REFERENCE_STEPS, REFERENCE_STEPS // 2)}) for params, plan in made.items()}


@pytest.fixture(scope="module")
def solved(planners):
    """Per request: the plan, its converged value (256 steps) and the converged value's own
    check (128 steps), the two solved from the plan's solution (the same branch)."""
    out = []
    for params, length, period, alpha, mode, extra in REQUESTS:
        planner, references = planners[params]
        request = GaitRequest(length, period, math.radians(alpha), mode, **extra)
        plan = planner.plan(request)
        assert plan.converged, (params, request, plan.message)
        reference, halved = (references[steps].plan(request, plan.warm_start()) for steps in sorted(references, reverse=True))
        out.append((request, plan, reference, halved, references[REFERENCE_STEPS].flow))
    return out


def _true_errors(plan, reference) -> dict[str, float]:
    """Each figure's distance from its reference value, relative to its size."""
    return {key: relative_error(FIELD_BY_KEY[key].read(plan), FIELD_BY_KEY[key].read(reference)) for key in FIGURES}


def _end_point(plan, flow) -> float:
    """How far the flow on ``flow``'s grid from the plan's start ends from the plan's q_T (rad)."""
    return float(np.max(np.abs(flow.propagate(plan.step.q0, plan.step.qd_a, plan.period).q - plan.step.q_target)))


def _samples(plan, reference) -> float:
    drawn, converged = FIELD_BY_KEY["trajectory"].read(plan), FIELD_BY_KEY["trajectory"].read(reference)
    return max(relative_error(drawn[key], converged[key]) for key in SAMPLED)


def _multipliers(plan, reference) -> float:
    """The largest distance of a multiplier of ``plan`` from the nearest of ``reference``'s and
    the reverse, relative to the reference's spectral radius."""
    a, b = plan.stability.values, reference.stability.values
    distances = np.abs(a[:, None] - b[None, :])
    return float(max(distances.min(axis=0).max(), distances.min(axis=1).max()) / reference.stability.spectral_radius)


def test_the_reference_is_converged(solved):
    """Halving the reference's step moves none of its figures by more than 1e-11 and its end point
    by at most 1e-11 rad (1.4e-12 at T = 0.625 s, below 1e-12 at the others), and the reference
    ends within 1e-12 rad of q_T: it is the converged value, to far better than the contract."""
    for request, _, reference, halved, fine in solved:
        assert reference.converged and halved.converged, request
        worst = max(_true_errors(halved, reference).items(), key=lambda item: item[1])
        assert worst[1] <= CONVERGED, (request, worst)
        assert _end_point(reference, fine) <= ROUNDING and _end_point(halved, fine) <= CONVERGED, request


def test_every_figure_of_a_plan_meets_the_contract(solved):
    """Every figure within 1e-8 of its converged value, every multiplier too (of the spectral
    radius: the reset's Jacobian is exact, ``ImpactMap.reset_jacobian``), the exact end point within 1e-9 rad of q_T; and the plan says so
    itself."""
    for request, plan, reference, _, fine in solved:
        errors = _true_errors(plan, reference)
        worst = max(errors, key=errors.get)
        assert errors[worst] <= FIGURE_BOUND, (request, worst, errors[worst])
        assert _end_point(plan, fine) <= END_POINT_BOUND, request
        assert _multipliers(plan, reference) <= FIGURE_BOUND, (request, _multipliers(plan, reference))
        assert relative_error(plan.stability.spectral_radius, reference.stability.spectral_radius) <= FIGURE_BOUND
        slow = request is solved[SLOW][0]  # on its atlas node's grid: 64 steps
        assert plan.accuracy.within_contract, (request, plan.accuracy)
        assert plan.accuracy.steps > DEFAULTS.fine_steps if slow else plan.accuracy.steps == DEFAULTS.fine_steps


def test_the_estimate_bounds_the_true_error(solved):
    """Each plan's estimate of its error is at least the true error (beyond rounding) and not a
    gross overestimate: within a factor 100 where the true error is above rounding."""
    for request, plan, reference, _, fine in solved:
        estimate = plan.accuracy
        true = {"end_point": _end_point(plan, fine), "W": relative_error(plan.W, reference.W),
                "figures": max(_true_errors(plan, reference).values()), "samples": _samples(plan, reference)}
        for name, error in true.items():
            estimated = getattr(estimate, name)
            assert error <= estimated + ROUNDING, (request, name, error, estimated)
            assert estimated <= 100 * max(error, ROUNDING), (request, name, error, estimated)


def test_a_coarse_grid_is_refined_until_it_meets_the_contract(planner, solved):
    """A planner on 4 steps per T (its estimate 1e-5 of the samples, 1e-6 rad of the end point)
    doubles its grid until its estimate meets the contract; the plan then does."""
    coarse = GaitPlanner(settings=_grid(4), atlas=False)
    request, plan, reference, _, fine = solved[0]
    refined = coarse.plan(request, plan.warm_start())
    assert refined.converged and refined.accuracy.within_contract, refined.accuracy
    assert refined.accuracy.steps > 4 and refined.step.nodes[0].size == refined.accuracy.steps + 1
    assert max(_true_errors(refined, reference).values()) <= FIGURE_BOUND
    assert _end_point(refined, fine) <= END_POINT_BOUND


def test_without_refinement_the_coarse_plan_says_it_misses_the_contract(solved, monkeypatch):
    """On 8 steps per T and not refined, the plan misses the contract (its end point is 8e-8 rad
    off) and says so: its estimate is beyond the bounds, and at least the true error."""
    monkeypatch.setattr(planner_module, "REFINEMENTS", 0)
    request, plan, reference, _, fine = solved[0]
    coarse = GaitPlanner(settings=_grid(8), atlas=False).plan(request, plan.warm_start())
    true_end = _end_point(coarse, fine)
    assert true_end > END_POINT_BOUND and coarse.accuracy.end_point >= true_end
    assert not coarse.accuracy.within_contract and coarse.accuracy.steps == 8


def test_the_shootings_coarse_solution_is_the_estimate_grids_own(planner, solved):
    """The estimate compares a plan with its step on the coarse grid as the shooting leaves it
    (``BvpSolution.coarse``): converged there to the BVP's tolerance, it is the coarse grid's own
    solution, the one solving the step again there from the plan's solution gives (to 1e-12)."""
    request, plan, *_ = solved[0]
    coarse = plan.step.coarse
    assert coarse is not None and coarse.converged and coarse.nodes[0].size == DEFAULTS.coarse_steps + 1
    assert coarse.end_residual <= DEFAULTS.tolerance and abs(coarse.closure_gap) <= DEFAULTS.tolerance
    problem = StepProblem(request.step_length, request.period, request.arm_amplitude, request.mode)
    again = solve_bvp(planner.hybrid, planner.coarse_flow, problem, plan.warm_start(), DEFAULTS)
    assert again.converged and np.max(np.abs(again.qd_a - coarse.qd_a)) <= 1e-12 * np.max(np.abs(coarse.qd_a))
    assert abs(again.theta - coarse.theta) <= 1e-12
    assert plan.accuracy.figures <= FIGURE_BOUND


def test_a_plan_from_the_atlas_starts_on_its_nodes_grid(planner):
    """Near atlas nodes solved on 64 steps (slow gaits: 32 miss the end point's 1e-9 rad), a plan
    starts on 64 steps and solves once: its estimate against the shooting's own 32-step solution."""
    atlas = planner.atlas(GaitMode.NORMAL)
    index = next(i for i in zip(*np.nonzero(atlas.nodes["grid_steps"] == 2 * DEFAULTS.fine_steps))
                 if atlas.status(i) == NodeStatus.ADMISSIBLE)
    point = atlas.grid.point(index)
    assert atlas.grid_steps(point) >= 2 * DEFAULTS.fine_steps
    calls = []
    solve_on = planner._solve_on
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(planner, "_solve_on", lambda grid, *args: calls.append(grid.steps) or solve_on(grid, *args))
        gait = planner.plan(GaitRequest(*point, GaitMode.NORMAL))
    assert gait.found == "atlas" and gait.meets_contract and calls == [gait.accuracy.steps] == [atlas.grid_steps(point)]
    assert gait.step.coarse.nodes[0].size == gait.accuracy.steps // 2 + 1


def test_a_reaction_at_rounding_level_has_no_friction_ratio_to_refine(planner):
    """A swing foot that lands at rest (L = 0.25 m, T = 0.3 s, alpha = 30 deg, anti-normal) leaves
    the passive impact I_R2 at rounding level (1e-10 N s): its friction ratio is 0, not the ratio of
    two rounding errors (which read 0.49 here and moved by 1e-4 from one grid to the next, so the
    plan refined its grid to 512 steps in vain); the plan meets the contract on 32."""
    gait = planner.plan(GaitRequest(0.25, 0.3, math.radians(30.0), "anti-normal"))
    impulses = gait.double_support.impulses
    assert np.linalg.norm(impulses.ir2) <= ZERO_REACTION and gait.double_support.impulse_friction_ratios[1] == 0.0
    assert gait.meets_contract and gait.accuracy.steps == DEFAULTS.fine_steps, gait.accuracy


def test_a_stride_meets_the_contract_step_by_step(planners):
    """A stride on a circle of 2 m (``aoustin2013-hips``): each step's figures and end point within
    the contract of the stride's on 256 steps, each estimate bounding its step's true error; the
    stride's spectral radius within ``STRIDE_RADIUS``."""
    planner, references = planners["aoustin2013-hips"]
    request = GaitRequest(0.45, 0.45, math.radians(20.0), "normal", turn_radius=2.0)
    stride = planner.plan_stride(request)
    reference = references[REFERENCE_STEPS].plan_stride(request, stride.warm_start())
    assert stride.converged and reference.converged and stride.meets_contract
    fine = references[REFERENCE_STEPS].flow
    for step, converged in zip(stride.steps, reference.steps):
        errors = _true_errors(step, converged)
        assert max(errors.values()) <= min(FIGURE_BOUND, step.accuracy.figures + ROUNDING), errors
        assert _end_point(step, fine) <= min(END_POINT_BOUND, step.accuracy.end_point + ROUNDING)
    assert relative_error(stride.stability.spectral_radius, reference.stability.spectral_radius) <= STRIDE_RADIUS


def test_relative_error_reads_figures_as_the_contract_does():
    assert relative_error(100.0, 100.0 * (1 + 1e-9)) == pytest.approx(1e-9, rel=1e-6)
    assert relative_error(1e-3, 0.0) == 1e-3  # at least one unit: a vanishing figure at the gait's scale
    assert relative_error([1.0, 200.0], [1.5, 200.0]) == pytest.approx(0.5 / 200)  # an array as a whole
    assert relative_error(math.nan, math.nan) == 0.0 and relative_error(math.inf, math.inf) == 0.0
    assert relative_error(1.0, math.nan) == math.inf and relative_error([1.0], [1.0, 2.0]) == math.inf
