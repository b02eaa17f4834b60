"""The sweep on a Dask distributed cluster (``--scheduler``) gives the same gaits as local
worker processes. The cluster is started here, on 127.0.0.1 only, and stopped after."""

from __future__ import annotations

import json
import os
import subprocess

import pytest

from .test_cli import ENTRY, run

pytestmark = pytest.mark.studies

distributed = pytest.importorskip("distributed")

# Volatile figures: wall time of each solve.
VOLATILE = {"solve_time_s"}
# 8 gaits, 4 chains (one per period and mode, along alpha); the 4 at T = 1.5 s fail (6.6 to 9.4 s each,
# measured 2026-12-06).
SWEEP = ["sweep", "--step-length", "0.45", "--period", "0.45", "1.5", "--alpha-deg", "0", "30", "--mode", "normal",
         "anti-normal"]


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        host="127.0.0.1", n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as local_cluster:
        assert all(address.startswith("tcp://127.0.0.1:") for address in local_cluster.scheduler.workers)
        yield local_cluster


def cases(out) -> list[dict]:
    document = json.loads((out / "sweep.json").read_text())
    assert document["complete"]
    return [{k: v for k, v in case.items() if k not in VOLATILE} for case in document["cases"]]


@pytest.mark.timeout(300)
def test_sweep_on_a_dask_cluster_equals_local_processes(tmp_path, cluster):
    on_cluster = run(*SWEEP, "--out", str(tmp_path / "dask"), "--scheduler", cluster.scheduler_address)
    assert on_cluster.returncode == 0, on_cluster.stderr
    local = run(*SWEEP, "--out", str(tmp_path / "local"), "--workers", "2")
    assert local.returncode == 0, local.stderr
    # The chains ran as tasks on the cluster's workers (the scheduler timed them).
    assert cluster.scheduler.task_prefixes["run_chain"].max_exec_time > 0
    dask_cases, local_cases = cases(tmp_path / "dask"), cases(tmp_path / "local")
    assert len(dask_cases) == 8 and sum(not c["converged"] for c in dask_cases) == 4  # T = 1.5 s fails, kept
    assert dask_cases == local_cases  # the same floating-point figures, bit for bit
    assert (tmp_path / "dask" / "sweep.csv").read_text().count("\n") == 9


def test_unreachable_scheduler_is_a_one_line_error(tmp_path):
    env = os.environ | {"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"}  # Dask's own setting, shortened
    proc = subprocess.run([ENTRY, *SWEEP, "--out", str(tmp_path / "x"), "--scheduler", "tcp://127.0.0.1:9"],
                          capture_output=True, text=True, timeout=60, env=env)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "cannot connect to the Dask scheduler at tcp://127.0.0.1:9" in lines[0]
