"""Where studies run: local worker processes (default) or a Dask distributed cluster, behind
the ``concurrent.futures.Executor`` interface, and the one planner each worker thread keeps.

Work is sent as plain picklable arguments (``BipedParams``, floats, strings); each worker
thread builds a ``GaitPlanner`` for a parameter set the first time it sees it and reuses it
(Pinocchio data are not thread-safe, so never shared between threads).

Local workers are forked from a server process (``forkserver``, Python 3.14's default on Linux)
that has imported the planner and started no thread, never from the command itself: a process
forked from one with threads (the executor's own, tqdm's monitor, the linear algebra's) can inherit
a lock held by one of them and wait on it forever, and did (a CI run's sweep, both workers idle for
200 s, at b387fa8).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import threading
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager

from ..core.gait.planner import GaitPlanner
from ..core.model.params import BipedParams

_local = threading.local()


def planner_for(params: BipedParams) -> GaitPlanner:
    """This thread's planner for ``params`` (built on first use, then reused)."""
    planners = getattr(_local, "planners", None)
    if planners is None:
        planners = _local.planners = {}
    if params not in planners:
        planners[params] = GaitPlanner(params)
    return planners[params]


def _ignore_sigint() -> None:
    """Worker initializer: Ctrl-C is the parent's to handle (it keeps what is computed)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def available_cpus() -> int:
    """CPUs this process may run on (its affinity, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_workers(workers: int | None) -> int:
    """Number of local worker processes: ``None`` means one per CPU; more than the CPUs is
    capped to them (one line on stderr says so); raises ``ValueError`` for a count below one."""
    cpus = available_cpus()
    if workers is None:
        return cpus
    if workers < 1:
        raise ValueError(f"the number of workers must be at least 1, got {workers}")
    if workers > cpus:
        print(f"note: {workers} worker processes asked for, capped to the {cpus} CPUs available", file=sys.stderr)
        return cpus
    return workers


@contextmanager
def open_executor(workers: int | None = None, scheduler: str | None = None) -> Iterator[Executor]:
    """An executor for studies: ``scheduler`` (a Dask scheduler address such as
    ``tcp://127.0.0.1:8786``) runs the work on that cluster, otherwise ``workers`` local
    processes (default: one per core) do.

    On leaving, work not yet started is cancelled; local processes finish the task they hold.
    Raises ``ValueError`` if the scheduler cannot be reached (within Dask's configured
    ``distributed.comm.timeouts.connect``, 30 s by default) or ``workers`` is below one.
    """
    if scheduler:
        from distributed import Client  # imported only when a cluster is asked for

        try:
            client = Client(scheduler)  # connect timeout: Dask's distributed.comm.timeouts.connect
        except (OSError, TimeoutError) as exc:
            raise ValueError(f"cannot connect to the Dask scheduler at {scheduler}: {exc}") from None
        executor = client.get_executor(pure=False)
        try:
            yield executor
        finally:
            executor.shutdown(wait=False)
            client.close()
    else:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload([__name__])  # the planner imported once, in the server
        pool = ProcessPoolExecutor(max_workers=check_workers(workers), mp_context=context, initializer=_ignore_sigint)
        try:
            yield pool
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
