"""The gait atlas and the planner that starts from it: coverage (every request where
continuation from the human-like seed finds an admissible gait is answered admissible, with the
same W; the others are refused with the limiting reason and a hint), the shipped atlases are
current, an atlas round-trips through its file, and a stale or corrupt file is refused."""

from __future__ import annotations

import dataclasses
import math
import re
import zipfile
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from biped_gait.core.gait.atlas import Atlas, AtlasError, Grid, NodeStatus, atlas_path, period_runs
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.gait.bvp import StepProblem
from biped_gait.core.gait.continuation import continue_to
from biped_gait.core.gait.fingerprint import code_fingerprint, model_fingerprint
from biped_gait.core.gait.turning_atlas import TurningAtlas, turning_atlas_path
from biped_gait.core.model.params import load_params, shipped_param_names
from biped_gait.core.gait.planner import SEED, GaitPlanner, GaitRequest
from biped_gait.studies.atlas_build import build_atlas

from .test_cli import run

pytestmark = pytest.mark.core

# Off-grid requests of the tests' own choosing: (L m, T s, alpha deg).
COVERAGE = [(L, T, a) for L in (0.33, 0.47, 0.58) for T in (0.37, 0.415, 0.52, 0.61) for a in (7.0, 33.0)]


def by_continuation(planner: GaitPlanner, mode: GaitMode, L: float, T: float, alpha: float):
    """The reference: the gait at (L, T, alpha) continued from the human-like seed, no atlas."""
    seed = planner.plan(GaitRequest(*SEED, mode), cold=True)
    guess = continue_to(planner.hybrid, planner.coarse_flow, planner.settings, SEED, seed.warm_start(),
                        StepProblem(L, T, alpha, mode))
    return None if guess is None else planner.plan(GaitRequest(L, T, alpha, mode), guess)


@pytest.mark.parametrize("mode", list(GaitMode))
def test_every_gait_continuation_finds_is_answered(planner, mode):
    answered = feasible = 0
    for L, T, alpha_deg in COVERAGE:
        alpha = math.radians(alpha_deg)
        reference = by_continuation(planner, mode, L, T, alpha)
        gait = planner.plan(GaitRequest(L, T, alpha, mode))
        if reference is not None and reference.admissible:
            feasible += 1
            assert gait.admissible, (L, T, alpha_deg, gait.reasons)
            assert gait.W == pytest.approx(reference.W, rel=1e-6), (L, T, alpha_deg)
            assert gait.found == "atlas", (L, T, alpha_deg, gait.found)
            answered += 1
        else:
            assert not gait.admissible and gait.reasons, (L, T, alpha_deg)
            assert gait.hint.startswith("nearest admissible"), gait.hint
            if reference is not None:  # the same human-like gait, limited by the same conditions
                assert gait.verdict.limits == reference.verdict.limits, (L, T, alpha_deg)
    print(f"\n{mode.value}: answered {answered} of {feasible} feasible requests ({len(COVERAGE)} asked)")
    assert feasible >= len(COVERAGE) // 2


def test_the_users_examples_are_admissible_human_like_gaits():
    for args in (["--period", "0.55"], ["--step-length", "0.42", "--period", "0.5", "--alpha-deg", "23.6"]):
        proc = run("plan", *args)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert "admissible True" in proc.stdout and "found by atlas" in proc.stdout
    proc = run("optimize-arms", "--step-length", "0.42", "--period", "0.50")
    assert proc.returncode == 0 and "an interior minimum of W" in proc.stdout, proc.stdout + proc.stderr


def _runs(hint: str) -> list[tuple[float, float]]:
    """The period intervals (s) of a hint "... T in [a, b] or [c, d] s at ..."."""
    return [(float(a), float(b)) for a, b in re.findall(r"\[([0-9.]+), ([0-9.]+)\]", hint.split(" s at ")[0])]


