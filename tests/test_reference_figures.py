"""The 9-DOF parameter sets give today's figures to the bit: plans, a walk, a sweep and the
shipped atlases' nodes against the references stored before the model became a joint table
(tests/reference_figures.py says what is stored and how to regenerate it). Figures added since
(new JSON keys, CSV columns, atlases of other sets) are not compared: every stored one is."""

from __future__ import annotations

import csv
import gzip
import io
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
        changed = [key for key in before if key not in now or now[key] != before[key]]
        assert not changed, f"plan {k} of {params} ({ref.REQUESTS[k][:4]}) changed in {changed}"


def test_walk_is_unchanged():
    now = ref.walk_arrays()
    with np.load(ref.DATA / "walk.npz") as stored:
        assert sorted(stored.files) == sorted(now)
        changed = [name for name in stored.files if not np.array_equal(stored[name], now[name])]
    assert not changed, f"the walk's {changed} changed"


def _columns(text: str) -> dict[str, list[str]]:
    rows = list(csv.reader(io.StringIO(text)))
    return {name: [row[k] for row in rows[1:]] for k, name in enumerate(rows[0])}


def test_sweep_is_unchanged():
    now, before = _columns(ref.sweep_csv()), _columns((ref.DATA / "sweep.csv").read_text())
    changed = [name for name in before if now.get(name) != before[name]]
    assert not changed, f"sweep columns changed: {changed}"


def test_atlas_nodes_are_unchanged():
    stored = json.loads((ref.DATA / "atlas-hashes.json").read_text())
    now = ref.atlas_hashes()
    changed = [name for name in stored if now.get(name) != stored[name]]
    assert not changed, f"atlas node arrays changed: {changed}"
