"""The walk in a second engine (``engine:=mujoco``, docs/model.md section 11): each step's single
support integrated by MuJoCo (RK4) on the floating export (``core/model/mjcf.py``: a free pelvis,
motors on the joints, point feet on a floor with the parameter set's friction), the double support
as finite joint torques over ``pulse_duration`` d seconds, and the walker's re-aim (and momentum
steering) as the feedback, from the state MuJoCo gives.

**The double support** (the phase of docs/model.md section 10, walked): the walker's impulses I^-
and I^+ spread into constant torques over d / 2 each,

- u^- = I^- / (d / 2) over the last d / 2 before the touchdown the planner's model predicts,
- the touchdown itself: MuJoCo's contact of the swing foot (a soft, inelastic contact, no
  torque of ours in it but the pulses'),
- u^+ = I^+ / (d / 2) over the first d / 2 after MuJoCo's touchdown (I^+ in the old step's
  joints: the same motors);

each torque's integral is exact: MuJoCo holds a control constant over its step h, so a step the
pulse only partly covers gets the torque times the fraction covered. As d -> 0 the pulses become
the impulses of the hybrid walker.

**The feedback.** ``DECISION_LEAD`` s before the pre-impact pulse is due (the last re-aim's
duration tells when), the engine reads MuJoCo's state as the model's (q, qd), predicts the
ballistic touchdown with the planner's flow and guard (RK8, ``Walker.flow``), and hands that
pre-impact state to the walker's double support (``Walker._double_support``): the re-aim of the
next step from there and the impulses of its LP, exactly as the hybrid walker does at its
touchdown. The next step then starts from whatever MuJoCo made of the pulses: its state at the
touchdown, read again, is the next step's (and its stance foot where MuJoCo put it).

**MuJoCo's state as the model's.** Joints: the URDF angles mapped by ``UrdfJoints`` (signs, sides,
mirror); the stance ankle's roll and pitch from the stance shin's orientation in the step's model
frame, R = Rz(psi) Rx(q1) Ry(q2): psi is the stance foot's spin about the vertical, a rigid turn
of the whole robot (which the dynamics does not see; the next step's heading takes the new
stance foot's); the rates from the shin's angular velocity (omega' = Rz(-psi) omega: q1d =
omega'_x, q2d = omega'_y / cos q1). Samples carry MuJoCo's contact force on the stance foot as
the ground reaction [Fx, Fy, Fz, Mz] (N, N m, model axes).

**Falls**: a limb (any geom but the feet) touching the floor, the stance foot more than
``FOOT_LIFT`` above it, no touchdown within 2 T, or the walker's double support failing.

Joint limits are not enforced (the planner does not: the default gait's stance knee overextends by
0.35 deg) and neither is the table's effort bound (the pulses' torques are the impulses over
milliseconds, far above it: ``MujocoTouchdown.peak_torque`` says how far). Units SI, rad; time
in the walk (s) unless said "in the step".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from ..model.biped import BipedModel
from ..model.exchange import mirror_for, other_side, world_axes
from ..model.mjcf import FLOOR, TIMESTEP, make_mjcf
from .push import AppliedPush
from .walk import Fall, Sample, StepOutcome, Walker, WalkState
from .world import WorldView

DECISION_LEAD = 0.01  # s: the touchdown is predicted this long before its pre-impact pulse is due
FOOT_LIFT = 2e-3  # m: the stance tip this far above the floor has left the ground (a fall)


@dataclass(frozen=True)
class MujocoTouchdown:
    """One touchdown in MuJoCo beside the planner's prediction of it: the step; MuJoCo's touchdown
    time (s in the walk, at its step's end); the predicted ballistic touchdown's time (s in the
    walk) and state (q, qd: rad, rad/s, the step's model coordinates) from the state at the
    decision; MuJoCo's state at its touchdown (after the pre-impact pulse); the largest pulse
    torque (N m) against the table's effort bound; the largest |F_xy| / F_z of the stance foot's
    contact over the step's samples; how far the stance foot slid during the step (m,
    horizontal) and turned about the vertical (rad)."""

    step: int
    t: float
    t_predicted: float
    q_predicted: np.ndarray
    qd_predicted: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    peak_torque: float
    effort_bound: float
    friction_used: float
    slip: float
    spin: float


@dataclass(frozen=True)
class _Pulse:
    """Constant motor controls ``ctrl`` (N m, actuator order) from ``start`` to ``end`` (s)."""

    ctrl: np.ndarray
    start: float
    end: float


@dataclass(frozen=True)
class _Records:
    """MuJoCo's state at sample instants, one row each: URDF joint angles and rates (rad, rad/s),
    the stance shin's rotation (3 x 3, world) and angular velocity (rad/s, world), the stance tip
    (m, world), the stance foot's contact force [F (world), moment about the normal] (N, N m)."""

    t: list[float]
    angles: list[np.ndarray]
    rates: list[np.ndarray]
    shin: list[np.ndarray]
    omega: list[np.ndarray]
    tip: list[np.ndarray]
    force: list[np.ndarray]


class MujocoEngine:
    """Walks a ``Walker``'s steps in MuJoCo (module docstring): ``walk_step(walker)`` in place of
    the hybrid step. ``world``: the walk's ``WorldView`` of ``bm``; ``rate``: samples per second of
    simulated time (MuJoCo's step is the largest at most ``mjcf.TIMESTEP`` that divides 1 / rate);
    ``pulse_duration``: d (s), the double support's."""

    def __init__(self, bm: BipedModel, world: WorldView, rate: float, pulse_duration: float) -> None:
        if not pulse_duration > 0:
            raise ValueError(f"the pulse duration must be positive, got {pulse_duration} s")
        self.bm, self.world, self.pulse_duration = bm, world, pulse_duration
        self.model = model = mujoco.MjModel.from_xml_string(make_mjcf(bm.params, "floating"))
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT) | int(mujoco.mjtDisableBit.mjDSBL_CLAMPCTRL)
        self.per_sample = max(1, math.ceil(1.0 / (rate * TIMESTEP) - 1e-9))  # MuJoCo steps per sample
        model.opt.timestep = self.h = 1.0 / (rate * self.per_sample)
        self.data = mujoco.MjData(model)
        self.joints = world.joints
        names = self.joints.names
        ids = [model.joint(name).id for name in names]
        self._qpos = np.array([model.jnt_qposadr[j] for j in ids])
        self._qvel = np.array([model.jnt_dofadr[j] for j in ids])
        self._actuators = np.array([model.actuator(name).id for name in names])
        self._effort = float(np.max(model.actuator_ctrlrange[:, 1]))
        self._shin = {side: model.body(f"{side}_shin").id for side in ("right", "left")}
        self._foot = {side: model.geom(f"{side}_foot").id for side in ("right", "left")}
        self._tip = {side: model.site(f"{side}_foot").id for side in ("right", "left")}
        self._floor = model.geom(FLOOR).id
        self._torso = model.body("torso").id
        self._ankles = bm.index("ankle_roll"), bm.index("ankle_pitch")
        # model q -> URDF angles is q @ M (a signed selection); its transpose maps back
        self._to_urdf = {side: self.joints.array(np.eye(bm.nq), side) for side in ("right", "left")}
        self.n = 0  # MuJoCo steps since the walk's t = 0
        self._pulses: list[_Pulse] = []
        self._started = False
        self.touchdowns: list[MujocoTouchdown] = []

    # MuJoCo's state and the model's -------------------------------------------------------------
    def set_state(self, s: WalkState) -> None:
        """MuJoCo's state from the walker's: the model state (q, qd) with its stance foot, side and
        heading, at the walk time ``s.t``."""
        pictures = self.world.pictures(s.q, s.qd, s.stance_side, s.stance_foot, s.heading)
        x, y, z, w = pictures.pelvis_quaternion[0]
        rotation = np.empty(9)
        mujoco.mju_quat2Mat(rotation, np.array([w, x, y, z]))
        d = self.data
        d.qpos[:3], d.qpos[3:7] = pictures.pelvis_position[0], (w, x, y, z)
        d.qvel[:3] = rotation.reshape(3, 3) @ pictures.pelvis_linear_velocity[0]  # MuJoCo: world axes
        d.qvel[3:6] = pictures.pelvis_angular_velocity[0]  # the pelvis frame, as MuJoCo's free joint
        d.qpos[self._qpos], d.qvel[self._qvel] = pictures.joint_positions[0], pictures.joint_velocities[0]
        d.ctrl[:] = 0.0
        self.n = round(s.t / self.h)
        d.time = self.n * self.h
        mujoco.mj_forward(self.model, d)

    def _record(self, records: _Records, side: str) -> None:
        """Append MuJoCo's current state (``side`` the stance foot) to ``records``."""
        d, shin = self.data, self._shin[side]
        records.t.append(self.n * self.h)
        records.angles.append(d.qpos[self._qpos].copy())
        records.rates.append(d.qvel[self._qvel].copy())
        records.shin.append(d.xmat[shin].reshape(3, 3).copy())
        records.omega.append(d.cvel[shin, :3].copy())  # cvel: [angular; linear], world axes
        records.tip.append(d.site_xpos[self._tip[side]].copy())
        records.force.append(self._foot_force(side))

    def _foot_force(self, side: str) -> np.ndarray:
        """The floor's force on the ``side`` foot (N, world) and moment about the normal (N m)."""
        d, foot, out, f6 = self.data, self._foot[side], np.zeros(4), np.zeros(6)
        for i in range(d.ncon):
            g1, g2 = d.contact.geom[i]
            if foot not in (g1, g2):
                continue
            mujoco.mj_contactForce(self.model, d, i, f6)
            frame = d.contact.frame[i].reshape(3, 3)  # rows: the normal (geom1 -> geom2), two tangents
            sign = 1.0 if g2 == foot else -1.0
            out[:3] += sign * frame.T @ f6[:3]
            out[3] += sign * f6[3]
        return out

    def model_states(self, records: _Records, side: str, heading: float) -> tuple[np.ndarray, ...]:
        """The model's (q, qd) of ``records`` (rows) in the model frame of the ``side`` stance foot
        at ``heading``, the stance foot's spin psi about the vertical in that frame (rad), and the
        ground reaction [Fx, Fy, Fz, Mz] in its axes (module docstring)."""
        axes, mirror = world_axes(side, heading), mirror_for(side)
        det = float(np.linalg.det(axes))
        shin = axes.T @ np.array(records.shin) @ mirror  # R in the model frame, rows of 3 x 3
        psi = np.arctan2(-shin[:, 0, 1], shin[:, 1, 1])
        c, s = np.cos(psi), np.sin(psi)
        unturn = np.zeros((len(psi), 3, 3))
        unturn[:, 0, 0], unturn[:, 0, 1], unturn[:, 1, 0], unturn[:, 1, 1], unturn[:, 2, 2] = c, s, -s, c, 1.0
        rest = unturn @ shin  # Rx(q1) Ry(q2)
        q1, q2 = np.arctan2(rest[:, 2, 1], rest[:, 1, 1]), np.arctan2(rest[:, 0, 2], rest[:, 0, 0])
        omega = np.einsum("nij,nj->ni", unturn, det * np.array(records.omega) @ axes)
        to_model = self._to_urdf[side].T
        q, qd = np.array(records.angles) @ to_model, np.array(records.rates) @ to_model
        (roll, pitch) = self._ankles
        q[:, roll], q[:, pitch] = q1, q2
        qd[:, roll], qd[:, pitch] = omega[:, 0], omega[:, 1] / np.cos(q1)
        force = np.array(records.force)
        grf = np.column_stack([np.einsum("nij,nj->ni", unturn, force[:, :3] @ axes), det * force[:, 3]])
        return q, qd, psi, grf

    def _now(self, side: str, heading: float) -> tuple[np.ndarray, ...]:
        """``model_states`` of MuJoCo's current state alone (rows of one)."""
        records = _Records([], [], [], [], [], [], [])
        self._record(records, side)
        return self.model_states(records, side, heading) + (records.tip[0],)

    def _controls(self, torque: np.ndarray, side: str) -> np.ndarray:
        """Motor controls (N m, actuator order) of the model's joint torques ``torque`` (the
        actuated coordinates' order) with the ``side`` foot in stance."""
        full = np.zeros(self.bm.nq)
        full[self.bm.actuated] = torque
        ctrl = np.zeros(self.model.nu)
        ctrl[self._actuators] = full @ self._to_urdf[side]
        return ctrl

    def _step(self, push: np.ndarray | None = None) -> None:
        """One MuJoCo step with the pulses' controls (each times the fraction of the step it
        covers) and ``push`` (N s, world) on the trunk's CoM spread over the step."""
        t0, t1 = self.n * self.h, (self.n + 1) * self.h
        ctrl = np.zeros(self.model.nu)
        for p in self._pulses:
            overlap = min(t1, p.end) - max(t0, p.start)
            if overlap > 0:
                ctrl += p.ctrl * (overlap / self.h)
        self._pulses = [p for p in self._pulses if p.end > t1 + 1e-12]
        self.data.ctrl[:] = ctrl
        self.data.xfrc_applied[self._torso, :3] = 0.0 if push is None else push / self.h
        mujoco.mj_step(self.model, self.data)
        self.n += 1
        self.data.xfrc_applied[self._torso, :3] = 0.0
        mujoco.mj_forward(self.model, self.data)

    def _touching(self) -> set[int]:
        """The geoms touching the floor now."""
        d, out = self.data, set()
        for i in range(d.ncon):
            g1, g2 = d.contact.geom[i]
            if self._floor in (g1, g2):
                out.add(int(g2 if g1 == self._floor else g1))
        return out

    # The step ----------------------------------------------------------------------------------
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

    def walk_step(self, walker: Walker) -> StepOutcome:
        """Walk the walker's current step in MuJoCo until its touchdown (module docstring): its
        samples, and the walker's touchdown report (its impulses, applied as pulses) with MuJoCo's
        time, or the fall."""
        s = walker.state
        if not self._started:
            self.set_state(s)
            self._started = True
        half = self.pulse_duration / 2
        period, swing = walker.period, other_side(s.stance_side)
        decide_at = s.t + walker.next_period - half - DECISION_LEAD
        records = _Records([], [], [], [], [], [], [])
        applied: list[AppliedPush] = []
        decision = None
        fall = ""
        while True:
            t = self.n * self.h
            touching = self._touching()
            landed = self._foot[swing] in touching and t - s.t > 0.5 * period
            if landed or decision is None and t >= decide_at - 1e-12:
                if decision is None:
                    try:
                        decision = self._decide(walker, s, t)
                    except Fall as exc:
                        fall = str(exc)
                        break
                if landed:  # the touchdown instant opens the next step
                    break
            if self.n % self.per_sample == 0:
                self._record(records, s.stance_side)
            if touching - {self._foot["right"], self._foot["left"]}:
                fall = f"a link touched the ground at t = {t:.4f} s"
                break
            if t - s.t > 0.05 * period and self.data.site_xpos[self._tip[s.stance_side], 2] > FOOT_LIFT:
                fall = f"the stance foot left the ground at t = {t:.4f} s"
                break
            if t - s.t > 2.0 * period:
                fall = f"the swing foot did not land within 2 T = {2 * period:.3f} s"
                break
            self._step(self._due_push(walker, s, t, applied))
        q, qd, psi, grf = self.model_states(records, s.stance_side, s.heading) if records.t else (None,) * 4
        samples = [Sample(t_k, t_k - s.t, q[k], qd[k], grf[k], s.step, s.stance_side, s.stance_foot)
                   for k, t_k in enumerate(records.t)]
        walker.sample_index += len(samples)
        if fall:
            walker._pushes = []
            return StepOutcome(samples, None, fall, tuple(applied))
        return StepOutcome(samples, self._land(walker, s, decision, records, psi, grf), pushes=tuple(applied))

    def _due_push(self, walker: Walker, s: WalkState, t: float, applied: list[AppliedPush]) -> np.ndarray | None:
        """The impulse (N s, world) of the walker's pushes due in the MuJoCo step from ``t``, each
        reported as applied (its velocity jump the model's at the step's state)."""
        total = None
        while walker._pushes and walker._pushes[0].time_in_step < t + self.h - s.t:
            push = walker._pushes.pop(0)
            q = self._now(s.stance_side, s.heading)[0]
            jump = walker.trunk_push.velocity_jump(q[0], push.impulse, s.axes)
            applied.append(AppliedPush(s.step, s.stance_side, t, t - s.t, push.impulse, jump))
            total = push.impulse if total is None else total + push.impulse
        return total

    def _decide(self, walker: Walker, s: WalkState, t: float):
        """The double support planned from MuJoCo's state at ``t``: the predicted ballistic
        touchdown, the walker's re-aim and impulses there (the walker's state becomes the
        predicted next step's), the pre-impact pulse scheduled to end at the predicted touchdown."""
        q, qd, _, _, _ = self._now(s.stance_side, s.heading)
        t_hit, q_hit, qd_hit = self._predict(walker, q[0], qd[0], t - s.t)
        touchdown = walker._double_support(q_hit, qd_hit, t_hit)
        half = self.pulse_duration / 2
        start = max(t, s.t + t_hit - half)
        self._pulses.append(_Pulse(self._controls(touchdown.i_minus, s.stance_side) / half, start, start + half))
        return touchdown, s.t + t_hit, q_hit, qd_hit

    def _land(self, walker: Walker, s: WalkState, decision, records: _Records, psi, grf):
        """MuJoCo's touchdown: the post-impact pulse scheduled, the walker's state made MuJoCo's
        (in the next step's frame: its stance foot where MuJoCo put it, its heading turned by the
        new stance foot's spin), the touchdown report with MuJoCo's time."""
        touchdown, t_predicted, q_hit, qd_hit = decision
        t = self.n * self.h
        half = self.pulse_duration / 2
        self._pulses.append(_Pulse(self._controls(touchdown.i_plus, s.stance_side) / half, t, t + half))
        q_td, qd_td, _, _, _ = self._now(s.stance_side, s.heading)
        nxt = walker.state
        turn = float(self._now(nxt.stance_side, nxt.heading)[2][0])
        heading = nxt.heading + (turn if nxt.stance_side == "right" else -turn)
        q_new, qd_new, _, _, tip = self._now(nxt.stance_side, heading)
        foot = tip.copy()
        foot[2] = 0.0
        walker.state = replace(nxt, q=q_new[0], qd=qd_new[0], t=t, stance_foot=foot, heading=heading)
        fz = grf[:, 2] if grf is not None else np.zeros(0)
        horizontal = np.hypot(grf[:, 0], grf[:, 1]) if grf is not None else np.zeros(0)
        loaded = fz > 1e-3 * self.bm.total_mass * self.bm.params.gravity
        tips = np.array(records.tip) if records.tip else np.zeros((1, 3))
        self.touchdowns.append(MujocoTouchdown(
            step=s.step, t=t, t_predicted=t_predicted, q_predicted=q_hit, qd_predicted=qd_hit, q=q_td[0], qd=qd_td[0],
            peak_torque=float(np.max(np.abs(np.concatenate([touchdown.i_minus, touchdown.i_plus])))) / half,
            effort_bound=self._effort,
            friction_used=float(np.max(horizontal[loaded] / fz[loaded])) if np.any(loaded) else math.nan,
            slip=float(np.max(np.hypot(*(tips[:, :2] - tips[0, :2]).T))),
            spin=float(np.max(np.abs(psi))) if psi is not None else 0.0))
        return replace(touchdown, t=t, t_step=t - s.t)
