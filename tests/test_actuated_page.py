"""The results page's section on the actuated swing, from the stored study
docs/actuated-swing-study.json (no solve): its tables against the file's numbers, the committed
docs/results.md's section against the file, the section rebuilt alone, its figure, the section
without a study. ``check_actuated_section`` is also what the results-page test runs on the page the
command writes."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from biped_gait.studies.actuated_page import (ACTUATED_FIGURE, HEADING, ActuatedStudy, actuated_figure,
                                              actuated_lines, main, splice)
from biped_gait.studies.figures import save
from biped_gait.studies.lasting_page import HEADING as LASTING_HEADING

from .test_lasting_page import ONE_DECIMAL, PNG_SIGNATURE, TWO_DECIMALS, _number, _rows, check_grid_row

pytestmark = pytest.mark.studies

DOCS = Path(__file__).resolve().parents[1] / "docs"
STORED = DOCS / "actuated-swing-study.json"
LIMIT = 200.0  # N m: the default set's joint table, every actuated joint's effort


def check_actuated_section(text: str, stored: dict) -> None:
    """The section of ``text`` says the stored study ``stored`` (its JSON): its date and commit, E,
    the impulsive E and each joint's peak torque against (tau, d), the free taus, the E(alpha) grid
    and the optimal amplitudes with their savings (found here from the file). Tolerances: the page
    prints E with 2 decimals, torques with 1 (``test_lasting_page``'s half a last digit)."""
    start = text.index(HEADING)
    end = text.find("\n## ", start)
    section = text[start:] if end < 0 else text[start:end]
    assert f"computed on {stored['date']} at commit {stored['commit']}" in section
    tau_rows = [c for c in _rows(section, r"0|0\.1") if len(c) == 12]  # d, tau, E, E impulsive, 7 joints, iterations
    assert len(tau_rows) == len(stored["taus"])
    for cells, row in zip(tau_rows, sorted(stored["taus"], key=lambda r: (r["d"], -r["tau"])), strict=True):
        assert (_number(cells[0]), _number(cells[1])) == (pytest.approx(row["d"]), pytest.approx(row["tau"]))
        assert _number(cells[3]) == pytest.approx(row["E_impulsive"], abs=TWO_DECIMALS)
        assert int(cells[11].split()[0]) == row["iterations"]
        if not row["success"]:
            assert cells[2] == "-" and set(cells[4:11]) == {"-"} and "(no cycle)" in cells[11]
            continue
        assert _number(cells[2]) == pytest.approx(row["E"], abs=TWO_DECIMALS)
        for cell, peak in zip(cells[4:11], row["peak_torque"], strict=True):
            assert _number(cell) == pytest.approx(peak, abs=ONE_DECIMAL)
            assert peak <= LIMIT + 1e-6  # within the limit to IPOPT's bound tolerance
    assert section.count(f"(limit {LIMIT:g})") == 7
    for d in sorted({r["d"] for r in stored["taus"]}):
        least = min(r["tau"] for r in stored["taus"] if r["d"] == d and r["success"])
        assert f"at d = {d:g} s" in section and f"the smallest tau solved is {least:g} s" in section
    free = _rows(section, r"0\.1|0\.05|0\.02|0\.01|0\.005")
    free = [c for c in free if len(c) == 5]
    for cells, row in zip(free, stored["free_taus"], strict=True):
        assert _number(cells[0]) == pytest.approx(row["tau"])
        assert cells[1] == "-" if not row["success"] else _number(cells[1]) == pytest.approx(row["E"], abs=TWO_DECIMALS)
    for mode in ("normal", "anti-normal"):
        for tau in sorted({r["tau"] for r in stored["alphas"]}):
            sweep = check_grid_row(section, stored["alphas"], mode, "tau", tau)
            (optimum,) = [c for c in _rows(section, re.escape(f"{tau:g}")) if len(c) == 6 and c[1] == mode]
            done = [r for r in sweep if r["success"]]
            if not done:
                assert optimum[2] == "-"
                continue
            best = min(done, key=lambda r: r["E"])
            assert _number(optimum[2]) == pytest.approx(best["alpha_deg"], abs=1e-9)
            assert _number(optimum[3]) == pytest.approx(best["E"], abs=TWO_DECIMALS)
            still = [r["E"] for r in done if r["alpha_deg"] == 0.0]
            if still:
                assert _number(optimum[5]) == pytest.approx(still[0] - best["E"], abs=2 * TWO_DECIMALS)
    assert f"({ACTUATED_FIGURE})" in section
    assert "Does the arms' optimum survive when no torque exceeds a motor's limit?" in section


@pytest.fixture(scope="module")
def study() -> ActuatedStudy:
    return ActuatedStudy.load(STORED)


def test_the_section_says_the_stored_study(study):
    check_actuated_section("\n".join([HEADING, *actuated_lines(study, STORED)]), json.loads(STORED.read_text()))


def test_the_committed_page_says_the_stored_study():
    """docs/results.md as committed agrees with the stored study (the page was regenerated from it)."""
    check_actuated_section((DOCS / "results.md").read_text(), json.loads(STORED.read_text()))


def test_the_section_is_rebuilt_alone(tmp_path):
    """``python -m biped_gait.studies.actuated_page`` replaces the section and nothing else: on the
    committed page it changes nothing; a page without it gets it after the lasting section, once."""
    page = tmp_path / "results.md"
    committed = (DOCS / "results.md").read_text()
    page.write_text(committed)
    (tmp_path / STORED.name).write_text(STORED.read_text())
    assert main(["--page", str(page)]) == 0
    assert page.read_text() == committed
    assert (tmp_path / ACTUATED_FIGURE).read_bytes()[:8] == PNG_SIGNATURE
    start = committed.index(HEADING)
    end = committed.index("\n## ", start)
    without = committed[:start] + committed[end + 1:]
    assert HEADING not in without
    once = splice(without, ["new text"])
    assert once.count(HEADING) == 1 and once.index(LASTING_HEADING) < once.index(HEADING)
    assert splice(once, ["new text"]) == once
    assert splice("# a page\n", ["x"]).endswith(f"{HEADING}\n\nx\n\n")


def test_the_figure_is_written(study, tmp_path):
    assert save(actuated_figure(study), tmp_path / ACTUATED_FIGURE).read_bytes()[:8] == PNG_SIGNATURE


def test_the_refusals_are_the_solvers(study):
    """Below the smallest tau solved at the default alpha every row is a failed solve, and the
    section says it is the solver's verdict (IPOPT's iteration limit in the file's message)."""
    for d in study.durations:
        least = min(r["tau"] for r in study.against_tau(d) if r["success"])
        below = [r for r in study.against_tau(d) if r["tau"] < least]
        assert below and all(not r["success"] and "Maximum_Iterations_Exceeded" in r["message"] for r in below)
    text = "\n".join(actuated_lines(study, STORED))
    assert "The refusals are the solver's verdict" in text
    assert all(math.isfinite(r["E"]) for r in study.taus if r["success"])


def test_without_a_study_the_section_says_how_to_make_it(tmp_path):
    missing = tmp_path / "actuated-swing-study.json"
    (line,) = actuated_lines(None, missing)
    assert f"No stored study at `{missing}`" in line and "python -m biped_gait.studies.actuated_swing_study" in line
