"""Benchmark: the Fig. 4 study, 3 step lengths x 31 arm amplitudes (0 to 45 deg) x 2 modes =
186 gaits at T = 0.45 s, as six continuation chains on local worker processes.

Prints the wall time of the whole study (worker start-up included), the wall time per gait,
and the mean solve time of one gait inside a worker. Run:

    .venv/bin/python benchmarks/bench_study.py [--workers N]   (default: one per core)
"""

from __future__ import annotations

import argparse
import statistics
import time

from biped_gait.studies.executors import check_workers, open_executor
from biped_gait.core.model.params import load_params
from biped_gait.studies.study import fig4_grid
from biped_gait.studies.sweep import SweepGrid, solve_grid


def time_study(workers: int) -> tuple[float, list, SweepGrid]:
    """Wall time (s, worker start-up included) of the Fig. 4 study on ``workers`` local
    processes, its gaits and its grid."""
    grid = fig4_grid(load_params())
    start = time.perf_counter()
    with open_executor(workers) as executor:
        results = [r for _, chain in solve_grid(grid, executor) for r in chain]
    wall = time.perf_counter() - start
    assert len(results) == grid.size and all(r.admissible for r in results)
    return wall, results, grid


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    args = parser.parse_args()
    workers = check_workers(args.workers)
    wall, results, grid = time_study(workers)
    print(f"Fig. 4 study: {grid.size} gaits in {len(grid.chains())} chains on {workers} worker processes")
    print(f"  wall time {wall:6.2f} s   per gait {1e3 * wall / grid.size:6.1f} ms (wall)")
    print(f"  solve time per gait in a worker: mean {1e3 * statistics.mean(r.solve_time_s for r in results):6.1f} ms, "
          f"median {1e3 * statistics.median(r.solve_time_s for r in results):6.1f} ms")


if __name__ == "__main__":
    main()
