"""Stability of a periodic gait: the Poincare map of the hybrid step and its Floquet multipliers
(docs/model.md section 8).

Section: just after the double support, the state x = (q, qd) (rad, rad/s, 2 nq numbers) of a
step's start in its own model coordinates. The open-loop map P(x): the ballistic flow from x until the
touchdown guard fires (swing-tip height w(q) = 0 at time tau(x)), then the double support with
the gait's joint impulses I-, I+ held fixed (eqs. 6-10 run forward), then the leg exchange.
The gait's start x* is a fixed point, P(x*) = x*.

Its Jacobian at x* composes, exactly: the flow's sensitivity Phi = d x(T) / d x(0) from the
variational equations (the BVP's RK8 grid), the guard's saltation (the touchdown time moves by
d tau = -(grad w . dq(T)) / (grad w . qd(T))), and the reset's derivative (linear in the
velocity; its configuration dependence through D_e, J1, J2 and the leg exchange differentiated
analytically, ``ImpactMap.reset_jacobian``). The multipliers are its eigenvalues; the gait is open-loop stable if all lie
inside the unit circle. One of the 2 nq is zero by construction (a perturbation along the flow
reaches the same touchdown: the guard removes it); the rest describe how a small perturbation
grows or decays from one step to the next.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dynamics.flow import BallisticFlow, FlowResult
from ..dynamics.hybrid import HybridStep


@dataclass(frozen=True, eq=False)
class Multipliers:
    """The Floquet multipliers of a gait's Poincare map (complex, by decreasing modulus), its
    spectral radius and whether it is below 1 (``stable``)."""

    values: np.ndarray
    jacobian: np.ndarray

    @property
    def spectral_radius(self) -> float:
        return float(np.max(np.abs(self.values)))

    @property
    def stable(self) -> bool:
        return self.spectral_radius < 1.0


def multipliers_of(jacobian: np.ndarray) -> Multipliers:
    """The multipliers (eigenvalues by decreasing modulus) of a Poincare map's Jacobian."""
    values = np.linalg.eigvals(jacobian)
    return Multipliers(values[np.argsort(-np.abs(values), kind="stable")], jacobian)


class PoincareMap:
    """The open-loop Poincare map of one gait: start (q0, qd0) (rad, rad/s), planned duration T
    (s), joint impulses I-, I+ (N m s), on ``flow``'s RK8 grid (steps per T)."""

    def __init__(self, hybrid: HybridStep, flow: BallisticFlow, period: float, i_minus: np.ndarray,
                 i_plus: np.ndarray) -> None:
        self.hybrid, self.flow, self.period = hybrid, flow, period
        self.i_minus, self.i_plus = np.asarray(i_minus, float), np.asarray(i_plus, float)

    def touchdown(self, q0: np.ndarray, qd0: np.ndarray, tol: float = 1e-13) -> tuple[float, np.ndarray, np.ndarray]:
        """The touchdown time tau (s) near T and the pre-impact state, by Newton's method on
        w(q(tau)) = 0 with the flow on a grid of ``flow.steps`` steps over tau."""
        tau = self.period
        for _ in range(20):
            run = self.flow.propagate(q0, qd0, tau)
            (height,), (rate,) = self.hybrid.samples.swing_tip_motion(run.q[None], run.qd[None])
            if abs(height) < tol:
                break
            tau -= height / rate
        return tau, run.q, run.qd

    def reset(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The next step's start (q', qd') from the pre-impact state, the impulses held fixed."""
        return np.concatenate([self.hybrid.exchange.configuration(q),
                               self.hybrid.impact(q).forward(qd, self.i_minus, self.i_plus)])

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """P(x): one step of the hybrid system from the start x = (q, qd) (2 nq,)."""
        n = self.hybrid.bm.nq
        _, q, qd = self.touchdown(x[:n], x[n:])
        return self.reset(q, qd)

    def jacobian(self, x: np.ndarray, run: FlowResult | None = None) -> np.ndarray:
        """dP/dx at the fixed point x (2 nq x 2 nq): variational flow, saltation, reset derivative.
        ``run``: the flow's ``variational_flow`` from x over T, if already integrated."""
        bm = self.hybrid.bm
        n = bm.nq
        if run is None:
            run = variational_flow(self.flow, self.period, x[:n], x[n:])
        q, qd, phi = run.q, run.qd, run.sens
        qdd = self.flow.acceleration(q, qd)
        grad = bm.tip_jacobians(q)[1][2, bm.ds_of_single]  # d w / d q (m/rad)
        dtau = -(grad @ phi[:n]) / (grad @ qd)  # d tau / d x (s per unit of x)
        pre = phi + np.outer(np.concatenate([qd, qdd]), dtau)  # d x(tau) / d x(0)
        return self.hybrid.impact(q).reset_jacobian(qd, self.i_minus, self.i_plus) @ pre


def variational_flow(flow: BallisticFlow, period: float, q0: np.ndarray, qd0: np.ndarray) -> FlowResult:
    """The flow from (q0, qd0) over ``period`` (s) with the sensitivity of the whole end state to
    the whole start state (2 nq x 2 nq): the Poincare map's flow part. On the compiled flow it
    runs without Python's lock, so a planner integrates it beside the double support."""
    return flow.propagate(q0, qd0, period, np.eye(2 * len(q0)))


def open_loop(hybrid: HybridStep, flow: BallisticFlow, period: float, q0: np.ndarray, qd0: np.ndarray,
              i_minus: np.ndarray, i_plus: np.ndarray, run: FlowResult | None = None) -> Multipliers:
    """The open-loop multipliers of the gait starting at (q0, qd0) with period T (s) and joint
    impulses I-, I+ (N m s); ``run``: its ``variational_flow``, if already integrated."""
    poincare = PoincareMap(hybrid, flow, period, i_minus, i_plus)
    return multipliers_of(poincare.jacobian(np.concatenate([q0, qd0]), run))


def closed_loop(walker_factory, x: np.ndarray, step: float = 1e-7) -> Multipliers:
    """The closed-loop multipliers: of the map the walker applies from a step's start (q, qd)
    to the next (the impulses re-solved from the actual state, the next step re-aimed), by
    central differences of steps walked from ``x`` (2 nq,) perturbed by ``step`` (rad, rad/s).
    ``walker_factory(q, qd)`` gives a walker whose current step starts there."""
    def step_map(state: np.ndarray) -> np.ndarray:
        n = len(state) // 2
        walker = walker_factory(state[:n], state[n:])
        outcome = walker.walk_step()
        if outcome.touchdown is None:
            raise ValueError(f"the closed loop fell from a perturbed start: {outcome.fall}")
        return np.concatenate([walker.state.q, walker.state.qd])

    jacobian = np.zeros((len(x), len(x)))
    for j in range(len(x)):
        e = np.zeros(len(x))
        e[j] = step
        jacobian[:, j] = (step_map(x + e) - step_map(x - e)) / (2 * step)
    return multipliers_of(jacobian)
