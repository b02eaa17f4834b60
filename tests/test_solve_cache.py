"""Solves kept on disk (core/gait/solve_cache.py): the same solve for the same key answered from
the directory, any other key (the request, the ends, the code) solved, a key being solved waited for, nothing
kept when off."""

from __future__ import annotations

import math
import threading
import time
from dataclasses import replace

import numpy as np
import pytest

from biped_gait.core.gait import solve_cache
from biped_gait.core.gait.lasting import LastingRequest
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.gait.solve_cache import CACHE_ENV, OFF, cached


@pytest.fixture(scope="module")
def planned():
    planner = GaitPlanner(modes=("normal",))
    return planner, planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5)))


def counted(planner, gait, effort: str, calls: list):
    """The impulsive limit of ``gait`` (a real IPOPT solve of a second or so), counted."""
    def solve():
        calls.append(effort)
        return planner.lasting.limit(gait, effort)
    return solve


def test_the_same_key_is_answered_from_disk_and_any_other_is_solved(planned, tmp_path, monkeypatch):
    planner, gait = planned
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "solves"))
    calls: list[str] = []
    boundary = planner.lasting.boundary(gait)
    first = cached("limit", (planner.params, boundary, LastingRequest(0.0)), counted(planner, gait, "l1", calls))
    # an equal key made anew (other objects, the same values) is the same key
    again = cached("limit", (planner.params, planner.lasting.boundary(gait), LastingRequest(0.0)),
                   counted(planner, gait, "l1", calls))
    assert calls == ["l1"] and first.success
    assert again.effort_total == first.effort_total  # the stored copy of the same float
    np.testing.assert_array_equal(again.i_minus, first.i_minus)
    assert any((tmp_path / "solves").rglob("output.pkl"))
    # another request, other ends, another code: each solved
    cached("limit", (planner.params, boundary, LastingRequest(0.0, "l2")), counted(planner, gait, "l2", calls))
    moved = replace(boundary, period=boundary.period + 1e-12)
    cached("limit", (planner.params, moved, LastingRequest(0.0)), counted(planner, gait, "l1", calls))
    monkeypatch.setattr(solve_cache, "core_digest", lambda: "other code")
    cached("limit", (planner.params, boundary, LastingRequest(0.0)), counted(planner, gait, "l1", calls))
    assert calls == ["l1", "l2", "l1", "l1"]


def test_a_key_being_solved_is_waited_for_not_solved_again(planned, tmp_path, monkeypatch):
    """A second asker of a key whose solve is under way (another thread here; another process
    takes the same lock) waits for it and gets its answer; its own solve is never called."""
    planner, gait = planned
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "solves"))
    key = (planner.params, planner.lasting.boundary(gait), LastingRequest(0.0))
    solving, answers = threading.Event(), {}

    def first():
        solving.set()
        time.sleep(0.5)  # the second asker is waiting by now
        return planner.lasting.limit(gait)

    def never():
        raise AssertionError("a key being solved was solved again")

    ahead = threading.Thread(target=lambda: answers.setdefault("first", cached("limit", key, first)))
    ahead.start()
    assert solving.wait(30.0)
    second = cached("limit", key, never)
    ahead.join(60.0)
    assert second.effort_total == answers["first"].effort_total


def test_off_solves_every_time(planned, monkeypatch):
    planner, gait = planned
    monkeypatch.setenv(CACHE_ENV, OFF)
    calls: list[str] = []
    key = (planner.params, planner.lasting.boundary(gait), LastingRequest(0.0))
    for _ in range(2):
        cached("limit", key, counted(planner, gait, "l1", calls))
    assert calls == ["l1", "l1"]


def test_the_default_directory_is_the_users_cache(monkeypatch, tmp_path):
    monkeypatch.delenv(CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert solve_cache.cache_directory() == tmp_path / "biped_gait"
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "here"))
    assert solve_cache.cache_directory() == tmp_path / "here"
