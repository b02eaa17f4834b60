"""Benchmark: one full gait solve (BVP with theta closure + impulse LP + reports).

Prints the median cold time (no guess: straight-line start), the median warm time (guess from
the gait 1 deg of arm amplitude away, as in a sweep), the split between the shooting and the
rest, and the number of dynamics evaluations (ABA or ABA-derivative calls). Run:

    .venv/bin/python benchmarks/bench_gait.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from biped_gait.core.planner import GaitPlanner, GaitRequest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    planner = GaitPlanner()
    alphas = np.radians(np.linspace(15.0, 30.0, args.repeat))
    requests = [GaitRequest(0.45, 0.45, float(a), "normal") for a in alphas]
    planner.plan(requests[0])  # import and first-call costs out of the way

    cold, cold_evals = [], []
    for req in requests:
        start = time.perf_counter()
        result = planner.plan(req)
        cold.append(time.perf_counter() - start)
        cold_evals.append(result.step.evaluations)
        assert result.converged and result.admissible, result.reasons

    warm, warm_evals, iters = [], [], []
    previous = planner.plan(GaitRequest(0.45, 0.45, float(alphas[0] - math.radians(1.0)), "normal"))
    for req in requests:
        guess = (np.array(previous.qd_a), previous.theta)
        start = time.perf_counter()
        result = planner.plan(req, guess=guess)
        warm.append(time.perf_counter() - start)
        warm_evals.append(result.step.evaluations)
        iters.append(result.step.iterations)
        assert result.converged and result.admissible, result.reasons
        previous = result

    ms = lambda xs: 1e3 * statistics.median(xs)  # noqa: E731
    print(f"gait solve, L = T = 0.45, alpha 15..30 deg, {args.repeat} gaits, grid {planner.flow.steps} RK8 steps")
    print(f"  cold: median {ms(cold):7.2f} ms   dynamics evaluations {statistics.median(cold_evals):.0f}")
    print(f"  warm: median {ms(warm):7.2f} ms   dynamics evaluations {statistics.median(warm_evals):.0f}"
          f"   Newton iterations {statistics.median(iters):.0f}")


if __name__ == "__main__":
    main()
