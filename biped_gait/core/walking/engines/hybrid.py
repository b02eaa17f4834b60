"""The planner's own model as the walk's engine (``engine:=hybrid``, docs/model.md sections 8.2,
8.3): the ballistic single support by the planner's RK8 flow, one grid step h = T / grid per
call, and the touchdown guard located on each step's quintic Hermite interpolant (Brent's
method, 1e-14 s) and landed on by an exact RK8 step from the grid step's start; the tips a
``Held`` motion's chain holds (both feet: the closed chain; the stance tip alone: the single
support driven by joint torques), its joints driven by its law, by the classical RK4, one step h
per call (no touchdown located in it). The samples are the interpolant's at their instants, on each side of a push's
velocity jump its own. The contact forces are not measured: the phases give them by the model's
inverse dynamics.

Units SI, rad; times in the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...dynamics.flow import hermite_samples
from ...dynamics.hybrid import HybridStep, passive_impact
from .engine import Held, Motion


@dataclass
class HybridWorkspace:
    """The state being integrated: ``t`` s into the step, (``q``, ``qd``)."""

    t: float = 0.0
    q: np.ndarray | None = None
    qd: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class HybridSegment:
    """One RK8 step: its nodes (t in the step, q, qd, qdd at its start and end), where it ended
    (its end, or the touchdown), and whether the touchdown is in it."""

    nodes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    t: float
    touchdown: bool


def held_step(held: Held, t: float, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
              h: float) -> tuple[np.ndarray, np.ndarray]:
    """One classical RK4 step of ``h`` s of the chain of ``held``, its joints driven by its law at
    each stage, from (``q``, ``qd``) at ``t`` (s in the step) whose acceleration is ``qdd``."""
    rate = held.acceleration
    k1 = qd, qdd
    k2 = qd + h / 2 * k1[1], rate(t + h / 2, q + h / 2 * k1[0], qd + h / 2 * k1[1])
    k3 = qd + h / 2 * k2[1], rate(t + h / 2, q + h / 2 * k2[0], qd + h / 2 * k2[1])
    k4 = qd + h * k3[1], rate(t + h, q + h * k3[0], qd + h * k3[1])
    return (q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]),
            qd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))


class HybridEngine:
    """The engine of ``hybrid``'s model (module docstring): ballistic single supports, and phases
    whose tips a chain holds under a feedback law (a single support with torque pulses is refused)."""

    contact_friction = math.inf  # the planner's model holds the stance tip: its reaction is not checked

    def __init__(self, hybrid: HybridStep) -> None:
        self.hybrid = hybrid
        self.flow = hybrid.flow(1)  # one RK8 step per call: the runner's phases choose the grid

    def workspace(self) -> HybridWorkspace:
        return HybridWorkspace()

    def begin(self, ws: HybridWorkspace, motion: Motion, origin: float, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        if motion.pulses and motion.held is None:
            raise ValueError("the hybrid engine integrates the ballistic single support only: a phase with joint "
                             "torques needs the mujoco engine")
        ws.t, ws.q, ws.qd = t, q, qd

    def advance(self, ws: HybridWorkspace, motion: Motion, t_stop: float, touchdown_after: float) -> HybridSegment:
        h, t = motion.h, ws.t
        dt = t_stop - t if t < t_stop < t + h else h
        if motion.held is not None:
            qdd = motion.held.acceleration(t, ws.q, ws.qd)  # RK4's first stage and the segment's first node
            q, qd = held_step(motion.held, t, ws.q, ws.qd, qdd, dt)
            nodes = (np.array([t, t + dt]), np.array([ws.q, q]), np.array([ws.qd, qd]),
                     np.array([qdd, motion.held.acceleration(t + dt, q, qd)]))
            ws.t, ws.q, ws.qd = t + dt, q, qd
            return HybridSegment(nodes, ws.t, False)
        run = self.flow.propagate(ws.q, ws.qd, dt, keep_nodes=True)
        nodes = (run.nodes[0] + t, *run.nodes[1:])
        touchdown = self.hybrid.guard(touchdown_after).touchdown(nodes) if math.isfinite(touchdown_after) else None
        if touchdown is None:
            ws.t, ws.q, ws.qd = t + dt, run.q, run.qd
            return HybridSegment(nodes, ws.t, False)
        end = self.flow.propagate(nodes[1][0], nodes[2][0], touchdown - nodes[0][0])  # landed on from the step's start
        ws.t, ws.q, ws.qd = touchdown, end.q, end.qd
        return HybridSegment(nodes, touchdown, True)

    def state(self, ws: HybridWorkspace) -> tuple[np.ndarray, np.ndarray]:
        return ws.q, ws.qd

    def set_velocity(self, ws: HybridWorkspace, qd: np.ndarray) -> None:
        ws.qd = qd

    def sample(self, ws: HybridWorkspace, segments: list[HybridSegment], taus: list[float],
               jumps: list[float]) -> tuple[np.ndarray, np.ndarray, None]:
        """On the interpolant of the segments (each sample on the step whose closed interval holds
        it first), in one call."""
        # Each step's first node, and its last where a push made the velocity jump (both sides
        # kept: the interpolation on each side of the jump uses its own) and at the end.
        ends = [any(abs(segment.nodes[0][-1] - t) < 1e-12 for t in jumps) for segment in segments[:-1]] + [True]
        nodes = tuple(np.concatenate([part for segment, end in zip(segments, ends)
                                      for part in (segment.nodes[k][:1], segment.nodes[k][1:2 * end])])
                      for k in range(4))
        q, qd = hermite_samples(nodes, np.array(taus), side="left")
        return q, qd, None

    def passive_impact(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return self.hybrid.exchange.velocity(q, passive_impact(self.hybrid.impact(q), qd).xd_plus)
