"""The benchmarks' results kept in the repository: each benchmark that the README quotes writes its
figures to ``benchmarks/results/<benchmark>.json`` with when, where and on which code it ran (the
date in UTC, the machine: CPU model, cores, Python, and the commit the benchmark started on,
``+dirty`` when the code that runs had changes: ``CODE``; the machine's load averages over 1, 5
and 15 minutes when it started and when it wrote, for a shared machine's figures move with them). The figures the README and docs quote are the ``quoted`` texts of these files,
as the benchmark formatted them (``tests/test_readme_figures.py`` checks each quoted figure is
there); ``figures`` keeps the raw medians (s, or ratios) beside them."""

from __future__ import annotations

import json
import os
import platform
import subprocess
from datetime import datetime, timezone
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
ROOT = RESULTS.parent.parent
CODE = ("biped_gait", "benchmarks", "msg_defs", "setup.py", "setup.cfg", "pyproject.toml", "requirements.txt")
"""What runs: a change elsewhere (docs, tests) leaves a run's commit clean."""


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _commit() -> str:
    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=True).stdout.strip()

    try:
        head = git("rev-parse", "--short=12", "HEAD")
        changed = [line for line in git("status", "--porcelain", "--", *CODE).splitlines()
                   if "benchmarks/results/" not in line]
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if changed else "")


COMMIT = _commit()  # the code that runs: taken when the benchmark starts
LOAD = os.getloadavg()  # the load when the benchmark starts


def write(name: str, quoted: dict[str, str], figures: dict[str, float], conditions: dict[str, object]) -> Path:
    """Write ``results/<name>.json``: the ``quoted`` texts (what the docs may quote, by key), the
    raw ``figures``, the run's ``conditions`` (counts, rates, workers) and where and when it ran."""
    RESULTS.mkdir(exist_ok=True)
    record = {
        "benchmark": f"benchmarks/{name}.py",
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": {"cpu": _cpu(), "cores": os.cpu_count(), "python": platform.python_version(),
                    "system": f"{platform.system()} {platform.release()}"},
        "commit": COMMIT,
        "load average (1, 5, 15 min)": {"at start": [round(x, 2) for x in LOAD],
                                         "at end": [round(x, 2) for x in os.getloadavg()]},
        "conditions": conditions,
        "quoted": quoted,
        "figures": figures,
    }
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps(record, indent=2) + "\n")
    print(f"results written to {path.relative_to(ROOT)}")
    return path
