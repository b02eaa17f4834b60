"""Sweeps: grids and their checks, continuation chains, local worker processes, the CSV and
JSON files (failed gaits kept and marked)."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from biped_gait.studies.executors import open_executor
from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.model.params import load_params
from biped_gait.core.gait.chains import inclusive_range, solve_chain, solve_near
from biped_gait.studies.sweep import MAX_CASES, SweepGrid, solve_grid
from biped_gait.studies.sweep_output import SweepFiles, csv_columns

from .conftest import DEFAULT_REQUEST

pytestmark = pytest.mark.studies

PARAMS = load_params()


def test_inclusive_range_includes_the_stop_despite_rounding():
    assert inclusive_range(0.40, 0.50, 0.05, "L") == (0.40, 0.45, 0.50)
    assert len(inclusive_range(0.0, 45.0, 1.5, "alpha")) == 31
    assert inclusive_range(0.0, 1.0, 0.3, "x") == (0.0, 0.3, 0.6, 0.9)  # stop not on the grid: not passed
    assert inclusive_range(2.0, 2.0, 1.0, "x") == (2.0,)


@pytest.mark.parametrize(
    "bounds, message",
    [
        ((0.0, 45.0, 0.0), "step must be positive, got 0"),
        ((0.0, 45.0, -1.0), "step must be positive"),
        ((45.0, 0.0, 1.0), "range is inverted: stop 0 is below start 45"),
        ((0.0, 45.0, 1e-6), "values (more than 100000)"),
        ((0.0, float("nan"), 1.0), "must be finite numbers"),
    ],
)
def test_bad_ranges_are_refused(bounds, message):
    with pytest.raises(ValueError) as err:
        inclusive_range(*bounds, "arm amplitude")
    assert message in str(err.value) and str(err.value).startswith("arm amplitude range")


def test_grid_is_normalized():
    grid = SweepGrid.build(PARAMS, [0.45, 0.40, 0.45], [0.45], [0.3, 0.1, 0.2, 0.1], ["anti_normal", "normal"])
    assert grid.step_lengths == (0.45, 0.40)  # duplicates removed, order kept
    assert grid.alphas == (0.1, 0.2, 0.3)  # ascending for continuation
    assert grid.modes == ("anti-normal", "normal")
    assert grid.size == 2 * 1 * 3 * 2 and len(grid.chains()) == 4
    assert grid.describe()["arm_amplitude_deg"] == pytest.approx(np.degrees([0.1, 0.2, 0.3]).tolist())


@pytest.mark.parametrize(
    "axes, message",
    [
        (dict(alphas=[]), "no arm amplitude given"),
        (dict(modes=["normal", "hop"]), "unknown gait mode 'hop'"),
        (dict(step_lengths=[0.45, 2.0]), "step length must be in (0, 1.814) m"),
        (dict(periods=[0.0]), "period must be positive"),
        (dict(alphas=[0.1, math.radians(95)]), "arm amplitude must be in [0, 90) deg"),
        (dict(alphas=np.linspace(0, 1, MAX_CASES)), f"the sweep has {2 * MAX_CASES} cases (more than {MAX_CASES})"),
    ],
)
def test_bad_grids_are_refused(axes, message):
    values = dict(step_lengths=[0.45], periods=[0.45], alphas=[0.1], modes=["normal", "anti-normal"]) | axes
    with pytest.raises(ValueError) as err:
        SweepGrid.build(PARAMS, **values)
    assert message in str(err.value)


def test_a_large_grid_passes_when_confirmed():
    alphas = np.linspace(0, 1, MAX_CASES)
    grid = SweepGrid.build(PARAMS, [0.45], [0.45], alphas, ["normal", "anti-normal"], confirmed=True)
    assert grid.size == 2 * MAX_CASES


def test_chain_by_continuation_equals_cold_solves(planner):
    alphas = np.radians([20.0, 21.0, 22.0])
    chain = solve_chain(planner, 0.45, 0.45, "normal", alphas)
    for alpha, warm in zip(alphas, chain):
        cold = planner.plan(GaitRequest(0.45, 0.45, float(alpha), "normal"), cold=True)
        assert warm.converged and warm.admissible
        assert warm.W == pytest.approx(cold.W, rel=1e-9)
        assert warm.theta == pytest.approx(cold.theta, abs=1e-10)
    assert [g.found for g in chain] == ["atlas", "guess", "guess"]  # then warm-started from its neighbour
    cold = planner.plan(GaitRequest(0.45, 0.45, float(alphas[1]), "normal"), cold=True)
    assert chain[1].step.evaluations < cold.step.evaluations


def test_a_failed_warm_start_is_solved_again_by_the_planner(planner, default_gait):
    garbage = (np.full(9, 50.0), 0.3)
    assert not planner.plan(DEFAULT_REQUEST, guess=garbage).converged
    result = solve_near(planner, DEFAULT_REQUEST, garbage)
    assert result.converged and result.W == pytest.approx(default_gait.W, rel=1e-9)


def test_a_chain_starts_on_the_human_like_gait_where_the_cold_start_does_not(planner):
    """At L = 0.45, T = 0.50 the straight-line start lands on a gait whose swing knee bends
    backwards; the chain's first gait, found by the planner, is the admissible human-like one."""
    cold = planner.plan(GaitRequest(0.45, 0.50, 0.0, "normal"), cold=True)
    assert cold.converged and not cold.admissible and "swing knee bends backwards" in cold.reasons[0]
    first = solve_chain(planner, 0.45, 0.50, "normal", (0.0,))[0]
    assert first.admissible and first.figures.q9_min >= -1e-9 and first.found in ("atlas", "continuation")


def test_local_processes_keep_failed_gaits_and_write_both_files(tmp_path):
    # T = 1.5 s diverges: those gaits are kept, marked, with their reasons.
    grid = SweepGrid.build(PARAMS, [0.45], [0.45, 1.5], np.radians([0.0, 20.0]), ["normal", "anti-normal"])
    with open_executor(workers=2) as executor, SweepFiles(tmp_path, grid) as files:
        for index, results in solve_grid(grid, executor):
            files.add(index, results)
    rows = list(csv.DictReader(files.csv_path.open()))
    assert len(rows) == grid.size == 8
    assert list(rows[0]) == csv_columns() and "trajectory" not in rows[0]
    failed = [r for r in rows if r["period"] == "1.5"]
    assert len(failed) == 4 and all(r["converged"] == "False" and r["W"] == "" for r in failed)
    assert all("ballistic BVP" in json.loads(r["reasons"])[0] for r in failed)
    ok = [r for r in rows if r["period"] == "0.45"]
    assert all(r["admissible"] == "True" and float(r["W"]) > 0 for r in ok)
    assert [(r["mode"], float(r["arm_amplitude_deg"])) for r in ok] == [
        ("normal", 0.0), ("normal", 20.0), ("anti-normal", 0.0), ("anti-normal", 20.0)]  # grid order
    assert len(json.loads(ok[0]["H_Tplus"])) == 2  # lists as JSON text
    document = json.loads(files.json_path.read_text())
    assert document["complete"] and document["cases_written"] == document["cases_planned"] == 8
    assert [c["W"] for c in document["cases"]] == [None if r["W"] == "" else float(r["W"]) for r in rows]
    assert document["grid"]["period_s"] == [0.45, 1.5]
