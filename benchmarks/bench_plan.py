"""Benchmark: the first plan of a process against the next ones, beside the straightforward cold
solve (``yardsticks.ColdSolve``) measured in the same run.

Each of ``--processes`` fresh Python processes makes a ``GaitPlanner`` (default parameters, its
atlases) and plans ``--plans`` gaits from the atlas, each a new request of one family (L = T =
0.45, alpha 15 to 30 deg, normal mode), then the first request again; the first plan's time is
set beside the same request's second plan and the median of the others. The processes alternate with cold solves of the yardstick, so that a change of load falls
on both. The multipliers' share: the time a plan spends in ``GaitPlanner._multipliers`` (waiting
for the variational flow begun beside the double support, then the reset's derivative, the
saltation and the eigenvalues), and the variational flow alone (the work the background thread does).
The integration-error estimate's share: the time a plan spends in ``GaitPlanner._integration_error``
(its step solved again on the coarse grid, with its double support and samples). Run:

    .venv/bin/python benchmarks/bench_plan.py [--processes N] [--plans N]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import time

import results
from harness import Timed
from yardsticks import ColdSolve, median_s


def child(plans: int) -> None:
    """In a fresh process: the planner's making, its plans (the first request last again) (s), as JSON."""
    import biped_gait.core.gait.planner as planning
    from biped_gait.core.gait.stability import variational_flow

    start = time.perf_counter()
    planner = planning.GaitPlanner()
    made = time.perf_counter()
    in_multipliers = Timed(planner, "_multipliers")
    in_estimate = Timed(planner, "_integration_error")
    times, found = [], set()
    alphas = [math.radians(15.0 + 15.0 * k / max(1, plans - 1)) for k in range(plans)]
    for alpha in alphas + alphas[:1]:
        begin = time.perf_counter()
        gait = planner.plan(planning.GaitRequest(0.45, 0.45, alpha, "normal"))
        times.append(time.perf_counter() - begin)
        found.add(gait.found)
    flow = median_s(lambda: variational_flow(planner.flow, 0.45, gait.step.q0, gait.step.qd_a), 5)
    print(json.dumps({"make": made - start, "plans": times, "found": sorted(found), "multipliers": in_multipliers.calls[1:-1],
                      "estimate": in_estimate.calls[1:-1], "variational_flow": flow}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--processes", type=int, default=7)
    parser.add_argument("--plans", type=int, default=8)
    args = parser.parse_args()
    cold = ColdSolve()
    cold.solve()
    runs, colds = [], []
    for _ in range(args.processes):
        out = subprocess.run([sys.executable, __file__, "--child", str(args.plans)], check=True, capture_output=True,
                             text=True).stdout
        runs.append(json.loads(out))
        colds.append(median_s(cold.solve, 1))
    first = statistics.median(run["plans"][0] for run in runs)
    again = statistics.median(run["plans"][-1] for run in runs)
    warm = statistics.median(t for run in runs for t in run["plans"][1:-1])
    yardstick = statistics.median(colds)
    found = sorted({f for run in runs for f in run["found"]})
    print(f"plan from the atlas, L = T = 0.45, alpha 15..30 deg (normal), {args.processes} fresh processes of "
          f"{args.plans} plans each (found by {', '.join(found)}); medians:")
    print(f"  straightforward cold solve (yardstick): {1e3 * yardstick:7.1f} ms")
    print(f"  first plan of a process: {1e3 * first:7.2f} ms   the same request again: {1e3 * again:7.2f} ms   "
          f"first / again = {first / again:.2f}")
    print(f"  the other plans: {1e3 * warm:7.2f} ms   first / other = {first / warm:.2f}")
    print(f"  cold solve / first plan = {yardstick / first:.1f}   cold solve / next plan = {yardstick / warm:.1f}")
    print(f"  (before the first plan: making the planner with its atlases {1e3 * statistics.median(r['make'] for r in runs):.1f} ms)")
    multipliers = statistics.median(t for run in runs for t in run["multipliers"])
    flow = statistics.median(run["variational_flow"] for run in runs)
    print(f"  multipliers: {1e3 * multipliers:5.2f} ms of a plan's {1e3 * warm:5.2f} ms ({multipliers / warm:.0%}), "
          f"the wait for their flow included; beside the double support, their variational flow took {1e3 * flow:5.2f} ms of a second core")
    estimate = statistics.median(t for run in runs for t in run["estimate"])
    print(f"  integration-error estimate: {1e3 * estimate:5.2f} ms of a plan's {1e3 * warm:5.2f} ms ({estimate / warm:.0%})")
    results.write("bench_plan", {
        "cold solve": f"{1e3 * yardstick:.0f} ms", "plan from the atlas": f"{1e3 * warm:.1f} ms",
        "plan from the atlas, in cold solves": f"1/{yardstick / warm:.1f}", "first plan / the others": f"{first / warm:.2f}",
        "multipliers' share": f"{multipliers / warm:.0%}"},
        {"cold_solve_s": yardstick, "first_plan_s": first, "same_again_s": again, "other_plans_s": warm,
         "multipliers_s": multipliers, "estimate_s": estimate},
        {"processes": args.processes, "plans per process": args.plans, "requests": "L = T = 0.45, alpha 15 to 30 deg"})


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        child(int(sys.argv[2]))
    else:
        main()
