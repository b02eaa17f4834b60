"""The walk in a second engine (``engine:=mujoco``, docs/model.md section 11): each step's single
support integrated by MuJoCo (RK4) on the exported stance-rooted tree (``core/model/mjcf.py``,
kind ``stance``: its qpos and qvel are the model's q and qd), the double support as finite joint
torques over ``pulse_duration`` d seconds, and the walker's re-aim (and momentum steering) as the
feedback, from the state MuJoCo gives.

**Why the stance-rooted tree, with the contact checked, and not MuJoCo's point-foot contacts.**
The floating export (a free pelvis, point feet on a floor) does load and walk in MuJoCo, but its
soft contacts are not the paper's pivot: the contact force needs a penetration to build (the
first millisecond is a free fall), the friction constraints restore velocities, not positions (the
stance foot creeps and spins about the vertical, 0.3 mrad in 40 ms, the spin moment off the
pivot's by up to 0.6 N m), and the ballistic single support amplifies any error about 100-fold
within one step: started on the plan, MuJoCo's floating robot reaches the touchdown 0.07 rad
(0.09 rad with the export's contact parameters) and 1.1 rad/s off the plan, whatever the contacts'
stiffness (impedance 0.9 to 0.9999, impratio 1 to 1000, time constant 0.5 to 2 ms, foot radius 1 mm
to 1 um), beyond what any re-aim from the touchdown recovers. The tree holds the stance tip as the
pivot does; the contact is checked instead, at every sample, from MuJoCo's own reaction at the tip
(``mj_rnePostConstraint``: the force the world exerts on the stance shin): the vertical force
positive, within the friction cone of the parameter set (``Fall`` otherwise).

**The double support** (the phase of docs/model.md section 10, walked): around each touchdown,

- the pre-impact pulse: constant torques u^- from d / 2 s before the predicted touchdown until
  MuJoCo's (the old stance foot on the ground);
- the passive impact, where MuJoCo's swing tip reaches the floor (located by Brent's method on
  MuJoCo's last step redone in part): eqs. (8)-(9) with MuJoCo's D_e and J2 (the ``extended``
  export), then the leg exchange;
- the post-impact pulse: constant torques u^+ over the first d / 2 s of the next step.

MuJoCo's steps are split where a pulse starts or ends: each sees one constant torque.

**The feedback** (``_plan``). ``DECISION_LEAD`` s before the pre-impact pulse is due (the last
re-aim's duration tells when; the planner's model again at mid-step and after a push), the engine reads MuJoCo's state, predicts the ballistic touchdown
with the planner's flow and guard, and hands that pre-impact state to the walker's double support
(``Walker._double_support``): the re-aim of the next step (with momentum steering if the walker
has it) and the LP's impulses I^-, I^+, exactly as the hybrid walker does at its touchdown. The
pulses u = I / (d / 2) reach that re-aimed next step only as d -> 0: the configuration moves
during them (the joints at up to 16 rad/s), and the open-loop step amplifies the difference.
So the torques are corrected, with the planner's model (``_Correction``), until the pulsed phase
lands on the re-aimed next step: unknowns the torques u^- and u^+ (2 nA) and the next step's
duration tau; equations: the swing tip on the ground at the pre-impact pulse's end (1), and the
next step's configuration at tau the re-aimed one's at its touchdown (nq); constraints: the
stance tip's reaction in the friction cone (the inscribed octagonal pyramid) with a positive
normal force at every node of both pulses, the impact's reaction likewise, the old stance foot
leaving, the swing tip coming down; Gauss-Newton (``finite_support.gauss_newton``: least-norm
steps, the constraints' least move) from the impulses spread plus the last correction's offset
from its own, to ``TOLERANCE``. The next step then starts from whatever MuJoCo made of the pulses.

Units SI, rad; times in the walk (s) unless said "in the step".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mujoco
import numpy as np
from scipy.optimize import brentq

from ..dynamics.hybrid import HybridStep, impact_with
from ..model.biped import SWING_TIP
from ..model.exchange import exchange_matrix, next_heading, other_side
from ..model.mjcf import TIMESTEP, make_mjcf
from .finite_support import FD_STEP, FiniteSupportFailed, cone_rows, friction_ratio, gauss_newton, passive_impact, pulse
from .push import AppliedPush
from .walk import Fall, Sample, StepOutcome, Touchdown, Walker, WalkState

DECISION_LEAD = 0.01  # s: the double support is planned this long before its pre-impact pulse is due
TOLERANCE = 1e-7  # m, rad: the corrected pulses land on the re-aimed next step to this (the next re-aim takes the rest)
PULSE_STEPS = 8  # RK4 steps of a pulse in the correction's model


@dataclass(frozen=True)
class MujocoTouchdown:
    """One double support in MuJoCo (units SI, rad): the step; MuJoCo's touchdown time (s in the
    walk); the planner's predicted ballistic touchdown from the decision's state (time in the walk,
    q, qd); MuJoCo's pre-impact state (q, qd, after the pre-impact pulse); the torques u^- (this
    step's actuated joints) and u^+ (the next step's), N m; their effort E = (d / 2) sum |u|
    (N m s) beside the impulses' W; the correction's residual (m, rad) and Gauss-Newton steps; the
    friction the planned phase needs (the largest |F_xy| / F_z at the pulses' nodes in the planner's
    model) and the largest |F_xy| / F_z of MuJoCo's stance-tip reaction over the step's samples."""

    step: int
    t: float
    t_predicted: float
    q_predicted: np.ndarray
    qd_predicted: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    u_minus: np.ndarray
    u_plus: np.ndarray
    effort: float
    impulsive_effort: float
    residual: float
    corrections: int
    friction_planned: float
    friction_used: float

    @property
    def peak_torque(self) -> float:
        """The largest pulse torque (N m)."""
        return float(np.max(np.abs(np.concatenate([self.u_minus, self.u_plus]))))


@dataclass(frozen=True)
class _Pulse:
    """Constant joint torques ``torque`` (N m, the step's q order) from ``start`` to ``end`` (s)."""

    torque: np.ndarray
    start: float
    end: float


@dataclass(frozen=True)
class _Plan:
    """A planned double support: the walker's touchdown report, the pre-impact pulse's start (s in
    the walk), the predicted ballistic touchdown (time in the walk, q, qd), the corrected torques
    (N m, full q vectors: this step's u^-, the next step's u^+), the correction's residual and
    steps, and the friction its pulses need (the largest |F_xy| / F_z at their nodes)."""

    touchdown: Touchdown
    pre_start: float
    t_hit: float
    q_hit: np.ndarray
    qd_hit: np.ndarray
    u_minus: np.ndarray
    u_plus: np.ndarray
    residual: float
    corrections: int
    friction: float


class _Correction:
    """The pulses' correction (module docstring): z = (tau, u^+, u^-), tau the next step's duration
    (s), u^+ (the next step's actuated joints) and u^- (this step's), N m; from the pre-impact
    pulse's start (``q_s``, ``qd_s``: rad, rad/s) to the next step's configuration at tau,
    ``target`` (rad)."""

    def __init__(self, engine: "MujocoEngine", walker: Walker, q_s: np.ndarray, qd_s: np.ndarray,
                 target: np.ndarray, phase_jacobian: np.ndarray | None = None) -> None:
        self.hybrid, self.flow = engine.hybrid, walker.step_flow
        self.coarse = engine.hybrid.flow(walker.settings.coarse_steps)  # the sensitivities' grid
        self.q_s, self.qd_s, self.target = q_s, qd_s, target
        self.duration, self.friction = engine.pulse_duration, engine.friction
        self.actuated, self.na = engine._actuated, len(engine._actuated)
        # d(next state, tip height, constraints) / d torques: given (the last double support's), or by differences
        self.phase_jacobian = phase_jacobian

    def torque(self, u: np.ndarray) -> np.ndarray:
        """The joint torques (nq, q order, N m) of the actuated joints' ``u``."""
        out = np.zeros(self.hybrid.bm.nq)
        out[self.actuated] = u
        return out

    def phase(self, u_plus: np.ndarray, u_minus: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
        """The pulsed phase of the torques ``u_plus``, ``u_minus`` (N m): the next step's state at
        the post-impact pulse's end (q, qd stacked, rad, rad/s), the swing tip's height at the
        pre-impact pulse's end (m), the constraints of ``evaluate`` and the stance tips' reactions
        at the pulses' nodes (N)."""
        hybrid, bm, half = self.hybrid, self.hybrid.bm, self.duration / 2
        q_e, qd_e, before = pulse(hybrid, self.q_s, self.qd_s, self.torque(u_minus), half, PULSE_STEPS)
        impact = hybrid.impact(q_e)
        landing = passive_impact(impact, qd_e)
        exchange = hybrid.exchange
        q_p, qd_p, after = pulse(hybrid, exchange.configuration(q_e), exchange.velocity(q_e, landing.xd_plus),
                                 self.torque(u_plus), half, PULSE_STEPS)
        forces = np.vstack([before, after])
        arrival = float(impact.j2[2] @ bm.embed(qd_e))
        constraints = np.concatenate([cone_rows(forces * half, self.friction).ravel(),
                                      cone_rows(landing.reaction, self.friction), [-landing.old_foot_vz, arrival]])
        return np.concatenate([q_p, qd_p]), float(bm.swing_tip(q_e)[2]), constraints, forces

    def evaluate(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The equations' residual (the next configuration at tau less the target, rad; the swing
        tip's height at the pulse's end, m), the constraints (<= 0: the stance tip's reaction at
        every node of both pulses in the friction cone with a positive normal force, as impulses
        over d / 2 (N s), the passive impact's reaction likewise, the old stance foot leaving, the
        swing tip coming down), and the stance tips' reactions at the pulses' nodes (N)."""
        na, n = self.na, self.hybrid.bm.nq
        state, height, constraints, forces = self.phase(z[1:1 + na], z[1 + na:])
        with np.errstate(over="ignore", invalid="ignore"):
            run = self.flow.propagate(state[:n], state[n:], z[0] - self.duration / 2)
        return np.append(run.q - self.target, height), constraints, forces

    def solve(self, z: np.ndarray, guess: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """z with the equations met to ``TOLERANCE`` and the constraints, from ``z`` (or
        ``z + guess`` if its residual is smaller), and the Gauss-Newton steps taken
        (``finite_support.gauss_newton``; the torques scaled by their largest, tau in s; the
        Jacobian ``differences``: the flow's at each step, the pulsed phase's given
        (``phase_jacobian``) or at the first step, and again when a step cannot lower the merit).
        ``Fall`` if it does not converge."""
        if guess is not None:  # the last double support's correction, if it does better
            if np.max(np.abs(self.evaluate(z + guess)[0])) < np.max(np.abs(self.evaluate(z)[0])):
                z = z + guess
        try:
            return gauss_newton(self.evaluate, lambda x, r, c, fresh: self.differences(x, r, c, phase=fresh), z,
                                self.scale, TOLERANCE, fresh=self.phase_jacobian is None)
        except FiniteSupportFailed as exc:
            raise Fall(f"the double support's pulses of {self.duration * 1e3:g} ms cannot reach the re-aimed next "
                       f"step within the friction cone: {exc}") from None

    def scale(self, z: np.ndarray) -> np.ndarray:
        """The unknowns' units: tau in s, the torques in their largest (N m)."""
        return np.append(1.0, np.full(2 * self.na, max(1.0, float(np.max(np.abs(z[1:]))))))

    def differences(self, z: np.ndarray, residual: np.ndarray, constraints: np.ndarray,
                    phase: bool = True) -> np.ndarray:
        """d(residual, constraints) / dz: the flow after the pulsed phase by its sensitivities at z
        (on the planner's coarse grid), the phase by forward differences (``phase``), or as the
        last differences found (short pulses: the phase is nearly linear in the torques)."""
        na, n, half = self.na, self.hybrid.bm.nq, self.duration / 2
        scale = self.scale(z)
        state, height, _, _ = self.phase(z[1:1 + na], z[1 + na:])
        run = self.coarse.propagate(state[:n], state[n:], z[0] - half, np.eye(2 * n))
        if phase or self.phase_jacobian is None:
            columns = []
            for k in range(1, len(z)):
                dz = np.zeros(len(z))
                dz[k] = FD_STEP * scale[k]
                moved, h, c, _ = self.phase(z[1:1 + na] + dz[1:1 + na], z[1 + na:] + dz[1 + na:])
                columns.append(np.concatenate([moved - state, [h - height], c - constraints]) / dz[k])
            self.phase_jacobian = np.array(columns).T
        d_state, d_rest = self.phase_jacobian[:2 * n], self.phase_jacobian[2 * n:]
        jac = np.zeros((len(residual) + len(constraints), len(z)))
        jac[:n, 0] = run.qd
        jac[:n, 1:] = run.sens[:n] @ d_state
        jac[n:, 1:] = d_rest
        return jac


class MujocoEngine:
    """Walks a ``Walker``'s steps in MuJoCo (module docstring): ``walk_step(walker)`` in place of
    the hybrid step. ``rate``: samples per second of simulated time (MuJoCo's step is the largest
    at most ``mjcf.TIMESTEP`` that divides 1 / rate); ``pulse_duration``: d (s)."""

    def __init__(self, hybrid: HybridStep, rate: float, pulse_duration: float) -> None:
        if not pulse_duration > 0:
            raise ValueError(f"the pulse duration must be positive, got {pulse_duration} s")
        self.hybrid, self.bm, self.pulse_duration = hybrid, hybrid.bm, pulse_duration
        params = self.bm.params
        self.model = model = mujoco.MjModel.from_xml_string(make_mjcf(params, "stance"))
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)  # as the planner: none enforced
        self.per_sample = max(1, math.ceil(1.0 / (rate * TIMESTEP) - 1e-9))  # MuJoCo steps per sample
        self.h = 1.0 / (rate * self.per_sample)
        model.opt.timestep = self.h
        self.data = mujoco.MjData(model)
        self.extended = mujoco.MjModel.from_xml_string(make_mjcf(params, "extended"))
        self.extended_data = mujoco.MjData(self.extended)
        self._shin = model.body("stance_shin").id
        self._trunk = model.body("trunk").id
        self._swing_tip = model.site(SWING_TIP).id
        actuated = self.bm.actuated
        self._actuated = actuated
        # u^+ in the next step's joints from I^+ in this step's (finite_support: a signed permutation)
        self._exchange_joints = exchange_matrix(self.bm.coordinates)[np.ix_(actuated, actuated)]
        self.friction = params.friction
        self.t = 0.0  # s, MuJoCo's state's time in the walk
        self._pulses: list[_Pulse] = []
        self._offset: np.ndarray | None = None  # the last correction less its impulses spread: the next one's guess
        self._phase_jacobian: np.ndarray | None = None  # the last correction's, the next one's first
        self._started = False
        self.touchdowns: list[MujocoTouchdown] = []

    # MuJoCo ------------------------------------------------------------------------------------
    def _torque(self, t0: float, t1: float | None = None) -> np.ndarray:
        """The pulses' joint torques (N m, q order) at ``t0``, or their mean over [t0, t1] (s)."""
        torque = np.zeros(self.model.nv)
        for p in self._pulses:
            if t1 is None:
                torque += p.torque if p.start <= t0 < p.end else 0.0
            elif (overlap := min(t1, p.end) - max(t0, p.start)) > 0:
                torque += p.torque * (overlap / (t1 - t0))
        return torque

    def _set(self, q: np.ndarray, qd: np.ndarray, t: float) -> None:
        """MuJoCo's state: (``q``, ``qd``) at ``t``, its derived quantities computed with the
        torques acting then."""
        d = self.data
        d.qpos[:], d.qvel[:], d.time = q, qd, t
        self.t = t
        d.qfrc_applied[:] = self._torque(t)
        mujoco.mj_forward(self.model, d)

    def _advance(self, t_end: float, push: np.ndarray | None = None) -> None:
        """One MuJoCo RK4 step to ``t_end`` (s) with the pulses' mean torques over it (each pulse
        times the fraction of the step it covers) and ``push`` (N s, model axes) on the trunk's CoM
        spread over it."""
        d, length = self.data, t_end - self.t
        d.qfrc_applied[:] = self._torque(self.t, t_end)
        d.xfrc_applied[self._trunk, :3] = 0.0 if push is None else push / length
        self.model.opt.timestep = length
        mujoco.mj_step(self.model, d)
        d.xfrc_applied[self._trunk, :3] = 0.0
        self._set(d.qpos.copy(), d.qvel.copy(), t_end)

    def _reaction(self) -> np.ndarray:
        """[Fx, Fy, Fz, Mz] (N, N m, the step's model axes) the ground exerts on the stance tip now:
        MuJoCo's interaction force of the stance shin with the world (the pulses' torques in it)."""
        d = self.data
        mujoco.mj_rnePostConstraint(self.model, d)
        wrench = d.cfrc_int[self._shin]  # [moment about the c-frame's origin; force], world axes
        cx, cy, _ = d.subtree_com[self._shin]  # the c-frame's origin; the tip is the world origin
        fx, fy, fz = wrench[3:]
        return np.array([fx, fy, fz, wrench[2] + cx * fy - cy * fx])

    def _tip_height(self) -> float:
        return float(self.data.site_xpos[self._swing_tip, 2])

    def _land_on_ground(self, t0: float, q0: np.ndarray, qd0: np.ndarray, push: np.ndarray | None) -> None:
        """The swing tip went below the floor in the MuJoCo step from ``t0`` (state ``q0``,
        ``qd0``, ``push`` in it) to now: redo that step in part, to where the tip is on the floor
        (Brent's method on the step's end, 1e-15 s)."""
        t1 = self.t

        def height(t: float) -> float:
            self._set(q0, qd0, t0)
            self._advance(t, push)
            return self._tip_height()

        start = t0 + 1e-15
        height(start if height(start) <= 0.0 else brentq(height, start, t1, xtol=1e-15, rtol=1e-15))

    def _impact(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The passive impact (eqs. 8-9) at ``q`` from ``qd`` with MuJoCo's D_e and J2 (the
        ``extended`` export; a foot's spin row, with hip roll and yaw joints, the planner's), then
        the leg exchange: the next step's initial velocity (its coordinates)."""
        model, data, bm = self.extended, self.extended_data, self.bm
        data.qpos[:] = bm.ds_state(q)
        mujoco.mj_forward(model, data)
        mass = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, mass)
        impact = self.hybrid.impact(q)
        j2 = impact.j2.copy()
        mujoco.mj_jacSite(model, data, j2[:3], None, model.site(SWING_TIP).id)
        xd_plus = impact_with(mass, j2, bm.embed(qd), np.zeros(impact.layout.na), impact.layout.joints, at_rest=True)
        return self.hybrid.exchange.velocity(q, xd_plus)

    # The plan of a double support ----------------------------------------------------------------
    def _predict(self, walker: Walker, q: np.ndarray, qd: np.ndarray, t_step: float) -> tuple[float, np.ndarray, np.ndarray]:
        """The ballistic touchdown from (``q``, ``qd``) at ``t_step`` (s in the step) with the
        planner's flow and guard: its time in the step and its state."""
        h, limit = walker.period / walker.grid, 2.0 * walker.period
        while t_step < limit:
            run = walker.flow.propagate(q, qd, h, keep_nodes=True)
            hit = walker.guard.touchdown((run.nodes[0] + t_step, *run.nodes[1:]))
            if hit is not None:
                end = walker.flow.propagate(q, qd, hit - t_step)
                return hit, end.q, end.qd
            t_step, q, qd = t_step + h, run.q, run.qd
        raise Fall("the planner's model predicts no touchdown from MuJoCo's state within 2 T")

    def _plan(self, walker: Walker, s: WalkState) -> _Plan:
        """The double support planned from MuJoCo's state now (module docstring, the feedback)."""
        half = self.pulse_duration / 2
        q, qd, t_step = self.data.qpos.copy(), self.data.qvel.copy(), self.t - s.t
        t_hit, q_hit, qd_hit = self._predict(walker, q, qd, t_step)
        touchdown = walker._double_support(q_hit, qd_hit, t_hit)
        nxt = walker.state  # the re-aimed next step: its start and duration
        target = walker.step_flow.propagate(nxt.q, nxt.qd, walker.next_period).q
        start = max(t_step, t_hit - half)
        q_s, qd_s = q, qd
        if start > t_step:  # the planner's state where the pre-impact pulse starts
            run = walker.flow.propagate(q, qd, start - t_step)
            q_s, qd_s = run.q, run.qd
        correction = _Correction(self, walker, q_s, qd_s, target, self._phase_jacobian)
        spread = np.concatenate([[walker.next_period], self._exchange_joints @ touchdown.i_plus / half,
                                 touchdown.i_minus / half])
        z, steps = correction.solve(spread, self._offset)
        self._offset, self._phase_jacobian = z - spread, correction.phase_jacobian
        residual, _, forces = correction.evaluate(z)
        walker.next_period = float(z[0])
        na = len(self._actuated)
        return _Plan(touchdown, s.t + start, s.t + t_hit, q_hit, qd_hit, correction.torque(z[1 + na:]),
                     correction.torque(z[1:1 + na]), float(np.max(np.abs(residual))), steps, friction_ratio(forces))

    # The step ------------------------------------------------------------------------------------
    def walk_step(self, walker: Walker) -> StepOutcome:
        """Walk the walker's current step in MuJoCo until its touchdown (module docstring): its
        samples, and the walker's touchdown report with MuJoCo's times, or the fall."""
        s = walker.state
        if not self._started or not (np.array_equal(s.q, self.data.qpos) and np.array_equal(s.qd, self.data.qvel)):
            self._set(s.q, s.qd, s.t)  # the walk's start, or a state the walker was given (``Walker.shove``)
            self._started = True
        half = self.pulse_duration / 2
        period = walker.period
        decide_at = s.t + walker.next_period - half - DECISION_LEAD
        t_rows, q_rows, qd_rows, grf_rows = [], [], [], []
        applied: list[AppliedPush] = []
        plan: _Plan | None = None
        while True:
            grid = round(self.t / self.h)
            if abs(self.t - grid * self.h) < 1e-12 and grid % self.per_sample == 0:
                t_rows.append(self.t)
                q_rows.append(self.data.qpos.copy())
                qd_rows.append(self.data.qvel.copy())
                grf_rows.append(self._reaction())
            if plan is None and self.t >= decide_at - 1e-12:
                try:
                    plan = self._plan(walker, s)
                except Fall as exc:
                    return self._fell(walker, s, t_rows, q_rows, qd_rows, grf_rows, applied, str(exc))
                self._pulses.append(_Pulse(plan.u_minus, plan.pre_start, math.inf))  # on until the touchdown
            if self.t - s.t > 2.0 * period:
                return self._fell(walker, s, t_rows, q_rows, qd_rows, grf_rows, applied,
                                  f"the swing foot did not land within 2 T = {2 * period:.3f} s")
            t0, q0, qd0 = self.t, self.data.qpos.copy(), self.data.qvel.copy()
            t_next = min([(math.floor(self.t / self.h + 1e-9) + 1) * self.h]  # the grid, or a pulse's start or end
                         + [b for p in self._pulses for b in (p.start, p.end) if b > self.t + 1e-12])
            push = self._due_push(walker, s, t_next, applied)
            self._advance(t_next, push)
            if plan is None and (push is not None or t0 - s.t < 0.5 * period <= self.t - s.t):
                # after a push, and at mid-step: when the touchdown is due, from the planner's model
                try:
                    t_hit = self._predict(walker, self.data.qpos.copy(), self.data.qvel.copy(), self.t - s.t)[0]
                except Fall as exc:
                    return self._fell(walker, s, t_rows, q_rows, qd_rows, grf_rows, applied, str(exc))
                decide_at = s.t + t_hit - half - DECISION_LEAD
            if self.t - s.t > 0.5 * period and self._tip_height() <= 0.0:
                self._land_on_ground(t0, q0, qd0, push)
                if plan is None:
                    return self._fell(walker, s, t_rows, q_rows, qd_rows, grf_rows, applied,
                                      f"the swing foot landed at t = {self.t:.4f} s, before its double support was planned")
                break
        samples, fall = self._samples(walker, s, t_rows, q_rows, qd_rows, grf_rows)
        if fall:
            walker._pushes = []
            return StepOutcome(samples, None, fall, tuple(applied))
        touchdown = self._touchdown(walker, s, plan, grf_rows, applied)
        return StepOutcome(samples, touchdown, pushes=tuple(applied))

    def _fell(self, walker: Walker, s: WalkState, t_rows, q_rows, qd_rows, grf_rows, applied, reason: str) -> StepOutcome:
        samples, fall = self._samples(walker, s, t_rows, q_rows, qd_rows, grf_rows)
        walker._pushes = []
        return StepOutcome(samples, None, fall or reason, tuple(applied))

    def _samples(self, walker: Walker, s: WalkState, t_rows, q_rows, qd_rows, grf_rows) -> tuple[list[Sample], str]:
        """The step's samples up to the first that falls (the walker's checks, and the friction
        cone on MuJoCo's reaction), and the fall's reason ('' for none)."""
        samples: list[Sample] = []
        if not t_rows:
            return samples, ""
        lowest = walker.samples.dynamics(np.array(q_rows), np.array(qd_rows)).lowest_link
        for k, t in enumerate(t_rows):
            sample = Sample(t, t - s.t, q_rows[k], qd_rows[k], grf_rows[k], s.step, s.stance_side, s.stance_foot)
            samples.append(sample)
            walker.sample_index += 1
            fall = walker._fall(sample, float(lowest[k]))
            fx, fy, fz, _ = sample.grf
            if not fall and math.hypot(fx, fy) > self.friction * fz:
                fall = (f"the stance foot slips at t = {t:.4f} s: |F_xy| / F_z = {math.hypot(fx, fy) / fz:.3f} > "
                        f"mu = {self.friction:g}")
            if fall:
                return samples, fall
        return samples, ""

    def _due_push(self, walker: Walker, s: WalkState, t_next: float, applied: list[AppliedPush]) -> np.ndarray | None:
        """The impulse (N s, model axes) of the walker's pushes due in the MuJoCo step from now to
        ``t_next`` (s), each reported as applied (its velocity jump the model's, now)."""
        total = None
        while walker._pushes and walker._pushes[0].time_in_step < t_next - s.t:
            push = walker._pushes.pop(0)
            q = self.data.qpos.copy()
            jump = walker.trunk_push.velocity_jump(q, push.impulse, s.axes)
            applied.append(AppliedPush(s.step, s.stance_side, self.t, self.t - s.t, push.impulse, jump))
            impulse = s.axes.T @ np.asarray(push.impulse, float)
            total = impulse if total is None else total + impulse
        return total

    def _touchdown(self, walker: Walker, s: WalkState, plan: _Plan, grf_rows, applied: list[AppliedPush]) -> Touchdown:
        """MuJoCo's touchdown: the pushes still due acting on it (``applied``), the passive impact
        and the leg exchange, the post-impact pulse, the walker's state made MuJoCo's; the walker's touchdown report with MuJoCo's time and what
        the pulses applied (their integrals (d / 2) u as I^-, I^+, their effort E as W; its state
        error the predicted ballistic touchdown's, as the hybrid walker's)."""
        half = self.pulse_duration / 2
        q_c, qd_c, t_c = self.data.qpos.copy(), self.data.qvel.copy(), self.t
        for push in walker._pushes:  # due after the touchdown: they act on it (as the hybrid walker's)
            jump = walker.trunk_push.velocity_jump(q_c, push.impulse, s.axes)
            applied.append(AppliedPush(s.step, s.stance_side, t_c, t_c - s.t, push.impulse, jump))
            qd_c = qd_c + jump
        walker._pushes = []
        q_next, qd_next = self.hybrid.exchange.configuration(q_c), self._impact(q_c, qd_c)
        self._pulses = [_Pulse(plan.u_plus, t_c, t_c + half)]
        self._set(q_next, qd_next, t_c)
        tip = s.stance_foot + s.axes @ self.bm.swing_tip(q_c)
        tip[2] = 0.0
        side = other_side(s.stance_side)
        walker.state = replace(walker.state, q=q_next, qd=qd_next, t=t_c, stance_foot=tip,
                               heading=next_heading(s.heading, side, self.hybrid.exchange.heading(q_c)))
        grf = np.array(grf_rows) if grf_rows else np.zeros((1, 4))
        loaded = grf[:, 2] > 0
        td = plan.touchdown
        self.touchdowns.append(MujocoTouchdown(
            step=s.step, t=t_c, t_predicted=plan.t_hit, q_predicted=plan.q_hit, qd_predicted=plan.qd_hit, q=q_c, qd=qd_c,
            u_minus=plan.u_minus[self._actuated], u_plus=plan.u_plus[self._actuated],
            effort=float(half * (np.abs(plan.u_minus).sum() + np.abs(plan.u_plus).sum())), impulsive_effort=td.W,
            residual=plan.residual, corrections=plan.corrections, friction_planned=plan.friction,
            friction_used=float(np.max(np.hypot(grf[loaded, 0], grf[loaded, 1]) / grf[loaded, 2])) if loaded.any() else math.nan))
        # The report carries what was applied: the pulses' integrals (I^+ in this step's joints) and their effort.
        return replace(td, t=t_c, t_step=t_c - s.t, i_minus=half * plan.u_minus[self._actuated],
                       i_plus=half * self._exchange_joints.T @ plan.u_plus[self._actuated], W=self.touchdowns[-1].effort)
