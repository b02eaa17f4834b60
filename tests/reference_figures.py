"""Reference figures of the 9-DOF parameter sets, stored before a behaviour-preserving change and
compared to the bit after it (tests/test_reference_figures.py).

What is stored (``tests/data/reference/``): the plan JSON (every figure and the sampled
trajectory, less the wall time of the solve) of five gaits per set, chosen to exercise each
option (modes, closures, efforts, friction, rate bound, the effort's reading); one 20-step walk of
the default gait with momentum steering (every sample's state, ground reaction and pelvis pose,
every touchdown's impulses); a sweep's CSV; and a SHA-256 of every node array of the shipped
atlases. Regenerate (only when the figures are meant to change) with

    .venv/bin/python -m tests.reference_figures
"""

from __future__ import annotations

import csv
import gzip
import io
import hashlib
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "reference"
SETS = ("aoustin2013", "aoustin2013-table")
# (L m, T s, alpha deg, mode, extra request fields)
REQUESTS = (
    (0.45, 0.45, 23.5, "normal", {}),
    (0.40, 0.45, 21.1, "anti-normal", {}),
    (0.50, 0.50, 30.0, "normal", {"closure": "slack"}),
    (0.45, 0.45, 10.0, "normal", {"effort": "l2"}),
    (0.55, 0.48, 15.0, "normal", {"friction": math.inf, "rate_bound": 20.0, "effort_coordinates": "absolute"}),
)
SWEEP_ARGS = ("--step-length", "0.45", "--period", "0.45", "--alpha-deg-range", "0", "45", "5",
              "--mode", "normal", "anti-normal")


def plan_texts(params: str) -> list[str]:
    """The plan JSON of each of ``REQUESTS`` for the parameter set ``params``, solve time left out."""
    from biped_gait.core.gait import views
    from biped_gait.core.gait.planner import GaitPlanner, GaitRequest

    planner = GaitPlanner(params)
    texts = []
    for length, period, alpha, mode, extra in REQUESTS:
        gait = planner.plan(GaitRequest(length, period, math.radians(alpha), mode, **extra))
        figures = views.to_dict(gait)
        figures.pop("solve_time_s")
        texts.append(json.dumps(figures, indent=1))
    return texts


def walk_arrays() -> dict[str, np.ndarray]:
    """20 steps of the default gait walked with momentum steering at 200 samples per second."""
    from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
    from biped_gait.core.walking.events import StepSamples, Touchdown
    from biped_gait.core.walking.orbit import PlannedOrbit
    from biped_gait.core.walking.walk import Walk

    gait = GaitPlanner().plan(GaitRequest(0.45, 0.45, math.radians(23.5), "normal"))
    walk = Walk(PlannedOrbit.of(gait), rate=200.0, steps=20, momentum_rate=0.25)
    q, qd, grf, position, quaternion, impulses, times = [], [], [], [], [], [], []
    for item in walk.batches():
        if isinstance(item, StepSamples):
            q += [s.q for s in item.samples]
            qd += [s.qd for s in item.samples]
            grf += [s.grf for s in item.samples]
            position.append(item.world.pelvis_position)
            quaternion.append(item.world.pelvis_quaternion)
        elif isinstance(item, Touchdown):
            impulses.append(np.concatenate([item.i_minus, item.i_plus, [item.W]]))
            times.append([item.t, item.t_step])
    return {"q": np.array(q), "qd": np.array(qd), "grf": np.array(grf), "pelvis_position": np.concatenate(position),
            "pelvis_quaternion": np.concatenate(quaternion), "touchdown_impulses": np.array(impulses),
            "touchdown_times": np.array(times)}


def sweep_csv(columns: list[str] | None = None) -> str:
    """The CSV of a small sweep over alpha, both modes, through the command line (the solve times
    left out; ``columns``: only these, in this order, which must come first)."""
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([sys.executable, "-m", "biped_gait.cli", "sweep", *SWEEP_ARGS, "--workers", "1", "--out", out],
                       check=True, capture_output=True)
        rows = list(csv.reader(io.StringIO((Path(out) / "sweep.csv").read_text())))
    keep = [k for k, name in enumerate(rows[0]) if name != "solve_time_s"]
    if columns is not None:
        assert [rows[0][k] for k in keep[:len(columns)]] == columns, "columns were added before the stored ones"
        keep = keep[:len(columns)]
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerows([[row[k] for k in keep] for row in rows])
    return text.getvalue()


def atlas_hashes() -> dict[str, str]:
    """SHA-256 of every node array of every shipped atlas, by "file/array"."""
    from importlib import resources

    out = {}
    folder = resources.files("biped_gait").joinpath("core", "data", "atlas")
    for path in sorted(Path(str(folder)).glob("*.npz")):
        with np.load(path) as archive:
            for name in sorted(archive.files):
                if name != "meta":
                    out[f"{path.name}/{name}"] = hashlib.sha256(np.ascontiguousarray(archive[name]).tobytes()).hexdigest()
    return out


def main() -> None:
    DATA.mkdir(parents=True, exist_ok=True)
    for params in SETS:
        for k, text in enumerate(plan_texts(params)):
            (DATA / f"plan-{params}-{k}.json.gz").write_bytes(gzip.compress(text.encode(), mtime=0))
    np.savez_compressed(DATA / "walk.npz", **walk_arrays())
    (DATA / "sweep.csv").write_text(sweep_csv())
    (DATA / "atlas-hashes.json").write_text(json.dumps(atlas_hashes(), indent=1) + "\n")


if __name__ == "__main__":
    main()
