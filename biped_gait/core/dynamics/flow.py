"""The ballistic flow of the single-support model, D(q) qdd + C(q, qd) + G(q) = 0 (paper eq. 3).

Integrated with the 12-stage, 8th-order Runge-Kutta scheme of Dormand and Prince (the
DOP853 tableau, ``rk8_tableau``) on a fixed grid of steps. A fixed grid makes the computed
end state a smooth function of the initial state, so the variational equations integrated by
the same scheme give the *exact* derivative of the computed flow map: Newton's method on it
converges quadratically to rounding level. Accuracy of the grid itself is checked against
SciPy's adaptive DOP853 and by energy conservation (tests).

Accelerations come from Pinocchio's ABA; the variational equations use its analytical ABA
derivatives (d qdd / d q, d qdd / d qd). Units: rad, rad/s, rad/s^2, s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import rk8_tableau

try:
    from ._flow_native import NativeFlow
except ImportError:  # not built (no compiler): the Python loop serves
    NativeFlow = None

_STAGES = rk8_tableau.STAGES
_A = rk8_tableau.A
_B = rk8_tableau.B


@dataclass
class FlowResult:
    """End state of a flow, and optionally its sensitivity to chosen initial perturbations.

    ``sens`` is 18 x k: d[q(T); qd(T)] / d(seed), for the k seed columns given at t = 0.
    ``nodes`` holds [t, q, qd, qdd] at every grid node when the trajectory was requested.
    """

    q: np.ndarray
    qd: np.ndarray
    sens: np.ndarray | None
    evaluations: int
    nodes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None


class BallisticFlow:
    """Fixed-grid RK8 integrator of the unactuated single-support dynamics, with sensitivities.

    ``native``: run the grid in the compiled twin (core/dynamics/native/flow.cpp, same scheme and
    same Pinocchio algorithms, built by tools/setup.sh) - None: when it is built; False: the
    Python loop below. Both give the same results to rounding (tests/test_flow.py).
    """

    def __init__(self, model: pin.Model, steps: int, native: bool | None = None) -> None:
        if steps < 1:
            raise ValueError(f"steps must be at least 1, got {steps}")
        self.model = model
        self.data = model.createData()
        self.steps = steps
        self.nq = model.nq
        self._tau = np.zeros(model.nv)
        if native is None:
            native = NativeFlow is not None
        if native and NativeFlow is None:
            raise ValueError("the compiled flow is not built: run tools/setup.sh")
        self.native = NativeFlow(model.saveToString(), np.ascontiguousarray(_A), _B, steps) if native else None

    def acceleration(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """qdd (rad/s^2) of the ballistic dynamics at (q, qd), by ABA."""
        return pin.aba(self.model, self.data, q, qd, self._tau).copy()

    def propagate(
        self,
        q0: np.ndarray,
        qd0: np.ndarray,
        duration: float,
        seeds: np.ndarray | None = None,
        keep_nodes: bool = False,
    ) -> FlowResult:
        """Integrate from (q0, qd0) over ``duration`` (s).

        ``seeds`` (18 x k) are initial variations [dq0; dqd0]; their images at the end are
        returned in ``FlowResult.sens``. ``keep_nodes`` also returns the state at every node.
        """
        if self.native is not None:
            q, qd, sens, evaluations, nodes = self.native.propagate(q0, qd0, duration, seeds, keep_nodes)
            if nodes is not None:
                nodes = (np.linspace(0.0, duration, self.steps + 1), *nodes)
            return FlowResult(q, qd, sens, evaluations, nodes)
        n = self.nq
        k = 0 if seeds is None else seeds.shape[1]
        cols = 1 + k
        # z holds [[q, Sq], [qd, Sv]] (18 x cols), flattened row-major; stages likewise.
        z = np.empty((2 * n, cols))
        z[:n, 0], z[n:, 0] = q0, qd0
        if k:
            z[:, 1:] = seeds
        z = z.ravel()
        size = z.size
        stages = np.empty((_STAGES, size))
        h = duration / self.steps
        a_h = _A * h
        b_h = _B * h
        split = n * cols
        model, data, tau = self.model, self.data, self._tau
        if keep_nodes:
            nodes_q = np.empty((self.steps + 1, n))
            nodes_qd = np.empty((self.steps + 1, n))
            nodes_qdd = np.empty((self.steps + 1, n))
        for step in range(self.steps):
            y = z
            for i in range(_STAGES):
                if i:
                    y = z + a_h[i, :i] @ stages[:i]
                out = stages[i].reshape(2 * n, cols)
                state = y.reshape(2 * n, cols)
                out[:n] = state[n:]
                if k:
                    ddq_dq, ddq_dv, _ = pin.computeABADerivatives(model, data, state[:n, 0], state[n:, 0], tau)
                    out[n:, 0] = data.ddq
                    out[n:, 1:] = ddq_dq @ state[:n, 1:] + ddq_dv @ state[n:, 1:]
                else:
                    out[n:, 0] = pin.aba(model, data, state[:n, 0], state[n:, 0], tau)
            if keep_nodes:
                state = z.reshape(2 * n, cols)
                nodes_q[step], nodes_qd[step] = state[:n, 0], state[n:, 0]
                nodes_qdd[step] = stages[0][split:].reshape(n, cols)[:, 0]
            z = z + b_h @ stages
        state = z.reshape(2 * n, cols)
        evaluations = self.steps * _STAGES
        nodes = None
        if keep_nodes:
            nodes_q[-1], nodes_qd[-1] = state[:n, 0], state[n:, 0]
            nodes_qdd[-1] = self.acceleration(state[:n, 0], state[n:, 0])
            evaluations += 1
            nodes = (np.linspace(0.0, duration, self.steps + 1), nodes_q, nodes_qd, nodes_qdd)
        return FlowResult(
            state[:n, 0].copy(), state[n:, 0].copy(), state[:, 1:].copy() if k else None, evaluations, nodes
        )


def hermite_samples(
    nodes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], times: np.ndarray, side: str = "right"
) -> tuple[np.ndarray, np.ndarray]:
    """q and qd at ``times`` by quintic Hermite interpolation of the nodes' (q, qd, qdd).

    The interpolant is of 6th order in the node spacing, far below the tolerances of the
    a-posteriori checks it serves (ground reaction, swing-tip height). A time at an inner node
    is interpolated on the interval that starts there (``side`` "right") or ends there ("left").
    """
    t, q, qd, qdd = nodes
    idx = np.clip(np.searchsorted(t, times, side=side) - 1, 0, len(t) - 2)
    h = (t[idx + 1] - t[idx])[:, None]
    s = ((times - t[idx]) / h[:, 0])[:, None]
    q0, q1 = q[idx], q[idx + 1]
    v0, v1 = qd[idx] * h, qd[idx + 1] * h
    a0, a1 = qdd[idx] * h**2, qdd[idx + 1] * h**2
    # Quintic Hermite basis on s in [0, 1] and its derivative.
    s2, s3, s4, s5 = s**2, s**3, s**4, s**5
    h00 = 1 - 10 * s3 + 15 * s4 - 6 * s5
    h01 = 10 * s3 - 15 * s4 + 6 * s5
    h10 = s - 6 * s3 + 8 * s4 - 3 * s5
    h11 = -4 * s3 + 7 * s4 - 3 * s5
    h20 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5
    h21 = 0.5 * s3 - s4 + 0.5 * s5
    d00 = -30 * s2 + 60 * s3 - 30 * s4
    d10 = 1 - 18 * s2 + 32 * s3 - 15 * s4
    d11 = -12 * s2 + 28 * s3 - 15 * s4
    d20 = s - 4.5 * s2 + 6 * s3 - 2.5 * s4
    d21 = 1.5 * s2 - 4 * s3 + 2.5 * s4
    q_s = h00 * q0 + h01 * q1 + h10 * v0 + h11 * v1 + h20 * a0 + h21 * a1
    qd_s = (d00 * (q0 - q1) + d10 * v0 + d11 * v1 + d20 * a0 + d21 * a1) / h
    return q_s, qd_s
