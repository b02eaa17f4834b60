"""The 9-DOF parameter sets give the stored reference figures on any machine: plans, a walk and a
sweep, each figure within the tolerance tests/reference_figures.py writes beside it and justifies
(never to the bit); the same for requests moved by a few ulps, which proves that no comparison
depends on bits; and the shipped atlases' nodes are gaits of this code on this machine."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests import reference_figures as ref

pytestmark = pytest.mark.core

ULPS = 3  # L and alpha moved by +3 ulps, T by -3: every figure moves by rounding, none by more


@pytest.fixture(scope="module", params=ref.SETS)
def stored_plans(request):
    return request.param, ref.stored_plans(request.param)


@pytest.mark.parametrize("ulps", [0, ULPS])
def test_plans_hold_their_figures(stored_plans, ulps):
    params, stored = stored_plans
    for k, (now, before) in enumerate(zip(ref.plan_figures(params, ulps), stored)):
        wrong = ref.mismatches(now, before)
        assert not wrong, f"plan {k} of {params} ({ref.REQUESTS[k][:4]}, {ulps} ulps): {wrong}"


def test_every_figure_has_a_tolerance():
    from biped_gait.core.gait.views import FIELDS

    missing = [f.key for f in FIELDS if f.key not in ref.TOLERANCES and f.key != "solve_time_s"]
    assert not missing, f"figures without a tolerance in tests/reference_figures.py: {missing}"


@pytest.mark.parametrize("ulps", [0, ULPS])
def test_the_walk_holds_its_figures(ulps):
    wrong = ref.walk_mismatches(ref.walk_arrays(ulps), ref.stored_walk())
    assert not wrong, f"the walk ({ulps} ulps): {wrong}"


@pytest.mark.parametrize("ulps", [0, ULPS])
def test_the_sweep_holds_its_figures(ulps):
    now, before = ref.sweep_rows(ref.sweep_csv(ulps)), ref.sweep_rows((ref.DATA / "sweep.csv").read_text())
    assert len(now) == len(before)
    for k, (row, stored) in enumerate(zip(now, before)):
        wrong = ref.mismatches(row, stored)
        assert not wrong, f"sweep row {k} ({ulps} ulps): {wrong}"


def test_the_tolerances_catch_a_real_change():
    """The comparison is not vacuous: a figure moved by what a change of the model moves it (a
    part in 1e6) fails, and so does a residual beyond its bound or a word changed."""
    stored = ref.stored_plans("aoustin2013")[0]
    assert not ref.mismatches(stored, stored)
    for key, value in (("W", stored["W"] * (1 + 1e-6)), ("qd_a", [v + 1e-6 for v in stored["qd_a"]]),
                       ("end_point_residual", 1e-9), ("found", "cold"),
                       ("multipliers", [[re * (1 + 1e-5), im] for re, im in stored["multipliers"]])):
        assert ref.mismatches({**stored, key: value}, stored), key


def _nodes(atlas, count: int) -> list[tuple[int, int, int]]:
    """``count`` admissible nodes of ``atlas`` that met the accuracy contract, spread over its grid
    (every n-th, in index order), and the first of those solved on its finest grid (refined to
    meet it)."""
    from biped_gait.core.gait.atlas import NodeStatus

    admissible = np.argwhere((atlas.nodes["status"] == NodeStatus.ADMISSIBLE) & (atlas.nodes["grid_steps"] > 0))
    spread = [tuple(int(i) for i in admissible[k]) for k in np.linspace(0, len(admissible) - 1, count).astype(int)]
    steps = atlas.nodes["grid_steps"][tuple(admissible.T)]
    return spread + [tuple(int(i) for i in admissible[int(np.argmax(steps))])]


@pytest.mark.parametrize("params", ["aoustin2013", "aoustin2013-table", "aoustin2013-hips"])
def test_the_shipped_atlases_nodes_are_gaits_of_this_machine(params):
    """Some nodes of each shipped straight atlas, solved again here from their own warm start:
    the same gait (W, theta, qd(0), the least vertical ground reaction and swing height, the
    spectral radius) within the plans' tolerances, on the grid the node records (the one the
    planner refines it to, to meet the accuracy contract). An atlas holds results computed elsewhere: it
    stays current on another machine because it is tied to the inputs and the code (its
    fingerprint), and it is right there because its nodes solve there."""
    from biped_gait.core.gait.configurations import GaitMode
    from biped_gait.core.gait.planner import GaitPlanner, GaitRequest

    planner = GaitPlanner(params)
    for mode in GaitMode:
        atlas = planner.atlas(mode)
        for index in _nodes(atlas, 4):
            L, T, alpha = atlas.grid.point(index)
            gait = planner.plan(GaitRequest(L, T, alpha, mode), (atlas.nodes["qd_a"][index].copy(),
                                                                 float(atlas.nodes["theta"][index])))
            assert gait.admissible, (params, mode, index, gait.reasons)
            # The grid is a decision, compared exactly: the estimate that makes it is known to about 1e-7 of
            # itself on another machine (a difference of end states ~1e-8 apart, moved by ~1e-15), and at
            # these nodes it clears the contract's bounds by 0.28 % at the least (0.525 m, 0.55 s, 15 deg,
            # aoustin2013-table: 1.0028e-9 rad on 32 steps, refined) and by 5 % or more at every other.
            assert gait.accuracy.steps == atlas.nodes["grid_steps"][index], (params, mode, index)
            for key, now in (("W", gait.W), ("theta", gait.theta), ("qd_a", gait.step.qd_a.tolist()),
                             ("min_grf_z", gait.figures.min_grf_z),
                             ("min_swing_height", gait.figures.min_swing_height)):
                stored = atlas.nodes[key][index]
                wrong = ref.TOLERANCES[key].mismatch(now, stored.tolist())
                assert not wrong, f"{params} {mode.value} node {index} {key}: {wrong}"
            wrong = ref.TOLERANCES["spectral_radius"].mismatch(gait.stability.spectral_radius,
                                                               float(atlas.nodes["spectral_radius"][index]))
            assert not wrong, f"{params} {mode.value} node {index} spectral radius: {wrong}"


@pytest.mark.parametrize("mode", ["normal", "anti-normal"])
def test_the_shipped_turning_atlases_nodes_are_strides_of_this_machine(hips, mode):
    """Two strides of each shipped turning atlas (its first turning node and a middle one), solved again here from
    their own warm start: the same W per stride and per step, trunk pitches and initial
    velocities, within the plans' tolerances."""
    from biped_gait.core.gait.atlas import NodeStatus
    from biped_gait.core.gait.configurations import GaitMode
    from biped_gait.core.gait.planner import GaitRequest

    atlas = hips.turning_atlas(GaitMode(mode))
    turning = np.argwhere((atlas.nodes["status"] == NodeStatus.ADMISSIBLE) & (atlas.grid.curvatures > 0))
    for index in (turning[0], turning[len(turning) // 2]):
        index = tuple(int(i) for i in index)
        L, T, alpha, kappa = (axis[i] for axis, i in zip(atlas.grid.axes, index))
        qd, theta = atlas.nodes["qd_a"][index], atlas.nodes["theta"][index]
        stride = hips.plan_stride(GaitRequest(L, T, alpha, GaitMode(mode), turn_radius=1.0 / kappa),
                                  (qd[0].copy(), float(theta[0]), qd[1].copy(), float(theta[1])), stability=False)
        assert stride.admissible, (mode, index, stride.reasons)
        for key, now, stored in (("W", stride.W, atlas.nodes["W"][index]),
                                 ("W", [step.W for step in stride.steps], atlas.nodes["step_W"][index]),
                                 ("theta", [step.theta for step in stride.steps], theta),
                                 ("qd_a", [step.step.qd_a.tolist() for step in stride.steps], qd)):
            wrong = ref.TOLERANCES[key].mismatch(now, stored.tolist())
            assert not wrong, f"{mode} turning node {index} {key}: {wrong}"


def test_the_moved_requests_are_other_numbers():
    """The ulp test moves the requests for real (a few ulps, not none, and not more)."""
    assert ref.moved(0.45, ULPS) != 0.45 and abs(ref.moved(0.45, ULPS) - 0.45) < 1e-15
    assert math.isclose(ref.moved(0.45, -ULPS), 0.45, rel_tol=1e-15) and ref.moved(0.45, -ULPS) < 0.45
