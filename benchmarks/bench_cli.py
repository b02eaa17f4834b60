"""Benchmark: the ``biped-gait`` command as a whole process beside the import floor (a Python that
only imports NumPy, SciPy, Pinocchio and highspy) measured in the same run: ``biped-gait plan``
(the default gait, from the atlas) and ``--help`` of every verb. The commands are run in turn,
``--repeat`` rounds, so that a change of load falls on all alike; medians. The processes may
write and use Python's bytecode cache (``PYTHONDONTWRITEBYTECODE`` is left out of their
environment), as a user's installation does after its first run. Run:

    .venv/bin/python benchmarks/bench_cli.py [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import results
from yardsticks import FLOOR_IMPORTS

ENVIRONMENT = {name: value for name, value in os.environ.items() if name != "PYTHONDONTWRITEBYTECODE"}
VERBS = ("plan", "urdf", "recover", "sweep", "optimize-arms", "figure", "maps", "push-study", "results-page", "atlas")


def wall_s(command: list[str]) -> float:
    """Wall time (s) of one run of ``command`` (its output discarded; it must succeed)."""
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENVIRONMENT)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    command = str(Path(sys.executable).with_name("biped-gait"))
    commands = {"import floor": [sys.executable, "-c", FLOOR_IMPORTS], "biped-gait plan": [command, "plan"]}
    commands.update({f"biped-gait {verb} --help": [command, verb, "--help"] for verb in VERBS})
    times: dict[str, list[float]] = {name: [] for name in commands}
    for name, argv in commands.items():  # warm-up: the files in the page cache
        wall_s(argv)
    for _ in range(args.repeat):
        for name, argv in commands.items():
            times[name].append(wall_s(argv))
    floor = statistics.median(times["import floor"])
    print(f"whole processes, median of {args.repeat} runs each, in turn:")
    for name, values in times.items():
        print(f"  {name:34s} {1e3 * statistics.median(values):7.0f} ms   {statistics.median(values) / floor:5.2f} x the floor")
    helps = [statistics.median(values) / floor for name, values in times.items() if name.endswith("--help")]
    plan = statistics.median(times["biped-gait plan"])
    results.write("bench_cli", {"import floor": f"{1e3 * floor:.0f} ms", "biped-gait plan": f"{1e3 * plan:.0f} ms",
                                "biped-gait plan / import floor": f"{plan / floor:.2f}",
                                "--help / import floor": f"{min(helps):.2f} to {max(helps):.2f}"},
                  {name: statistics.median(values) for name, values in times.items()}, {"repeat": args.repeat})


if __name__ == "__main__":
    main()
