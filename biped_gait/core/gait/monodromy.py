"""The flow part of a gait's Poincare map, integrated on a thread of its own while the planner
solves the double support and the figures (docs/development.md, benchmarks).

Once the shooting has converged, the open-loop multipliers need the full-state variational flow
of the step (``stability.variational_flow``: the step again, with the sensitivity of its end
state to its whole start state) and the double support's impulses. The flow does not depend on
the impulses, and the compiled flow runs without Python's lock: started as soon as the step is
known, it is done, on a second core, by the time the impulse LP and the step figures are. The
results are those of integrating it in line, to the bit (it is the same computation on a flow
of its own).

It begins earlier still: the shooting ends with the chord step on the fine grid that reaches the
tolerance, as a rule the one after the coarse solution's; ``SpeculativeFlow``, the fine flow of
one solve, begins the variational flow from each chord step's start after the first, so that it
runs beside that step's own flow and is nearly done when the shooting returns. A step that turns
out not to be the last wastes its variational flow (the next waits for it): the planner then
still gets the right one, begun from the shooting's end.
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


class SpeculativeFlow:
    """The fine flow of one shooting solve (``bvp.solve_bvp``'s ``flow``): propagates as ``flow``
    does, and begins the variational flow on ``background`` from the start of each chord step
    after the first (a propagation with the nodes kept and no sensitivity: the shooting's fine
    residual), the step most likely to be the shooting's last."""

    def __init__(self, flow: BallisticFlow, background: BackgroundVariationalFlow) -> None:
        self._flow, self._background = flow, background
        self._chord_steps = 0
        self._begun: tuple[float, bytes, bytes, Future[FlowResult]] | None = None

    def __getattr__(self, name: str):  # the wrapped flow's grid and acceleration
        return getattr(self._flow, name)

    def propagate(self, q0: np.ndarray, qd0: np.ndarray, duration: float, seeds: np.ndarray | None = None,
                  keep_nodes: bool = False) -> FlowResult:
        """``BallisticFlow.propagate``; a chord step's also begins its variational flow."""
        if seeds is None and keep_nodes:
            self._chord_steps += 1
            if self._chord_steps > 1:  # the background flow copies the state it is given
                self._begun = (duration, _bits(q0), _bits(qd0), self._background.start(duration, q0, qd0))
        return self._flow.propagate(q0, qd0, duration, seeds, keep_nodes)

    def variational_flow(self, period: float, q0: np.ndarray, qd0: np.ndarray) -> Future[FlowResult]:
        """The variational flow from (q0 rad, qd0 rad/s) over ``period`` (s): the one begun at a
        chord step from that very state (to the bit), else one begun now."""
        if self._begun is not None:
            duration, q, qd, future = self._begun
            if duration == period and q == _bits(q0) and qd == _bits(qd0):
                return future
        return self._background.start(period, q0, qd0)


def _bits(state: np.ndarray) -> bytes:
    """A state's float64 bytes: two states are the same to the bit when these are."""
    return np.asarray(state, float).tobytes()
