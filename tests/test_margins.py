"""Margins as requests: a gait that meets the limits but not the margins is refused as such (the
swing clearance, the friction margin on the step and the impulses, the joint-rate bound), no
margin computes today's gait (within the reference figures' tolerances), and the atlas answers margins by filtering its nodes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from biped_gait.core.dynamics.impulses import friction_ratios
from biped_gait.core.gait import views
from biped_gait.core.gait.admissibility import Limit
from biped_gait.core.gait.atlas import NodeStatus
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.gait.margins import PREFIX, Margins, MarginVerdict

from .conftest import DEFAULT_REQUEST
from .reference_figures import mismatches
from .test_cli import run

pytestmark = pytest.mark.core


def plan(planner, **fields):
    return planner.plan(dataclasses.replace(DEFAULT_REQUEST, **fields))


def test_no_margin_is_todays_gait(planner, default_gait):
    zero = plan(planner, min_clearance=0.0, friction_margin=0.0, rate_bound=math.inf)
    now, before = views.to_dict(zero), views.to_dict(default_gait)
    for figures in (now, before):
        figures.pop("solve_time_s")
    assert not mismatches(now, before)
    keys = list(now)
    assert keys[-4:] == ["trajectory", "min_clearance", "friction_margin", "within_limits"]  # new keys come last
    assert now["within_limits"] is True and now["min_clearance"] == 0.0 and now["friction_margin"] == 0.0


def test_a_clearance_margin_above_the_gaits_is_reported_as_the_margins_not_the_limits(planner, default_gait):
    height = default_gait.figures.min_swing_height
    assert 0.003 < height < 0.004  # the default gait sits on its limit (3.4 mm)
    missed = plan(planner, min_clearance=0.005)
    assert not missed.admissible and missed.within_limits
    assert isinstance(missed.verdict, MarginVerdict) and missed.verdict.margins == Limit.CLEARANCE
    assert missed.verdict.limits == Limit(0)
    [reason] = missed.reasons
    assert reason.startswith(PREFIX) and "swing clearance 3.38 mm" in reason and "more than 5 mm" in reason
    assert missed.W == default_gait.W  # the same gait: the margin judges it, it does not change it
    assert "within the margins" in missed.hint
    met = plan(planner, min_clearance=0.003)
    assert met.admissible and met.W == default_gait.W


def test_a_friction_margin_narrows_the_cone_of_the_impulses_and_judges_the_step(planner, default_gait):
    mu = planner.params.friction
    margin = 0.1
    gait = plan(planner, friction_margin=margin)
    assert gait.converged and gait.double_support.impulses.success
    ratios = friction_ratios(gait.double_support.impulses)
    assert np.max(ratios) <= mu - margin + 1e-9 < np.max(default_gait.double_support.impulse_friction_ratios)
    assert gait.W > default_gait.W  # less friction to lean on costs effort
    assert gait.admissible == (gait.figures.max_friction_ratio <= mu - margin)
    assert gait.problem.options.friction == mu  # the request's coefficient is echoed, not mu - margin
    step_ratio = default_gait.figures.max_friction_ratio
    over = plan(planner, friction_margin=mu - step_ratio + 0.01)  # leaves the step less than it needs
    assert not over.admissible and over.within_limits
    assert Limit.FRICTION in over.verdict.margins and any("friction ratio" in r for r in over.reasons)


def test_impulses_only_within_the_limits_are_the_margins_that_fail(planner):
    bounded = plan(planner, rate_bound=5.0)  # no impulses keep the joint rates below 5 rad/s
    assert not bounded.admissible and bounded.within_limits
    assert bounded.verdict.margins == Limit.NO_IMPULSES
    assert bounded.reasons[0].startswith(PREFIX + "no impulses within the margins")


def test_a_gait_that_misses_the_limits_is_reported_by_its_limits(planner):
    short = plan(planner, period=0.32, min_clearance=0.01)  # the swing knee bends backwards at this period
    assert not short.admissible and not short.within_limits
    assert short.verdict.limits and not any(r.startswith(PREFIX) for r in short.reasons)


def test_bad_margins_are_refused(planner):
    for fields, message in [({"min_clearance": -0.001}, "swing clearance margin must be 0 (none) or positive"),
                            ({"min_clearance": math.inf}, "swing clearance margin must be a finite number"),
                            ({"friction_margin": 0.5}, "friction margin must be in [0, 0.5)"),
                            ({"friction": 0.0}, "frictionless floor")]:
        with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")):
            plan(planner, **fields)


def test_the_atlas_answers_margins_by_filtering_its_nodes(planner):
    atlas = planner.atlas(GaitMode.NORMAL)
    admissible = atlas.nodes["status"] == NodeStatus.ADMISSIBLE
    counts = []
    for clearance in (0.0, 0.005, 0.01, 0.02):
        seen = atlas.within(Margins(clearance))
        kept = seen.nodes["status"] == NodeStatus.ADMISSIBLE
        assert np.all(kept <= admissible)  # filtered, never added
        assert np.all(seen.nodes["min_swing_height"][kept] > clearance)
        assert np.array_equal(seen.nodes["qd_a"], atlas.nodes["qd_a"], equal_nan=True)  # not rebuilt
        counts.append(int(kept.sum()))
    assert counts[0] == int(admissible.sum()) and counts == sorted(counts, reverse=True) and counts[-1] < counts[0]
    friction = atlas.within(Margins(friction=0.1))
    kept = friction.nodes["status"] == NodeStatus.ADMISSIBLE
    assert np.all(friction.nodes["max_friction_ratio"][kept] <= atlas.friction - 0.1)


def test_the_atlas_show_verb_counts_the_nodes_within_the_margins():
    proc = run("atlas", "show", "--mode", "normal", "--min-clearance", "0.005")
    assert proc.returncode == 0, proc.stderr
    assert "within the margins (swing clearance > 5 mm):" in proc.stdout and "admissible nodes" in proc.stdout
