"""The results page's section on the double support that lasts, from the stored study
docs/lasting-study.json (no solve): its tables against the file's numbers, its figures, the section
without a study. ``check_lasting_section`` is also what the results-page test runs on the page the
command writes."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from biped_gait.core.model.params import DEFAULT_PARAMS, load_params
from biped_gait.studies.figures import save
from biped_gait.studies.lasting_page import (ARMS_FIGURE, EFFORT_FIGURE, LastingStudy, lasting_figures,
                                             lasting_lines)

pytestmark = pytest.mark.studies

STORED = Path(__file__).resolve().parents[1] / "docs" / "lasting-study.json"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# The page prints E, W and E(0+) with 2 decimals, the friction used with 3, torques with 1: a
# printed figure is within half its last digit of the file's (and a hair more for the float's own
# rounding to decimal).
TWO_DECIMALS, THREE_DECIMALS, ONE_DECIMAL = 0.0051, 0.00051, 0.051


def _rows(text: str, first_cell: str) -> list[list[str]]:
    """The cells of the table rows of ``text`` whose first cell matches ``first_cell`` (a regex)."""
    rows = []
    for line in text.splitlines():
        if line.startswith("| "):
            cells = [c.strip() for c in line.strip("|").split("|")]
            if re.fullmatch(first_cell, cells[0]):
                rows.append(cells)
    return rows


def _number(cell: str) -> float:
    return float(cell.strip("*").split()[0])


def check_grid_row(section: str, alphas: list[dict], mode: str, key: str, value: float) -> list[dict]:
    """The E(alpha) row "``mode``, ``value`` s" of ``section`` says the stored sweep's rows of ``mode``
    at ``key`` = ``value`` (a dash where the solve did not finish); returns those rows by alpha."""
    sweep = sorted((r for r in alphas if r["mode"] == mode and r[key] == value), key=lambda r: r["alpha_deg"])
    (cells,) = _rows(section, re.escape(f"{mode}, {value:g} s"))
    for cell, r in zip(cells[1:], sweep, strict=True):
        assert cell == "-" if not r["success"] else _number(cell) == pytest.approx(r["E"], abs=TWO_DECIMALS)
    return sweep


def check_lasting_section(text: str, stored: dict) -> None:
    """The section of ``text`` says the stored study ``stored`` (its JSON): its date and commit, E,
    E / W, the friction used and the iterations against d, the peak torques at d = 0.1 s against
    the effort limit, the E(alpha) grid and the optimal amplitudes (found here from the file)."""
    start = text.index("## A double support that lasts: its effort and the arms' optimum")
    end = text.find("\n## ", start)
    section = text[start:] if end < 0 else text[start:end]
    assert f"computed on {stored['date']} at commit {stored['commit']}" in section
    durations = stored["durations"]
    W, E0 = durations[0]["W"], durations[0]["E0"]
    limit = _rows(section, r"0\+ \(the limit\)")
    assert len(limit) == 1 and _number(limit[0][1]) == pytest.approx(E0, abs=TWO_DECIMALS)
    for row in durations:
        cells = _rows(section, re.escape(f"{row['d']:g}"))[0]  # the first table with d first is E against d
        assert _number(cells[1]) == pytest.approx(row["E"], abs=TWO_DECIMALS)
        assert _number(cells[2]) == pytest.approx(row["E"] / W, abs=TWO_DECIMALS)
        assert _number(cells[4]) == pytest.approx(max(row["peak_torque"]), abs=ONE_DECIMAL)
        assert _number(cells[6]) == pytest.approx(row["friction_used"], abs=THREE_DECIMALS)
        assert int(cells[7]) == row["iterations"]
    human = next(r for r in durations if math.isclose(r["d"], 0.1))
    params = load_params(DEFAULT_PARAMS)
    joint_rows = [r for r in _rows(section, r"[a-z_]+") if len(r) == 4 and r[0] != "joint"]
    assert len(joint_rows) == len(human["peak_torque"])
    for cells, peak in zip(joint_rows, human["peak_torque"]):
        assert _number(cells[1]) == pytest.approx(peak, abs=ONE_DECIMAL)
        assert _number(cells[2]) == 200.0  # the default set's joint table: every actuated joint's effort
    assert params.friction == 0.5 and "friction used (mu = 0.5)" in section
    for mode in ("normal", "anti-normal"):
        for d in sorted({r["d"] for r in stored["alphas"]}):
            sweep = check_grid_row(section, stored["alphas"], mode, "d", d)
            best = min((r for r in sweep if r["success"]), key=lambda r: r["E"])
            (optimum,) = [c for c in _rows(section, re.escape(f"{d:g}")) if c[1] == mode]
            assert _number(optimum[2]) == pytest.approx(best["alpha_deg"], abs=1e-9)
            assert _number(optimum[3]) == pytest.approx(best["E"], abs=TWO_DECIMALS)
            still = [r["E"] for r in stored["alphas"] if r["d"] == d and r["alpha_deg"] == 0.0 and r["success"]]
            assert _number(optimum[4]) == pytest.approx(still[0], abs=TWO_DECIMALS)
            assert _number(optimum[5]) == pytest.approx(still[0] - best["E"], abs=2 * TWO_DECIMALS)
    assert f"![E against d, with E(0+) and W]({EFFORT_FIGURE})" in section
    assert f"({ARMS_FIGURE})" in section


@pytest.fixture(scope="module")
def study() -> LastingStudy:
    return LastingStudy.load(STORED)


def test_the_section_says_the_stored_study(study):
    stored = json.loads(STORED.read_text())
    text = "\n".join(["## A double support that lasts: its effort and the arms' optimum (beyond the paper)",
                      *lasting_lines(study, STORED)])
    check_lasting_section(text, stored)
    normal = re.search(r"The normal swing's alpha\* is ([\d., ]+) deg at d = ([\d., ]+) s", text)
    assert normal is not None  # the closing note's figures, here read from the file
    assert "on a 7.5 deg grid, so each within 3.75 deg" in text


def test_a_failed_solve_is_a_dash_and_the_arms_still_come_from_either_swing(study):
    """alpha = 0 is one gait for both swings: E with the arms still is the mean of its solves that
    finished (they agree to the solver's tolerance where both did)."""
    for d in study.sweep_durations:
        still = [r for mode in ("normal", "anti-normal") for r in study.sweep(mode, d)
                 if r["alpha_deg"] == 0.0 and r["success"]]
        assert still  # at every d of the sweep one of them finished
        assert max(r["E"] for r in still) - min(r["E"] for r in still) < 1e-3


def test_the_figures_are_written(study, tmp_path):
    figures = lasting_figures(study)
    assert sorted(name for _, name in figures.values()) == sorted([EFFORT_FIGURE, ARMS_FIGURE])
    for figure, name in figures.values():
        assert save(figure, tmp_path / name).read_bytes()[:8] == PNG_SIGNATURE


def test_without_a_study_the_section_says_how_to_make_it(tmp_path):
    missing = tmp_path / "lasting-study.json"
    (line,) = lasting_lines(None, missing)
    assert f"No stored study at `{missing}`" in line and "python -m biped_gait.studies.lasting_study" in line
    assert lasting_figures(None) == {}