def test_a_refusal_says_why_and_where_admissible_gaits_are(planner):
    gait = planner.plan(GaitRequest(0.45, 0.35, math.radians(23.5)))
    assert not gait.admissible and "swing knee bends backwards" in gait.reasons[0]
    assert gait.hint.startswith("nearest admissible (atlas grid): T in [")
    assert gait.found in ("atlas", "continuation")
    assert _runs(gait.hint) and not any(a <= 0.35 <= b for a, b in _runs(gait.hint))


def test_period_runs_never_hold_the_refused_period():
    periods = np.round(np.arange(0.30, 0.651, 0.025), 3)
    assert period_runs(periods, periods >= 0.3, 0.45) == "T in [0.300, 0.425] or [0.475, 0.650] s"
    assert period_runs(periods, periods >= 0.3, 0.46) == "T in [0.300, 0.450] or [0.475, 0.650] s"
    assert period_runs(periods, periods > 0.5, 0.35) == "T in [0.525, 0.650] s"
    assert period_runs(periods, periods < 0, 0.35) == ""


def test_a_refusal_beyond_the_atlas_hints_at_its_own_fields(hips):
    """The README's step width 0.3 m at T = 0.45 s is refused; the atlas (built at the hips'
    spacing) cannot say where gaits are at that width: the hint's periods are solved at it, the
    request's L and alpha, and do not hold the refused T; its ends plan admissible as asked."""
    request = GaitRequest(0.45, 0.45, math.radians(20.0), step_width=0.3)
    gait = hips.plan(request)
    assert not gait.admissible
    assert "step width 0.300 m" in gait.hint and "L = 0.450 m, alpha = 20 deg" in gait.hint, gait.hint
    runs = _runs(gait.hint)
    assert runs and not any(a <= 0.45 <= b for a, b in runs), gait.hint
    for a, b in runs:
        for period in (a, b):
            assert hips.plan(dataclasses.replace(request, period=period)).admissible, (period, gait.hint)


@pytest.mark.parametrize("name", shipped_param_names())
def test_the_shipped_atlases_are_current(name):
    """By their model fingerprint, which is the same on every Python version (not only by the
    bytes of the code: its comments may change), the turning atlases too."""
    params = load_params(name)
    for mode in GaitMode:
        atlas = Atlas.load(atlas_path(params, mode), params, name)
        assert atlas.fingerprint == model_fingerprint(params)
        if params.joints.lateral_hips:
            TurningAtlas.load(turning_atlas_path(params, mode), params, name)
        counts = atlas.counts()
        assert counts["admissible"] > 0.35 * sum(counts.values()), counts  # T >= ~0.42 s at every L, mostly
        seed = tuple(int(np.argmin(np.abs(axis - x))) for axis, x in zip(atlas.grid.axes, (0.45, 0.45, math.radians(25.0))))
        assert atlas.status(seed) == NodeStatus.ADMISSIBLE
        assert atlas.grid.step_lengths[0] <= 0.25 and atlas.grid.step_lengths[-1] >= 0.65
        assert atlas.grid.periods[0] <= 0.30 and atlas.grid.periods[-1] >= 0.65
        assert atlas.grid.alphas[0] == 0.0 and math.degrees(atlas.grid.alphas[-1]) >= 45.0 - 1e-9


def test_atlas_check_finds_every_shipped_atlas_current():
    proc = run("atlas", "check")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("every shipped atlas is current ("), proc.stdout


@pytest.fixture(scope="module")
def small_atlas() -> Atlas:
    """An atlas on a small grid around the seed, built by the real builder (threads)."""
    grid = Grid(np.array([0.40, 0.45, 0.50]), np.array([0.375, 0.45, 0.525]), np.radians([20.0, 25.0]))
    with ThreadPoolExecutor(2) as executor:
        return build_atlas(load_params(), GaitMode.NORMAL, executor, grid)


