"""The suite's own order (tests/conftest.py): the modules it starts first are this suite's."""

from __future__ import annotations

from pathlib import Path

from .conftest import LONGEST_FIRST


def test_the_modules_started_first_exist_once_each():
    here = Path(__file__).resolve().parent
    assert [name for name in LONGEST_FIRST if not (here / f"{name}.py").is_file()] == []
    assert len(set(LONGEST_FIRST)) == len(LONGEST_FIRST)
