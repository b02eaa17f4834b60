"""The ballistic single support as a CasADi function, for the lasting double support's program.

``FlowFunction(flow, period)`` maps the step's start (q0, qd0) to its end [q(T); qd(T)] by the
planner's own shooting flow (``core/dynamics/flow.py``: RK8 on its fixed grid), and its Jacobian is
the flow's exact sensitivities (its variational equations, as the shooting's Newton uses). The
flow's second derivatives are not computed: IPOPT approximates the program's Hessian (limited
memory), its constraints and their Jacobian exact (``CoupledConstraints``).

A value and its Jacobian are kept for the last point asked, so that IPOPT's constraint and Jacobian
evaluations at one iterate integrate once.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..dynamics.flow import BallisticFlow


class _Evaluation:
    """The flow over ``period`` at the last (q0, qd0) asked, with its sensitivities once they were
    asked for (the period is part of what is kept: set it before asking)."""

    def __init__(self, flow: BallisticFlow, period: float) -> None:
        self.flow, self.period = flow, period
        self.key: bytes | None = None
        self.value: np.ndarray | None = None
        self.jacobian: np.ndarray | None = None

    def at(self, start: np.ndarray, with_jacobian: bool) -> None:
        key = start.tobytes() + np.float64(self.period).tobytes()
        if key == self.key and (self.jacobian is not None or not with_jacobian):
            return
        n = len(start) // 2
        seeds = np.eye(2 * n) if with_jacobian else None
        res = self.flow.propagate(start[:n], start[n:], self.period, seeds)
        self.key, self.value = key, np.concatenate([res.q, res.qd])
        self.jacobian = res.sens if with_jacobian else None


class _Dense(ca.Callback):
    """A function of one dense vector to one dense matrix, evaluated by ``value``."""

    def __init__(self, name: str, size: int, shape: tuple[int, int]) -> None:
        ca.Callback.__init__(self)
        self.size, self.shape = size, shape
        self.construct(name, {})

    def get_n_in(self):
        return 1

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self.size, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(*self.shape)

    def eval(self, arg):
        return [self.value(np.array(arg[0]).ravel())]


class _FlowJacobian(_Dense):
    """d [q(T); qd(T)] / d [q0; qd0] at the start [q0; qd0]."""

    def __init__(self, name: str, evaluation: _Evaluation, size: int) -> None:
        self.evaluation = evaluation
        super().__init__(name, size, (size, size))

    def value(self, start: np.ndarray) -> np.ndarray:
        self.evaluation.at(start, True)
        return self.evaluation.jacobian


class CoupledConstraints(ca.Callback):
    """g(w, p) = [inner(w, p); E w - flow(A w)]: a program's SX constraints and the ballistic
    flow's, with an exact sparse Jacobian built from the inner constraints' own (SX, sparse) and the
    flow's sensitivities (``A`` the constant map from the unknowns to the flow's start, ``E`` to
    the unknowns that hold the flow's end)."""

    def __init__(self, name: str, inner: ca.Function, flow: "FlowFunction", start_map: np.ndarray,
                 end_map: np.ndarray) -> None:
        ca.Callback.__init__(self)
        self.inner, self.flow = inner, flow
        self.start_map = ca.DM(ca.sparsify(ca.DM(start_map)))
        self.nw, self.np = inner.sparsity_in(0).size1(), inner.sparsity_in(1).size1()
        self.ng = inner.sparsity_out(0).size1() + flow.size
        w, p = ca.MX.sym("w", self.nw), ca.MX.sym("p", self.np)
        select = ca.DM(ca.sparsify(ca.DM(end_map)))
        coupling = ca.mtimes(select, w) - flow(ca.mtimes(self.start_map, w))
        self.whole = ca.Function("g", [w, p], [ca.vertcat(inner(w, p), coupling)])
        inner_jacobian = inner.jacobian()
        out = ca.MX.sym("out", self.ng)
        jac_inner = inner_jacobian(w, p, ca.MX(inner.sparsity_out(0).size1(), 1))[0]
        flow_jacobian = flow.jacobian_function(ca.mtimes(self.start_map, w))
        jac_coupling = select - ca.mtimes(flow_jacobian, self.start_map)
        self.jacobian_function = ca.Function("jac_g", [w, p, out],
                                             [ca.vertcat(jac_inner, jac_coupling), ca.MX(self.ng, self.np)])
        self.construct(name, {})

    def get_n_in(self):
        return 2

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self.nw if i == 0 else self.np, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(self.ng, 1)

    def eval(self, arg):
        return [self.whole(arg[0], arg[1])]

    def has_jacobian(self):
        return True

    def has_jac_sparsity(self, oind, iind):
        return True

    def get_jac_sparsity(self, oind, iind, symmetric):
        return self.jacobian_function.sparsity_out(iind)

    def get_jacobian(self, name, inames, onames, opts):
        w, p, out = ca.MX.sym("w", self.nw), ca.MX.sym("p", self.np), ca.MX.sym("out", self.ng)
        return ca.Function(name, [w, p, out], self.jacobian_function(w, p, out), inames, onames, opts)


class FlowFunction(_Dense):
    """[q0; qd0] -> [q(T); qd(T)] over the ballistic single support of ``period`` s on ``flow``'s
    grid (module docstring). Keep the object alive while a function built on it is used."""

    def __init__(self, name: str, flow: BallisticFlow, period: float, nq: int) -> None:
        self.evaluation = _Evaluation(flow, period)
        super().__init__(name, 2 * nq, (2 * nq, 1))
        self.jacobian_function = _FlowJacobian(name + "_jacobian", self.evaluation, self.size)

    def value(self, start: np.ndarray) -> np.ndarray:
        self.evaluation.at(start, False)
        return self.evaluation.value
