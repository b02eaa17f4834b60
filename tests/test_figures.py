"""Figures: the two-step momentum curve against the double-support figures, PNG files written."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from biped_gait.studies.figures import (effort_figure, momentum_figure, period_figure, save, sweep_figures,
                                        two_step_momentum)
from biped_gait.studies.sweep import solve_chain

from .conftest import DEFAULT_REQUEST

pytestmark = pytest.mark.studies

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def anti_gait(planner):
    return planner.plan(dataclasses.replace(DEFAULT_REQUEST, mode="anti-normal"))


def test_two_step_momentum_is_h_then_its_mirror(default_gait):
    t, h = two_step_momentum(default_gait)
    n = len(default_gait.figures.samples.t)
    period = default_gait.period
    assert len(t) == 2 * n and t[0] == 0.0 and t[-1] == pytest.approx(2 * period, abs=1e-15)
    assert t[n - 1] == t[n] == pytest.approx(period, abs=1e-15)  # the double support, drawn as a jump
    # Step 1 ends at H(T-) about the old stance foot, step 2 starts at H(T+) about the new one.
    assert h[n - 1] == pytest.approx(default_gait.double_support.h_t_minus[0], abs=1e-9)
    assert h[n] == pytest.approx(default_gait.double_support.h_t_plus[1], abs=1e-9)
    assert np.allclose(h[n:], -h[:n], atol=0)


def test_figures_are_written_as_png(tmp_path, planner, default_gait, anti_gait):
    path = save(momentum_figure(default_gait, anti_gait), tmp_path / "sub" / "fig5.png")
    assert path.read_bytes()[:8] == PNG_SIGNATURE and path.stat().st_size > 10_000
    chain = solve_chain(planner, 0.45, 0.45, "normal", np.radians([0.0, 20.0, 40.0]))
    fig = effort_figure(chain, title="test")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "arm amplitude alpha (deg)" and ax.get_ylabel() == "effort W (N m s)"
    assert np.allclose(ax.lines[0].get_xdata(), [0.0, 20.0, 40.0])
    assert np.allclose(ax.lines[0].get_ydata(), [r.W for r in chain])
    assert ax.lines[0].get_linestyle() == "-"


def test_sweep_figures_one_per_step_length_and_period(tmp_path, planner):
    results = [r for length in (0.40, 0.45) for r in solve_chain(planner, length, 0.45, "anti-normal", (0.0, 0.3))]
    paths = sweep_figures(results, tmp_path)
    assert [p.name for p in paths] == ["W_vs_alpha_L0.400_T0.450.png", "W_vs_alpha_L0.450_T0.450.png"]
    assert all(p.read_bytes()[:8] == PNG_SIGNATURE for p in paths)
    fig = effort_figure(results)
    assert [line.get_linestyle() for line in fig.axes[0].lines] == ["--", "--"]  # anti-normal dashed
    assert math.isclose(fig.axes[0].lines[1].get_ydata()[1], results[3].W)


def test_a_period_sweep_draws_w_against_t_with_the_marks_in_the_legend(tmp_path, planner):
    """One alpha, three periods: a W-vs-T figure (no one-point W-vs-alpha plots); a gait drawn
    as not admissible has its legend entry."""
    results = [planner.plan(dataclasses.replace(DEFAULT_REQUEST, period=period)) for period in (0.44, 0.45, 0.46)]
    results[1] = dataclasses.replace(results[1], verdict=dataclasses.replace(results[1].verdict, admissible=False,
                                                                              reasons=("made up",)))
    paths = sweep_figures(results, tmp_path)
    assert [p.name for p in paths] == ["W_vs_T_L0.450.png"]
    fig = period_figure(results)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "step period T (s)" and np.allclose(ax.lines[0].get_xdata(), [0.44, 0.45, 0.46])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "not admissible (its W)" in labels and "normal" in labels
