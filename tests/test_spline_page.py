"""The results page's sections on the stop and the start, from the plans the package keeps (no
solve): their figures against the plans' own arrays, the committed docs/results.md's sections
against the plans, the sections rebuilt alone, their figures."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from biped_gait.studies.actuated_page import HEADING as ACTUATED_HEADING
from biped_gait.studies.spline_page import FIGURES, HEADINGS, impulse, kept_plans, main, section_lines, splice

from .test_lasting_page import PNG_SIGNATURE

pytestmark = pytest.mark.studies

DOCS = Path(__file__).resolve().parents[1] / "docs"


@pytest.fixture(scope="module")
def plans():
    return kept_plans()


def check_section(text: str, kind: str, plan) -> None:
    """The section on ``kind`` of ``text`` says the kept plan: its date and commit, duration, E, its
    impulse's sum |I|, the torques' integral, peak torque, friction used and least normal force, and
    each joint's impulse and peak (half a last printed digit: 2 decimals for efforts, 1 for torques
    and forces, 3 for mu)."""
    model, support, meta = plan
    start = text.index(HEADINGS[kind])
    end = text.find("\n## ", start)
    section = text[start:] if end < 0 else text[start:end]
    assert f"solved on {meta['date']} at commit {meta['commit']}" in section
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in section.splitlines()
            if line.startswith("| ") and not line.startswith("| duration") and not line.startswith("| joint")]
    figures = [float(c) for c in rows[0]]
    impulses = impulse(kind, support)
    expected = [support.duration, support.effort_total, np.abs(impulses).sum(), support.effort_l1,
                support.peak_torque.max(), support.friction_used, support.contact_forces[..., 2].min()]
    for got, want, half in zip(figures, expected, (0.5, 0.005, 0.005, 0.005, 0.05, 5e-4, 0.05)):
        assert abs(got - want) <= half + 1e-12, (got, want)
    joints = {row[0]: (float(row[1]), float(row[2])) for row in rows[1:]}
    assert list(joints) == list(model.actuated_names)
    for name, i, peak in zip(model.actuated_names, impulses, support.peak_torque):
        assert abs(joints[name][0] - i) <= 0.005 + 1e-12 and abs(joints[name][1] - peak) <= 0.05 + 1e-12
    assert re.search(rf"\]\({re.escape(FIGURES[kind])}\)", section)


def test_the_package_keeps_the_stop_and_the_start(plans):
    assert list(plans) == ["stop", "start"]
    assert all(meta["kind"] == kind for kind, (_, _, meta) in plans.items() if "kind" in meta)


def test_each_section_says_its_kept_plan(plans):
    for kind, plan in plans.items():
        check_section("\n".join([HEADINGS[kind], "", *section_lines(kind, *plan)]), kind, plan)


def test_the_committed_page_says_the_kept_plans(plans):
    committed = (DOCS / "results.md").read_text()
    for kind, plan in plans.items():
        check_section(committed, kind, plan)


def test_the_sections_are_rebuilt_alone(tmp_path, plans):
    """``python -m biped_gait.studies.spline_page`` replaces the sections and nothing else: on the
    committed page it changes nothing; a page without the stop's gets it after the actuated swing's,
    one without the start's after the stop's, once."""
    page = tmp_path / "results.md"
    committed = (DOCS / "results.md").read_text()
    page.write_text(committed)
    assert main(["--page", str(page)]) == 0
    assert page.read_text() == committed
    for kind, before in (("stop", ACTUATED_HEADING), ("start", HEADINGS["stop"])):
        assert (tmp_path / FIGURES[kind]).read_bytes()[:8] == PNG_SIGNATURE
        start = committed.index(HEADINGS[kind])
        end = committed.find("\n## ", start)
        cut = committed[:start] + (committed[end + 1:] if end >= 0 else "")
        once = splice(cut, kind, ["new text"])
        assert once.count(HEADINGS[kind]) == 1 and once.index(before) < once.index(HEADINGS[kind])
