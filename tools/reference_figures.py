"""A developer's tool for the reference figures of tests/reference_figures.py, outside the test
suite (which compares them within tolerances on any machine):

    .venv/bin/python tools/reference_figures.py --bits    # this machine reproduces every reference bit for bit (a refactor meant to change nothing)
    .venv/bin/python tools/reference_figures.py --store   # regenerate them, only when the figures are meant to change

Bit for bit holds on the machine that stored them; another CPU's BLAS, Eigen or compiler path
moves the last digits.
"""

from __future__ import annotations

import argparse
import csv
import gzip
import io
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.reference_figures import (DATA, SETS, atlas_hashes, plan_figures, stored_plans, stored_walk,  # noqa: E402
                                     sweep_csv, walk_arrays)


def store() -> None:
    """Write every reference anew (only when the figures are meant to change)."""
    DATA.mkdir(parents=True, exist_ok=True)
    for params in SETS:
        for k, figures in enumerate(plan_figures(params)):
            text = json.dumps(figures, indent=1)
            (DATA / f"plan-{params}-{k}.json.gz").write_bytes(gzip.compress(text.encode(), mtime=0))
    np.savez_compressed(DATA / "walk.npz", **walk_arrays())
    (DATA / "sweep.csv").write_text(sweep_csv())
    (DATA / "atlas-hashes.json").write_text(json.dumps(atlas_hashes(), indent=1) + "\n")


def bits() -> list[str]:
    """What this machine does not reproduce to the bit (a developer's check of a refactor)."""
    out = []
    for params in SETS:
        for k, (now, stored) in enumerate(zip(plan_figures(params), stored_plans(params))):
            out += [f"plan {k} of {params}: {key}" for key in stored if now.get(key) != stored[key]]
    now, stored = walk_arrays(), stored_walk()
    out += [f"walk: {name}" for name in stored if name not in now or not np.array_equal(now[name], stored[name])]
    now_rows, stored_rows = (list(csv.DictReader(io.StringIO(text))) for text in (sweep_csv(), (DATA / "sweep.csv").read_text()))
    out += [f"sweep row {k}: {key}" for k, (row, stored) in enumerate(zip(now_rows, stored_rows)) for key in stored
            if row.get(key) != stored[key]] + (["sweep: rows"] if len(now_rows) != len(stored_rows) else [])
    digests = atlas_hashes()
    out += [f"atlas {name}" for name, digest in json.loads((DATA / "atlas-hashes.json").read_text()).items()
            if digests.get(name) != digest]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(prog="tools/reference_figures.py", description=__doc__.split("\n\n")[0])
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--bits", action="store_true", help="check that this machine reproduces the references to the bit")
    what.add_argument("--store", action="store_true", help="regenerate the references")
    args = parser.parse_args()
    if args.store:
        store()
        return
    differ = bits()
    print("\n".join(differ) if differ else "every reference reproduced to the bit")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
