"""Benchmark: one full gait solve (BVP with theta closure + impulse LP + reports).

Prints the median cold time (``plan(cold=True)``: the straight-line start), the median warm time (guess from
the gait 1 deg of arm amplitude away, as in a sweep), the number of dynamics evaluations (ABA or
ABA-derivative calls), and the median times of two parts of a solve: the impulse LP (HiGHS
through highspy) and the step's figures (91 samples evaluated in one call, in the compiled twin
and by the Python loops); beside them the straightforward cold solve (``yardsticks.ColdSolve``)
of this run. Run:

    .venv/bin/python benchmarks/bench_gait.py [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from biped_gait.core.dynamics.flow import hermite_samples
from biped_gait.core.dynamics.impulses import solve_l1
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.gait.figures import energy_drift, step_figures
from biped_gait.core.dynamics.samples import NativeSamples, SampleEvaluator
from yardsticks import ColdSolve, median_s


def median_ms(call, repeat: int) -> float:
    """Median wall time (ms) of ``call()`` over ``repeat`` calls."""
    return 1e3 * median_s(call, repeat)


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
        result = planner.plan(req, cold=True)
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
    yardstick = median_ms(ColdSolve().solve, 5)
    print(f"gait solve, L = T = 0.45, alpha 15..30 deg, {args.repeat} gaits, grid {planner.flow.steps} RK8 steps; "
          f"the straightforward cold solve {yardstick:.1f} ms (this run): cold / warm = {yardstick / ms(warm):.1f}")
    print(f"  cold: median {ms(cold):7.2f} ms   dynamics evaluations {statistics.median(cold_evals):.0f}")
    print(f"  warm: median {ms(warm):7.2f} ms   dynamics evaluations {statistics.median(warm_evals):.0f}"
          f"   Newton iterations {statistics.median(iters):.0f}")

    gait = previous
    lp = planner.hybrid.impact(gait.step.q_target).problem(gait.step.qd_b, gait.step.qd_a)
    print(f"  impulse LP (HiGHS through highspy): median {median_ms(lambda: solve_l1(lp), 200):.3f} ms")
    times, (nodes_q, nodes_qd) = np.linspace(0.0, gait.period, planner.settings.samples), gait.step.nodes[1:3]
    for native in (True, False) if NativeSamples is not None else (False,):
        samples = SampleEvaluator(planner.model, native=native)

        def figures() -> None:  # what the planner does after the solve (GaitPlanner._figures)
            q, qd = hermite_samples(gait.step.nodes, times)
            step_figures(samples, times, q, qd, gait.period, energy_drift(samples, nodes_q, nodes_qd))

        where = "compiled twin" if native else "Python loops"
        print(f"  step figures ({times.size} samples, {where}): median {median_ms(figures, 100):.3f} ms")


if __name__ == "__main__":
    main()