def test_an_atlas_round_trips_through_its_file(small_atlas, tmp_path):
    assert small_atlas.status((1, 1, 0)) == NodeStatus.ADMISSIBLE
    assert small_atlas.status((1, 0, 0)) == NodeStatus.INADMISSIBLE  # T = 0.375: the knee limits it
    path = small_atlas.save(tmp_path / "a.npz")
    back = Atlas.load(path, load_params(), "aoustin2013")
    assert (back.params, back.mode, back.fingerprint, back.friction) == (
        small_atlas.params, small_atlas.mode, small_atlas.fingerprint, small_atlas.friction)
    for name, array in small_atlas.nodes.items():
        assert np.array_equal(array, back.nodes[name], equal_nan=True), name
    guess = back.guess((0.45, 0.45, math.radians(22.5)))
    assert guess is not None and np.all(np.isfinite(guess[0]))


def test_a_corrupt_or_stale_atlas_is_refused_with_the_rebuild_command(small_atlas, tmp_path):
    params = load_params()
    corrupt = tmp_path / "corrupt.npz"
    corrupt.write_bytes(b"PK\x03\x04 not an archive")
    with pytest.raises(AtlasError, match="unreadable: rebuild it with `biped-gait atlas build --params aoustin2013`"):
        Atlas.load(corrupt, params, "aoustin2013")
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(small_atlas.save(tmp_path / "whole.npz").read_bytes()[:500])
    with pytest.raises(AtlasError, match="unreadable"):
        Atlas.load(truncated, params, "aoustin2013")
    path = small_atlas.save(tmp_path / "a.npz")
    other = dataclasses.replace(params, friction=0.8)
    with pytest.raises(AtlasError, match=r"stale \(built for other parameters or model code\): rebuild it with "
                                         r"`biped-gait atlas build --params my.yaml`"):
        Atlas.load(path, other, "my.yaml")
    with pytest.raises(AtlasError, match="no gait atlas at"):
        Atlas.load(tmp_path / "missing.npz", params)
    assert zipfile.is_zipfile(path)


def test_an_atlas_of_this_very_code_is_current_without_parsing_the_code(small_atlas, tmp_path):
    """Its source fingerprint (the code's bytes) says so; an atlas whose source fingerprint
    differs (the code's comments changed since, say) is still current by its model fingerprint."""
    params = load_params()
    code_fingerprint.cache_clear()
    Atlas.load(small_atlas.save(tmp_path / "same.npz"), params, "aoustin2013")
    assert code_fingerprint.cache_info().misses == 0
    other = dataclasses.replace(small_atlas, source="built from other bytes").save(tmp_path / "other.npz")
    back = Atlas.load(other, params, "aoustin2013")
    assert code_fingerprint.cache_info().misses == 1 and back.source == "built from other bytes"
    stale = dataclasses.replace(small_atlas, fingerprint="0" * 64, source="").save(tmp_path / "stale.npz")
    with pytest.raises(AtlasError, match="stale"):
        Atlas.load(stale, params, "aoustin2013")


def test_without_an_atlas_the_planner_continues_from_the_seed():
    planner = GaitPlanner(atlas=False)
    gait = planner.plan(GaitRequest(0.45, 0.55, math.radians(23.5)))
    assert gait.admissible and gait.found == "continuation" and gait.figures.q9_min >= -1e-9
    assert not gait.hint


def test_a_planner_made_for_one_mode_loads_the_other_mode_s_atlas_when_asked():
    """``modes``: the atlases loaded when the planner is made (one for a process that plans one
    gait); another mode's atlas is loaded on its first request, which it answers from it."""
    planner = GaitPlanner(modes=("normal",))
    assert set(planner._atlases) == {GaitMode.NORMAL}
    gait = planner.plan(GaitRequest(0.45, 0.45, math.radians(20.0), "anti-normal"))
    assert gait.admissible and gait.found == "atlas"
    assert set(planner._atlases) == set(GaitMode)
