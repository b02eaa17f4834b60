"""The 9-DOF parameter sets give today's figures to the bit: plans, a walk, a sweep and the
shipped atlases' nodes against the references stored before the model became a joint table
(tests/reference_figures.py says what is stored and how to regenerate it). Figures added since
(plan keys, sweep columns) come after the stored ones, which are compared to the bit."""

from __future__ import annotations

import gzip
import json

import numpy as np
import pytest

from tests import reference_figures as ref

pytestmark = pytest.mark.core


@pytest.mark.parametrize("params", ref.SETS)
def test_plans_are_unchanged(params):
    for k, text in enumerate(ref.plan_texts(params)):
        stored = gzip.decompress((ref.DATA / f"plan-{params}-{k}.json.gz").read_bytes()).decode()
        now, before = json.loads(text), json.loads(stored)
        assert list(now)[:len(before)] == list(before), "keys were added before the stored ones"
        if json.dumps({key: now[key] for key in before}, indent=1) != stored:
            changed = [key for key in before if now.get(key) != before[key]]
            pytest.fail(f"plan {k} of {params} ({ref.REQUESTS[k][:4]}) changed in {changed}")


def test_walk_is_unchanged():
    now = ref.walk_arrays()
    with np.load(ref.DATA / "walk.npz") as stored:
        assert sorted(stored.files) == sorted(now)
        changed = [name for name in stored.files if not np.array_equal(stored[name], now[name])]
    assert not changed, f"the walk's {changed} changed"


def test_sweep_is_unchanged():
    stored = (ref.DATA / "sweep.csv").read_text()
    header = stored.splitlines()[0].split(",")
    now = ref.sweep_csv(header)
    assert now == stored


def test_atlas_nodes_are_unchanged():
    stored = json.loads((ref.DATA / "atlas-hashes.json").read_text())
    now = ref.atlas_hashes()
    assert sorted(now) == sorted(stored)
    changed = [name for name in stored if now[name] != stored[name]]
    assert not changed, f"atlas node arrays changed: {changed}"
