"""The results page's section on the stop, from the plan the package keeps (no solve): its figures
against the plan's own arrays, the committed docs/results.md's section against the plan, the section
rebuilt alone, its figure."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from biped_gait.studies.actuated_page import HEADING as ACTUATED_HEADING
from biped_gait.studies.stop_page import HEADING, STOP_FIGURE, kept_stop_plan, main, splice, stop_lines

from .test_lasting_page import PNG_SIGNATURE

pytestmark = pytest.mark.studies

DOCS = Path(__file__).resolve().parents[1] / "docs"


@pytest.fixture(scope="module")
def plan():
    return kept_stop_plan()


def check_stop_section(text: str, plan) -> None:
    """The section of ``text`` says the kept plan: its date and commit, duration, E, sum |I^-|, the
    torques' integral, peak torque, friction used and least normal force, and each joint's I^- and
    peak (half a last printed digit: 2 decimals for efforts, 1 for torques and forces, 3 for mu)."""
    model, support, meta = plan
    start = text.index(HEADING)
    end = text.find("\n## ", start)
    section = text[start:] if end < 0 else text[start:end]
    assert f"solved on {meta['date']} at commit {meta['commit']}" in section
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in section.splitlines()
            if line.startswith("| ") and not line.startswith("| duration") and not line.startswith("| joint")]
    figures = [float(c) for c in rows[0]]
    expected = [support.duration, support.effort_total, np.abs(support.i_minus).sum(), support.effort_l1,
                support.peak_torque.max(), support.friction_used, support.contact_forces[..., 2].min()]
    for got, want, half in zip(figures, expected, (0.5, 0.005, 0.005, 0.005, 0.05, 5e-4, 0.05)):
        assert abs(got - want) <= half + 1e-12, (got, want)
    joints = {row[0]: (float(row[1]), float(row[2])) for row in rows[1:]}
    assert list(joints) == list(model.actuated_names)
    for name, i, peak in zip(model.actuated_names, support.i_minus, support.peak_torque):
        assert abs(joints[name][0] - i) <= 0.005 + 1e-12 and abs(joints[name][1] - peak) <= 0.05 + 1e-12
    assert re.search(rf"\]\({re.escape(STOP_FIGURE)}\)", section)


def test_the_section_says_the_kept_plan(plan):
    check_stop_section("\n".join([HEADING, "", *stop_lines(*plan)]), plan)


def test_the_committed_page_says_the_kept_plan(plan):
    check_stop_section((DOCS / "results.md").read_text(), plan)


def test_the_section_is_rebuilt_alone(tmp_path):
    """``python -m biped_gait.studies.stop_page`` replaces the section and nothing else: on the
    committed page it changes nothing; a page without it gets it after the actuated swing's, once."""
    page = tmp_path / "results.md"
    committed = (DOCS / "results.md").read_text()
    page.write_text(committed)
    assert main(["--page", str(page)]) == 0
    assert page.read_text() == committed
    assert (tmp_path / STOP_FIGURE).read_bytes()[:8] == PNG_SIGNATURE
    start = committed.index(HEADING)
    end = committed.index("\n## ", start)
    once = splice(committed[:start] + committed[end + 1:], ["new text"])
    assert once.count(HEADING) == 1 and once.index(ACTUATED_HEADING) < once.index(HEADING)
