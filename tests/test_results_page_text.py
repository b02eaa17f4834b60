"""The results page's text on made-up numbers (fast, no solve): the angular-momentum jump with
the paper's definition (H(T+) about the new stance foot minus H(T-) about the old one) next to
the paper's 19.59 and 28.02."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from biped_gait.studies.results_page import (PAPER_JUMP, PAPER_JUMP_ROW, Reference, _momentum_at_paper_point,
                                             _reference_table, paper_momentum_jump)

pytestmark = pytest.mark.studies


def gait(h_minus_old: float, h_minus_new: float, h_plus_new: float):
    """What the page reads of a gait: H(T-) about the old and new feet, H(T+) about the new one."""
    support = SimpleNamespace(h_t_minus=np.array([h_minus_old, h_minus_new]), h_t_plus=np.array([0.0, h_plus_new]))
    return SimpleNamespace(double_support=support)


@pytest.fixture
def reference() -> Reference:
    normal, anti = gait(-11.5, 6.0, 7.58), gait(-15.0, 4.0, 8.89)
    return Reference(normal=normal, anti_normal=anti, normal_slack=normal, cold_long_period=normal)


def test_the_papers_jump_is_across_the_two_feet(reference):
    assert PAPER_JUMP == pytest.approx({"normal": 19.59, "anti-normal": 28.02})
    assert paper_momentum_jump(reference.normal) == pytest.approx(19.08)
    assert paper_momentum_jump(reference.anti_normal) == pytest.approx(23.89)


def test_the_page_compares_the_jump_with_the_papers(reference):
    text = _momentum_at_paper_point(reference)
    assert "the project gives 19.08 (normal) against the paper's 19.59, and 23.89 (anti-normal) against 28.02" in text
    table = "\n".join(_reference_table({"aoustin2013": reference}))
    assert f"| {PAPER_JUMP_ROW} | normal | 19.59 | 19.080 |" in table
    assert f"| {PAPER_JUMP_ROW} | anti-normal | 28.02 | 23.890 |" in table
