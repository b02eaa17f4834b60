"""Figures: the two-step momentum curve against the double-support figures, PNG files written;
the maps, push and plan figures say what a reader needs (margins, units, blank cells, the stance
foot, the friction line)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from biped_gait.core.gait.configurations import GaitMode
from biped_gait.studies.figures import (effort_figure, momentum_figure, period_figure, plan_figure, save, sweep_figures,
                                        two_step_momentum)
from biped_gait.studies.maps import Optimum, WalkingMaps
from biped_gait.studies.push_study import STUDY_DIRECTIONS, PushLimit, limit_vs_alpha_figure, polar_figure
from biped_gait.studies.results_page import maps_figures
from biped_gait.core.gait.chains import solve_chain

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


def made_up_maps(margins: str) -> WalkingMaps:
    """Maps on a 4 x 4 grid (no solve): the lower half without an admissible gait, two optima,
    one of whose other-mode gait is not admissible."""
    region = np.zeros((4, 4), dtype=int)
    region[:, :2] = 1
    optima = [Optimum(0.40, 0.50, 0.4, 30.0, 33.0, True), Optimum(0.50, 0.50, 0.5, 35.0, math.nan, False)]
    return WalkingMaps("aoustin2013", GaitMode.NORMAL, margins, np.array([0.35, 0.40, 0.45, 0.50]),
                       np.array([0.35, 0.40, 0.45, 0.50]), region, [], optima, 2)


def test_margin_maps_say_their_margins_and_explain_their_blank_cells():
    """The maps of a run with margins are titled and named by them (the plain ones keep their
    names); the cells without an admissible gait are shaded and the legends say what shading,
    white and an empty tile mean."""
    plain, margins = maps_figures(made_up_maps("")), maps_figures(made_up_maps("swing clearance > 5 mm"))
    assert [name for _, name in plain.values()] == ["map-region-aoustin2013.png", "map-optimum-aoustin2013.png",
                                                    "map-ratio-aoustin2013.png"]
    assert [name for _, name in margins.values()] == [f"map-{kind}-aoustin2013-swing-clearance-5-mm.png"
                                                      for kind in ("region", "optimum", "ratio")]
    region, optimum, ratio = (fig for fig, _ in margins.values())
    assert region.axes[0].get_title().splitlines()[-1] == "margins: swing clearance > 5 mm"
    assert "margins: swing clearance > 5 mm" in optimum.texts[0].get_text()  # the suptitle
    assert "margins: swing clearance > 5 mm" in ratio.axes[0].get_title()
    legend = [t.get_text() for t in ratio.legends[0].get_texts()]
    assert any("no admissible normal gait within the margins" in t for t in legend)
    assert any("every other atlas node" in t for t in legend)
    assert any("anti-normal gait at alpha* is not admissible" in t for t in legend)


def test_push_figures_give_units_and_the_stance_foot():
    """The polar plot's radius is in N s and names the stance foot; the log axis of the push
    against alpha reads as numbers, not powers of ten."""
    limits = [PushLimit(name, angle, alpha, 0.5, 0.25, 0.5 + 3 * abs(math.sin(angle)) + alpha, math.inf, "", ())
              for alpha in (0.0, 0.4) for name, angle in STUDY_DIRECTIONS.items()]
    polar = polar_figure(limits, "test")
    ax = polar.axes[0]
    polar.canvas.draw()
    radial = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
    assert radial and all(t.endswith(" N s") for t in radial), radial  # the unit on its labels
    assert "right foot in stance" in ax.get_title()
    assert "stance" in [t.get_text() for t in ax.get_xticklabels()][6]
    assert all(line.get_linestyle() == "-" for line in ax.lines)  # 8 directions: a curve through them
    fig = limit_vs_alpha_figure(limits, "test")
    fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels() if t.get_text()]
    assert labels and all("10^" not in t and "times" not in t for t in labels), labels
    assert {"0.5", "1", "2"} <= set(labels)


def test_the_plan_pictures_friction_line_is_apart_from_the_curves(planner, default_gait):
    """The friction panel starts at 0 and goes up to twice mu: mu = 0.5 reads as a line the ratio
    stays under, not as where a curve saturates."""
    fig = plan_figure(default_gait, planner.model)
    reaction, ratio = fig.axes[2], fig.axes[4]
    assert reaction.get_ylim()[0] == 0.0 and ratio.get_ylim() == (0.0, 1.0)
    assert any(t.get_text().startswith("mu = 0.5") for t in ratio.texts)


def test_a_polar_plot_of_few_directions_draws_only_what_was_measured():
    """The tutorial's four directions: markers alone (a curve between them would claim limits at
    the diagonals, which were not pushed), the radial labels in a gap between the directions."""
    four = {name: STUDY_DIRECTIONS[name] for name in ("forward", "backward", "left", "right")}
    limits = [PushLimit(name, angle, 0.4, 0.5, 0.25, 1.0 + abs(math.sin(angle)), math.inf, "", ())
              for name, angle in four.items()]
    ax = polar_figure(limits, "test").axes[0]
    [line] = ax.lines
    assert line.get_linestyle() == "None" and line.get_marker() == "o" and len(line.get_xdata()) == 4
    at = math.radians(ax.get_rlabel_position())
    assert min(abs(math.remainder(at - angle, 2 * math.pi)) for angle in four.values()) == pytest.approx(math.pi / 4)


def test_the_plan_pictures_momentum_panel_spans_its_curve(planner, default_gait):
    """The yaw momentum panel's scale is the curve's (no zero line stretching it when the
    momentum keeps its sign)."""
    fig = plan_figure(default_gait, planner.model)
    momentum = fig.axes[3]
    h = np.asarray(default_gait.figures.h_vertical)
    low, high = momentum.get_ylim()
    span = float(h.max() - h.min())
    assert low >= h.min() - 0.2 * span and high <= h.max() + 0.2 * span, (low, high, h.min(), h.max())


def test_the_optimum_maps_scale_spans_the_interior_optima():
    """An optimum at an end of the alpha range (45 deg, no interior minimum) is outlined and does
    not stretch the colour scale of the others (10 to 31 deg): the bar spans them, an arrow for it."""
    optima = [Optimum(0.40, 0.50, math.radians(10.6), 20.0, 1.1, True),
              Optimum(0.45, 0.50, math.radians(31.4), 30.0, 1.2, True),
              Optimum(0.50, 0.50, math.radians(45.0), 40.0, 1.3, False)]
    maps = dataclasses.replace(made_up_maps(""), optima=optima)
    [fig] = [fig for fig, name in maps_figures(maps).values() if name.startswith("map-optimum")]
    [alphas] = [c for c in fig.axes[0].collections if c.get_array() is not None and len(c.get_array()) == 3]
    assert alphas.norm.vmin == pytest.approx(10.6) and alphas.norm.vmax == pytest.approx(31.4)
    # where the ends are most tiles (a set whose least W is mostly at alpha = 0), the scale spans all
    mostly_ends = [dataclasses.replace(o, interior=k == 0) for k, o in enumerate(optima)]
    [fig] = [fig for fig, name in maps_figures(dataclasses.replace(maps, optima=mostly_ends)).values()
             if name.startswith("map-optimum")]
    [alphas] = [c for c in fig.axes[0].collections if c.get_array() is not None and len(c.get_array()) == 3]
    assert alphas.norm.vmin == pytest.approx(10.6) and alphas.norm.vmax == pytest.approx(45.0)
