"""Benchmark: the planner with the gait atlas against the cold solve, and the Fig. 4 study.

1. ``plan`` on random requests inside the atlas (L 0.25..0.65 m, T 0.30..0.65 s, alpha 0..45
   deg, both modes; fixed seed): median solve time from the atlas against the cold solve
   (``plan(..., cold=True)``: the straight-line start, what ``plan`` did before the atlas) of the
   same requests, in the same run, and against the straightforward cold solve
   (``yardsticks.ColdSolve``); how each gait was found and on which grid; how many cold solves
   end on the backward-knee twin or nowhere while the atlas answers.
2. The Fig. 4 study (186 gaits, six chains) on local worker processes, as a count of the
   straightforward cold solves (``yardsticks.ColdSolve``) measured in the same run.
3. The shipped atlases: build time (recorded when built) and file size.

    .venv/bin/python benchmarks/bench_atlas.py [--requests N] [--workers N]
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings

import numpy as np

from biped_gait.core.gait.atlas import Atlas, atlas_path
from biped_gait.core.gait.configurations import GaitMode
from biped_gait.core.model.params import load_params, shipped_param_names
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.studies.executors import check_workers
from bench_study import time_study  # this folder's Fig. 4 timing
import results
from yardsticks import ColdSolve, median_s


def random_requests(count: int, seed: int = 7) -> list[GaitRequest]:
    rng = np.random.default_rng(seed)
    return [GaitRequest(float(rng.uniform(0.25, 0.65)), float(rng.uniform(0.30, 0.65)),
                        float(np.radians(rng.uniform(0.0, 45.0))), list(GaitMode)[i % 2]) for i in range(count)]


def timed(call):
    start = time.perf_counter()
    result = call()
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=60)
    parser.add_argument("--workers", type=int, help="local worker processes for the study (default: one per core)")
    args = parser.parse_args()
    warnings.simplefilter("error")  # a missing or stale atlas would make this benchmark meaningless
    planner = GaitPlanner()
    requests = random_requests(args.requests)
    planner.plan(requests[0])
    planner.plan(requests[1])  # both atlases loaded, first-call costs out of the way
    atlas_times, cold_times, found = [], [], {}
    admissible = cold_wrong = 0
    for request in requests:
        dt, gait = timed(lambda: planner.plan(request))
        atlas_times.append(dt)
        found[gait.found] = found.get(gait.found, 0) + 1
        dt, cold = timed(lambda: planner.plan(request, cold=True))
        cold_times.append(dt)
        if gait.admissible:
            admissible += 1
            cold_wrong += not cold.admissible
    ms = lambda xs: 1e3 * statistics.median(xs)  # noqa: E731
    print(f"plan on {len(requests)} random requests inside the atlas (both modes):")
    print(f"  from the atlas: median {ms(atlas_times):7.2f} ms   p90 {1e3 * np.percentile(atlas_times, 90):7.2f} ms   "
          f"found by {found}")
    print(f"  cold solve:     median {ms(cold_times):7.2f} ms   (the same requests, this run)")
    print(f"  ratio cold / atlas: {statistics.median(cold_times) / statistics.median(atlas_times):.2f}x")
    yardstick = ColdSolve()
    straightforward = median_s(yardstick.solve, 5)
    steps = {}
    for request in requests:
        gait = planner.plan(request)
        if gait.accuracy is not None:
            steps[gait.accuracy.steps] = steps.get(gait.accuracy.steps, 0) + 1
    print(f"  the straightforward cold solve (yardstick, this run): {1e3 * straightforward:7.1f} ms = "
          f"{straightforward / statistics.median(atlas_times):.1f} plans from the atlas (median); their grids "
          f"(RK8 steps per T: plans) {dict(sorted(steps.items()))}")
    print(f"  {admissible} requests admissible; the cold solve is not admissible for {cold_wrong} of them "
          "(backward-knee twin or no convergence)")

    cold = ColdSolve()
    yardstick = median_s(cold.solve, 5)
    workers = check_workers(args.workers)
    study, _, grid = time_study(workers)
    print(f"Fig. 4 study: {grid.size} gaits on {workers} worker processes: {study:.2f} s wall = "
          f"{study / yardstick:.1f} straightforward cold solves ({1e3 * yardstick:.1f} ms each, this run)")

    results.write("bench_atlas", {
        "cold solve": f"{1e3 * straightforward:.0f} ms", "plan from the atlas": f"{ms(atlas_times):.1f} ms",
        "plan from the atlas, in cold solves": f"1/{straightforward / statistics.median(atlas_times):.1f}",
        "Fig. 4 study, in cold solves": f"{study / yardstick:.1f}"},
        {"cold_solve_s": straightforward, "atlas_plan_median_s": statistics.median(atlas_times),
         "atlas_plan_p90_s": float(np.percentile(atlas_times, 90)), "planner_cold_median_s": statistics.median(cold_times),
         "study_s": study, "study_cold_solve_s": yardstick},
        {"requests": len(requests), "study gaits": int(grid.size), "workers": workers})

    for name in shipped_param_names():
        params = load_params(name)
        for mode in GaitMode:
            path = atlas_path(params, mode)
            atlas = Atlas.load(path, params, name)
            print(f"atlas {name} {mode.value}: built in {atlas.build_seconds:.0f} s, {path.stat().st_size / 1e6:.2f} MB, "
                  f"{sum(atlas.counts().values())} nodes {atlas.counts()}")


if __name__ == "__main__":
    main()
