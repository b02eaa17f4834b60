"""Benchmark: the Fig. 4 study, 3 step lengths x 31 arm amplitudes (0 to 45 deg) x 2 modes =
186 gaits at T = 0.45 s, as six continuation chains on local worker processes.

Prints the wall time of the whole study (worker start-up included) as a count of the
straightforward cold solves (``yardsticks.ColdSolve``) measured in the same run, between the
``--repeat`` studies (medians), the wall time per gait, the solve time of one gait inside a worker,
and what is not solving: the wall time less the workers' solve time shared out. Run:

    .venv/bin/python benchmarks/bench_study.py [--workers N] [--repeat N]   (default: one worker per core)
"""

from __future__ import annotations

import argparse
import statistics
import time

from biped_gait.studies.executors import check_workers, open_executor
from biped_gait.core.model.params import load_params
from biped_gait.studies.study import fig4_grid
from biped_gait.studies.sweep import SweepGrid, solve_grid
from yardsticks import ColdSolve, median_s


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
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    workers = check_workers(args.workers)
    cold = ColdSolve()
    colds, walls, solving, results = [median_s(cold.solve, 1)], [], [], []
    for _ in range(args.repeat):
        wall, results, grid = time_study(workers)
        walls.append(wall)
        solving.append(sum(r.solve_time_s for r in results) / workers)
        colds.extend(median_s(cold.solve, 1) for _ in range(2))
    wall, yardstick = statistics.median(walls), statistics.median(colds)
    print(f"Fig. 4 study: {grid.size} gaits in {len(grid.chains())} chains on {workers} worker processes, "
          f"median of {args.repeat}")
    print(f"  wall time {wall:6.2f} s = {wall / yardstick:5.1f} straightforward cold solves ({1e3 * yardstick:.1f} ms "
          f"each, this run)   per gait {1e3 * wall / grid.size:6.1f} ms (wall)")
    print(f"  solve time per gait in a worker: mean {1e3 * statistics.mean(r.solve_time_s for r in results):6.1f} ms, "
          f"median {1e3 * statistics.median(r.solve_time_s for r in results):6.1f} ms")
    print(f"  not solving (worker start-up, planners, results, the last chain alone): "
          f"{statistics.median(w - s for w, s in zip(walls, solving)):5.2f} s")


if __name__ == "__main__":
    main()
