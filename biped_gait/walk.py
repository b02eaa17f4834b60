"""Walking a planned gait step after step (pure core of the simulator node).

Each step integrates the ballistic dynamics from the actual state with the fixed-grid RK8
flow, detects the swing foot's touchdown as an event (its tip height crossing zero downward,
located on the quintic Hermite interpolant and landed on by an exact RK8 step), applies the
double support with impulses recomputed by the core's LP from the actual pre-impact state
towards the plan's post-impact velocity, and exchanges the legs (spec section 5).

Off the planned orbit that velocity is not exactly reachable: the angular momentum about the
foot-to-foot line is conserved through the double support. Aiming at the nearest reachable
velocity (the plan's plus s z_d, z_d the locked rotation) is not enough to walk: the ballistic
gait is open-loop unstable (a touchdown error grows about 150-fold per step), so by default
(``reaim=True``) the walker re-aims each step: it re-solves the step's boundary-value problem
from the actual configuration after the leg exchange to the planned touchdown configuration
(trunk pitch theta free), under the current impact's momentum closure, so that the target is
exactly reachable and the next touchdown lands on the plan. It reports |s| for the plan's own
velocity as the miss, and how far the re-aimed velocity is from the plan's. Everything is in the model's coordinates (stance leg 1 on the right);
``stance_side`` says which physical foot that is, and ``stance_foot`` where it is in the world
(m). Units SI, radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from pinocchio import forwardKinematics
from scipy.optimize import brentq

from .boundary import P_INVERSE, P_MATRIX, mirror_for
from .bvp import impact_problem, next_step_velocity
from .flow import BallisticFlow, hermite_samples
from .impulses import solve_impulses
from .model import BipedModel
from .reports import ground_reaction_inverse_dynamics
from .result import GaitResult



class Fall(Exception):
    """The robot fell, or its next step cannot be made: the message says why."""


@dataclass
class Sample:
    """The state at one publishing instant: time in the walk (s) and in the step, q, qd, and the
    ground reaction [Fx, Fy, Fz, Mz] at the stance tip (N, N m)."""

    t: float
    t_step: float
    q: np.ndarray
    qd: np.ndarray
    grf: np.ndarray


@dataclass
class Touchdown:
    """The end of one step: when, the double support applied, and the distance to the plan."""

    step: int
    t: float  # time in the walk (s)
    t_step: float  # duration of the step (s)
    i_minus: np.ndarray
    i_plus: np.ndarray
    W: float
    state_error: float  # max |(q, qd) at touchdown - the plan's (q_T, qd_b)| (rad, rad/s)
    velocity_miss: float  # |s|: how far the plan's post-impact velocity is from reachable (rad/s)
    correction: float  # max |re-aimed post-impact velocity - the plan's| (rad/s), 0 without re-aiming
    equation_residual: float


@dataclass
class StepOutcome:
    """One step: its samples, and its touchdown or the reason the robot fell."""

    samples: list[Sample]
    touchdown: Touchdown | None
    fall: str = ""


@dataclass
class WalkState:
    """Where the walker is: the model state at the start of the current step, which physical
    foot is the stance foot, and that foot's world position (m)."""

    q: np.ndarray
    qd: np.ndarray
    step: int = 0
    t: float = 0.0
    stance_side: str = "right"
    stance_foot: np.ndarray = field(default_factory=lambda: np.array([0.0, -0.2, 0.0]))


