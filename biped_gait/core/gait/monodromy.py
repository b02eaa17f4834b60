"""The flow part of a gait's Poincare map, integrated on a thread of its own while the planner
solves the double support and the figures (docs/development.md, benchmarks).

Once the shooting has converged, the open-loop multipliers need the full-state variational flow
of the step (``stability.variational_flow``: the step again, with the sensitivity of its end
state to its whole start state) and the double support's impulses. The flow does not depend on
the impulses, and the compiled flow runs without Python's lock: started as soon as the step is
known, it is done, on a second core, by the time the impulse LP and the step figures are. The
results are those of integrating it in line, to the bit (it is the same computation on a flow
of its own).
"""

from __future__ import annotations

import os
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from ..dynamics.flow import BallisticFlow, FlowResult
from .stability import variational_flow


class BackgroundVariationalFlow:
    """Integrates ``stability.variational_flow`` on ``flow`` (a flow of its own: Pinocchio's data
    are not shared between threads) on one background thread, one step at a time."""

    def __init__(self, flow: BallisticFlow) -> None:
        self.flow = flow
        self._executor: ThreadPoolExecutor | None = None
        self._pid = -1

    def start(self, period: float, q0: np.ndarray, qd0: np.ndarray) -> Future[FlowResult]:
        """Begin the variational flow from (q0 rad, qd0 rad/s) over ``period`` (s); its result
        is the future's (integrated here and now once the interpreter is shutting down, when no
        thread may start)."""
        if self._executor is None or self._pid != os.getpid():  # a forked child has no thread of its parent's
            self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="variational-flow")
            self._pid = os.getpid()
        try:
            return self._executor.submit(variational_flow, self.flow, period, np.array(q0), np.array(qd0))
        except RuntimeError:  # "cannot schedule new futures after (interpreter) shutdown"
            done: Future[FlowResult] = Future()
            done.set_result(variational_flow(self.flow, period, q0, qd0))
            return done