class Walker:
    """Walks the gait of ``plan`` (a converged GaitResult) with ``bm``'s dynamics."""

    def __init__(
        self, bm: BipedModel, plan: GaitResult, rate: float, grid: int = 32, effort: str = "l1", reaim: bool = True
    ) -> None:
        """``rate``: samples per second of simulated time; ``grid``: RK8 steps per period T;
        ``reaim``: re-solve each step's BVP from the actual state (else aim at the plan's velocity)."""
        if not plan.converged:
            raise ValueError("cannot walk a plan that did not converge")
        if not rate > 0:
            raise ValueError(f"publishing rate must be positive, got {rate}")
        self.bm, self.plan, self.rate, self.effort = bm, plan, rate, effort
        self.period = plan.period
        self.grid = grid
        self.flow = BallisticFlow(bm.single, 1)  # one RK8 step per call: the walker owns the grid
        self.q_t, self.qd_b = np.array(plan.qT), np.array(plan.qd_b)
        self.qd_a = np.array(plan.qd_a)
        self.state = WalkState(np.array(plan.q0), np.array(plan.qd_a),
                               stance_foot=np.array([0.0, -bm.params.hip_half_width, 0.0]))
        self.reaim = reaim
        self.sample_index = 0  # the next sample is at sample_index / rate in the walk (s)
        self.step_flow = BallisticFlow(bm.single, grid)
        self.next_period = plan.period
        if reaim:
            # d q(T) / d qd(0) on the planned orbit: the chord Jacobian of every re-aim.
            seeds = np.vstack([np.zeros((9, 9)), np.eye(9)])
            self._phi_qv = self.step_flow.propagate(self.state.q, self.qd_a, self.period, seeds).sens[:9]

    def shove(self, delta_qd: np.ndarray) -> None:
        """Add ``delta_qd`` (rad/s, model coordinates) to the velocity the current step starts with."""
        self.state.qd = self.state.qd + np.asarray(delta_qd, float)

    def swing_height(self, q: np.ndarray) -> float:
        """Height (m) of the swing-foot tip."""
        return float(self.bm.swing_tip(q)[2])

    def _lowest_link(self, q: np.ndarray) -> float:
        """Height (m) of the lowest joint or hand other than the two feet."""
        model, data = self.bm.single, self.bm.single_data
        forwardKinematics(model, data, q)
        heights = [data.oMi[j].translation[2] for j in range(3, model.njoints)]  # knee and above
        arm = self.bm.params.arm.length
        for name in ("stance_side_shoulder", "swing_side_shoulder"):
            heights.append(data.oMi[model.getJointId(name)].act(np.array([0.0, 0.0, -arm]))[2])
        return float(min(heights))

    def walk_step(self) -> StepOutcome:
        """Integrate the current step until touchdown (or a fall) and apply the double support."""
        s = self.state
        h = self.period / self.grid
        t_step, q, qd = 0.0, s.q, s.qd
        samples: list[Sample] = []
        limit = 2.0 * self.period
        while t_step < limit:
            run = self.flow.propagate(q, qd, h, keep_nodes=True)
            nodes = (run.nodes[0] + t_step, *run.nodes[1:])
            height_end = self.swing_height(run.q)
            landed = t_step + h > 0.5 * self.period and height_end <= 0.0
            t_end = t_step + h
            if landed:
                t_end = self._touchdown_time(nodes)
            # Samples at the instants k / rate of the walk that fall in [start, touchdown): the
            # touchdown instant itself opens the next step (post-impact state).
            taus = []
            while (tau := (self.sample_index + len(taus)) / self.rate - s.t) < t_end - 1e-12 or (
                not landed and tau <= t_end
            ):
                taus.append(tau)
            if taus:
                sq, sqd = hermite_samples(nodes, np.array(taus))
                for tau, q_s, qd_s in zip(taus, sq, sqd):
                    sample = self._sample(s.t + tau, tau, q_s, qd_s)
                    samples.append(sample)
                    self.sample_index += 1
                    fall = self._fall(sample)
                    if fall:
                        return StepOutcome(samples, None, fall)
            if landed:
                end = self.flow.propagate(q, qd, t_end - t_step)
                try:
                    return StepOutcome(samples, self._double_support(end.q, end.qd, t_end))
                except Fall as fall:
                    return StepOutcome(samples, None, str(fall))
            t_step, q, qd = t_end, run.q, run.qd
        return StepOutcome(samples, None, f"the swing foot did not land within 2 T = {limit:.3f} s")

    def _touchdown_time(self, nodes) -> float:
        """Time in the step (s) where the swing tip's height crosses zero, on the interpolant."""
        t0, t1 = nodes[0][0], nodes[0][-1]

        def height(t: float) -> float:
            q, _ = hermite_samples(nodes, np.array([t]))
            return self.swing_height(q[0])

        if height(t0) <= 0.0:  # already touching at the start of this grid step
            return t0
        return brentq(height, t0, t1, xtol=1e-14, rtol=1e-14)

    def _sample(self, t: float, t_step: float, q: np.ndarray, qd: np.ndarray) -> Sample:
        qdd = self.flow.acceleration(q, qd)
        return Sample(t, t_step, q, qd, ground_reaction_inverse_dynamics(self.bm, q, qd, qdd))

    def _fall(self, sample: Sample) -> str:
        if not sample.grf[2] > 0.0:
            return f"vertical ground reaction not positive ({sample.grf[2]:.3g} N) at t = {sample.t:.4f} s"
        if sample.t_step > 0.05 * self.period and self._lowest_link(sample.q) < 0.0:
            return f"a link went below the ground at t = {sample.t:.4f} s"
        return ""

    def _double_support(self, q_td: np.ndarray, qd_td: np.ndarray, t_step: float) -> Touchdown:
        """Impulses from the actual pre-impact state towards the plan, then the leg exchange."""
        bm, s = self.bm, self.state
        planned = impact_problem(bm, q_td, qd_td, self.qd_a)
        reachable, miss = planned.reachable()
        if self.reaim:
            momentum_row = planned.locked_rotation @ planned.mass_matrix
            qd_next = self._reaim(P_MATRIX @ q_td, momentum_row, planned.xd_b, q_td)
            problem = replace(planned, xd_a=next_step_velocity(bm, q_td, qd_next))
        else:
            problem = reachable
        xd_a = problem.xd_a
        if not np.all(np.isfinite(xd_a)):
            raise Fall(f"no reachable velocity after the touchdown at t = {s.t + t_step:.4f} s")
        sol = solve_impulses(problem, self.effort)
        if not sol.success:
            raise Fall(f"the double support at t = {s.t + t_step:.4f} s has no solution ({sol.message})")
        error = max(float(np.max(np.abs(q_td - self.q_t))), float(np.max(np.abs(qd_td - self.qd_b))))
        touchdown = Touchdown(
            step=s.step, t=s.t + t_step, t_step=t_step, i_minus=sol.i_minus.copy(), i_plus=sol.i_plus.copy(),
            W=sol.W, state_error=error, velocity_miss=abs(miss),
            correction=float(np.max(np.abs(xd_a[3:] - planned.xd_a[3:]))), equation_residual=sol.equation_residual,
        )
        # The new stance foot's world position, then the mirror: the next step in model coordinates.
        tip = bm.swing_tip(q_td)
        new_foot = s.stance_foot + mirror_for(s.stance_side) @ tip
        new_foot[2] = 0.0
        self.state = WalkState(
            q=P_MATRIX @ q_td,
            qd=P_MATRIX @ xd_a[3:],
            step=s.step + 1,
            t=s.t + t_step,
            stance_side="left" if s.stance_side == "right" else "right",
            stance_foot=new_foot,
        )
        return touchdown

    def _reaim(self, q_start: np.ndarray, momentum_row: np.ndarray, xd_b: np.ndarray, q_td: np.ndarray) -> np.ndarray:
        """The next step's initial velocity (its own coordinates) and duration: the flow from
        ``q_start`` reaches the planned touchdown configuration q_T exactly, and the velocity
        is reachable through this double support (momentum about the feet line kept). The
        step's duration is the free tenth unknown: the one quantity the impulses cannot set,
        that momentum, is regulated by how long gravity acts on it.

        Chord iterations with the planned orbit's Jacobian: off the orbit by a numerical
        error only, they converge to rounding level in one or two steps.
        """
        bm = self.bm
        j2 = bm.tip_jacobians(q_td)[1]
        gain = (momentum_row[3:] - momentum_row[:3] @ j2[:, 3:]) @ P_INVERSE  # d(momentum)/d(qd_next)
        target_momentum = float(momentum_row @ xd_b)
        jac = np.zeros((10, 10))
        jac[:9, :9], jac[:9, 9], jac[9, :9] = self._phi_qv, self.qd_b, gain
        v, duration = self.qd_a.copy(), self.next_period
        for _ in range(8):
            with np.errstate(over="ignore", invalid="ignore"):
                run = self.step_flow.propagate(q_start, v, duration)
            residual = np.append(run.q - self.q_t, gain @ v - target_momentum)
            if np.max(np.abs(residual)) < 1e-12:
                break
            if not np.all(np.isfinite(residual)) or not duration > 0:
                raise Fall("re-aiming the next step diverged: the state is too far from the plan")
            delta = np.linalg.solve(jac, -residual)
            v, duration = v + delta[:9], duration + delta[9]
        else:
            raise Fall("re-aiming the next step did not converge: the state is too far from the plan")
        self.next_period = duration
        return v
