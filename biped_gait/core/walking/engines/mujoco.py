"""MuJoCo as the walk's engine (``engine:=mujoco``, docs/model.md section 11): each phase integrated
by MuJoCo (RK4) on the exported stance-rooted tree (``core/model/mjcf.py``, kind ``stance``: its
qpos and qvel are the model's q and qd), the phase's joint torques applied, MuJoCo's step the
largest at most ``mjcf.TIMESTEP`` that divides 1 / rate, split where a torque pulse starts or ends
or the runner asks (a push, an instant that ends a phase): each step sees one constant torque.

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
(``mj_rnePostConstraint``: the force the world exerts on the stance shin, the torques in it): the
runner checks it positive and within the friction cone of the parameter set
(``contact_friction``).

**Both feet held** (a ``Held`` motion: standing, docs/model.md section 13.2): MuJoCo integrates the
floating export instead, both point feet on its floor by its own contacts (``floating``: the
contact forces with friction are MuJoCo's, nothing holds a foot but them), the held law's torques
on its motors from the model's state measured at each MuJoCo step (held until the step's end), each
foot's contact force and how far its tip moved from where it was put down measured at the samples.

**The touchdown**: where MuJoCo's swing tip reaches the floor, located by Brent's method on
MuJoCo's last step redone in part (1e-15 s); **the passive impact** there: eqs. (8)-(9) with
MuJoCo's D_e and J2 (the ``extended`` export), then the leg exchange.

Units SI, rad; times in the step unless said "in the walk" (MuJoCo's own clock is the walk's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import mujoco
import numpy as np
from scipy.optimize import brentq

from ...dynamics.hybrid import HybridStep, impact_with
from ...model.biped import SWING_TIP
from ...model.mjcf import TIMESTEP, make_mjcf
from .engine import Contacts, Held, Motion, Pulse
from .floating import FloatingRobot

RECORD_MATCH = 1e-9  # s: a sample's instant and the grid node MuJoCo stepped to agree to rounding


@dataclass(frozen=True, eq=False)
class Record:
    """MuJoCo's state at a node of the publishing grid: time in the walk (s), q, qd, the reaction
    [Fx, Fy, Fz, Mz] at each foot on the ground (feet x 4: N, N m, model axes; the stance foot
    first), and how far each tip has moved from where it was put down (feet x 3, m; None: held there)."""

    t: float
    q: np.ndarray
    qd: np.ndarray
    forces: np.ndarray
    moved: np.ndarray | None = None


@dataclass
class MujocoWorkspace:
    """One walk in MuJoCo: the stance tree's data and the floating robot's (``floor``, made with the
    first phase that holds both feet), MuJoCo's state's time in the walk (s), the step's start in
    the walk (``origin``), the current phase's torque pulses (times in the walk), or its feet held
    (``held``: the floating robot's state is the walk's, ``measured`` the model's state measured
    from it, ``placed`` where its tips were put down, m), and the records at the grid nodes since
    the phase began."""

    data: mujoco.MjData
    floor: mujoco.MjData | None = None
    t: float = 0.0
    origin: float = 0.0
    pulses: tuple[Pulse, ...] = ()
    held: Held | None = None
    measured: tuple[np.ndarray, np.ndarray] | None = None
    placed: np.ndarray | None = None
    records: list[Record] = field(default_factory=list)
    started: bool = False


@dataclass(frozen=True)
class MujocoSegment:
    """One MuJoCo step: where it ended (s in the step) and whether the swing foot touched down in it."""

    t: float
    touchdown: bool


class MujocoEngine:
    """MuJoCo's model of ``hybrid``'s biped (module docstring); ``rate``: samples per second of
    simulated time."""

    def __init__(self, hybrid: HybridStep, rate: float) -> None:
        self.hybrid, self.bm = hybrid, hybrid.bm
        params = self.bm.params
        self.model = model = mujoco.MjModel.from_xml_string(make_mjcf(params, "stance"))
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)  # as the planner: none enforced
        self.per_sample = max(1, math.ceil(1.0 / (rate * TIMESTEP) - 1e-9))  # MuJoCo steps per sample
        self.h = 1.0 / (rate * self.per_sample)
        model.opt.timestep = self.h
        self.extended = mujoco.MjModel.from_xml_string(make_mjcf(params, "extended"))
        self.extended_data = mujoco.MjData(self.extended)  # the impact's scratch
        self._shin = model.body("stance_shin").id
        self._swing_tip = model.site(SWING_TIP).id
        self.contact_friction = params.friction

    @cached_property
    def floating(self) -> FloatingRobot:
        """The floating export both feet stand on, made with the first phase that holds them
        (a walk that never stands does without)."""
        return FloatingRobot(self.hybrid.samples, self.h)

    def workspace(self) -> MujocoWorkspace:
        return MujocoWorkspace(mujoco.MjData(self.model))

    # MuJoCo ------------------------------------------------------------------------------------
    def _torque(self, ws: MujocoWorkspace, t0: float, t1: float | None = None) -> np.ndarray:
        """The pulses' joint torques (N m, q order) at ``t0``, or their mean over [t0, t1] (s in the walk)."""
        torque = np.zeros(self.model.nv)
        for p in ws.pulses:
            if t1 is None:
                torque += p.torque if p.start <= t0 < p.end else 0.0
            elif (overlap := min(t1, p.end) - max(t0, p.start)) > 0:
                torque += p.torque * (overlap / (t1 - t0))
        return torque

    def _set(self, ws: MujocoWorkspace, q: np.ndarray, qd: np.ndarray, t: float) -> None:
        """MuJoCo's state: (``q``, ``qd``) at ``t`` (s in the walk), its derived quantities computed
        with the torques acting then."""
        d = ws.data
        d.qpos[:], d.qvel[:], d.time = q, qd, t
        ws.t = t
        d.qfrc_applied[:] = self._torque(ws, t)
        mujoco.mj_forward(self.model, d)

    def _advance(self, ws: MujocoWorkspace, t_end: float) -> None:
        """One MuJoCo RK4 step to ``t_end`` (s in the walk) with the pulses' mean torques over it
        (each pulse times the fraction of the step it covers)."""
        d = ws.data
        d.qfrc_applied[:] = self._torque(ws, ws.t, t_end)
        self.model.opt.timestep = t_end - ws.t
        mujoco.mj_step(self.model, d)
        self._set(ws, d.qpos.copy(), d.qvel.copy(), t_end)

    def _hold(self, ws: MujocoWorkspace) -> None:
        """The floating robot's state measured, the held law's torques at it applied (until the next
        step's end: the control rate is MuJoCo's step's)."""
        ws.measured = self.floating.measure(ws.floor)
        self.floating.apply(ws.floor, ws.held.law(ws.t - ws.origin, *ws.measured))

    def _reaction(self, ws: MujocoWorkspace) -> np.ndarray:
        """[[Fx, Fy, Fz, Mz]] (1 x 4: N, N m, the step's model axes) the ground exerts on the stance tip
        now: MuJoCo's interaction force of the stance shin with the world (the pulses' torques in it)."""
        d = ws.data
        mujoco.mj_rnePostConstraint(self.model, d)
        wrench = d.cfrc_int[self._shin]  # [moment about the c-frame's origin; force], world axes
        cx, cy, _ = d.subtree_com[self._shin]  # the c-frame's origin; the tip is the world origin
        fx, fy, fz = wrench[3:]
        return np.array([[fx, fy, fz, wrench[2] + cx * fy - cy * fx]])

    def _tip_height(self, ws: MujocoWorkspace) -> float:
        return float(ws.data.site_xpos[self._swing_tip, 2])

    def _record(self, ws: MujocoWorkspace) -> None:
        """Keep MuJoCo's state if it is at a node of the publishing grid (and not kept yet)."""
        grid = round(ws.t / self.h)
        if abs(ws.t - grid * self.h) < 1e-12 and grid % self.per_sample == 0 and not (
                ws.records and abs(ws.records[-1].t - ws.t) < RECORD_MATCH):
            if ws.held is not None:  # the contact forces with the torques applied now
                floating, d = self.floating, ws.floor
                mujoco.mj_forward(floating.model, d)
                ws.records.append(Record(ws.t, *ws.measured, floating.contact_forces(d), floating.tips(d) - ws.placed))
            else:
                ws.records.append(Record(ws.t, ws.data.qpos.copy(), ws.data.qvel.copy(), self._reaction(ws)))

    def _land_on_ground(self, ws: MujocoWorkspace, t0: float, q0: np.ndarray, qd0: np.ndarray) -> None:
        """The swing tip went below the floor in the MuJoCo step from ``t0`` (state ``q0``, ``qd0``)
        to now: redo that step in part, to where the tip is on the floor (Brent's method on the
        step's end, 1e-15 s)."""
        t1 = ws.t

        def height(t: float) -> float:
            self._set(ws, q0, qd0, t0)
            self._advance(ws, t)
            return self._tip_height(ws)

        start = t0 + 1e-15
        height(start if height(start) <= 0.0 else brentq(height, start, t1, xtol=1e-15, rtol=1e-15))

    # The engine --------------------------------------------------------------------------------
    def begin(self, ws: MujocoWorkspace, motion: Motion, origin: float, t: float, q: np.ndarray, qd: np.ndarray) -> None:
        ws.origin = origin
        ws.pulses = tuple(Pulse(p.torque, origin + p.start, origin + p.end) for p in motion.pulses)
        ws.held = motion.held
        ws.records = [r for r in ws.records if r.t > origin + t - RECORD_MATCH]
        if motion.held is not None:
            if ws.floor is None:
                ws.floor = self.floating.data()
            if ws.measured is None or not (np.array_equal(q, ws.measured[0]) and np.array_equal(qd, ws.measured[1])):
                self.floating.place(ws.floor, q, qd)  # onto the floor: the walk's start, or a state given
                ws.floor.time = ws.t = origin + t
                mujoco.mj_kinematics(self.floating.model, ws.floor)
                ws.placed = self.floating.tips(ws.floor)
            self._hold(ws)
        else:
            ws.measured = None  # off the floor
            if not ws.started or not (np.array_equal(q, ws.data.qpos) and np.array_equal(qd, ws.data.qvel)):
                self._set(ws, q, qd, origin + t)  # the walk's start, or a state the runner was given (a shove)
        ws.started = True
        self._record(ws)

    def advance(self, ws: MujocoWorkspace, motion: Motion, t_stop: float, touchdown_after: float) -> MujocoSegment:
        t0, q0, qd0 = ws.t, ws.data.qpos.copy(), ws.data.qvel.copy()
        t_next = min([(math.floor(ws.t / self.h + 1e-9) + 1) * self.h, ws.origin + t_stop]  # the grid, or a cut
                     + [b for p in ws.pulses for b in (p.start, p.end) if b > ws.t + 1e-12])  # or a pulse's start or end
        if ws.held is not None:  # on the floor: one step of the held law's torques, then measured
            self.floating.model.opt.timestep = t_next - ws.t
            mujoco.mj_step(self.floating.model, ws.floor)
            ws.t = t_next
            self._hold(ws)
            self._record(ws)
            return MujocoSegment(ws.t - ws.origin, False)
        self._advance(ws, t_next)
        if ws.t - ws.origin > touchdown_after and self._tip_height(ws) <= 0.0:
            self._land_on_ground(ws, t0, q0, qd0)
            return MujocoSegment(ws.t - ws.origin, True)
        self._record(ws)
        return MujocoSegment(ws.t - ws.origin, False)

    def state(self, ws: MujocoWorkspace) -> tuple[np.ndarray, np.ndarray]:
        if ws.held is not None:
            return ws.measured[0].copy(), ws.measured[1].copy()
        return ws.data.qpos.copy(), ws.data.qvel.copy()

    def set_velocity(self, ws: MujocoWorkspace, qd: np.ndarray) -> None:
        if ws.held is not None:
            self.floating.set_velocity(ws.floor, ws.measured[0], qd)
            self._hold(ws)
        else:
            self._set(ws, ws.data.qpos.copy(), qd, ws.t)

    def sample(self, ws: MujocoWorkspace, segments: list[MujocoSegment], taus: list[float],
               jumps: list[float]) -> tuple[np.ndarray, np.ndarray, Contacts]:
        """The records at the samples' instants: MuJoCo's steps end on every node of the grid."""
        rows, records, k = [], ws.records, 0
        for tau in taus:  # both in time order
            t = ws.origin + tau
            while k < len(records) and records[k].t < t - RECORD_MATCH:
                k += 1
            if k == len(records) or records[k].t > t + RECORD_MATCH:
                raise RuntimeError(f"MuJoCo did not step to the sample's instant {t:.9f} s")
            rows.append(records[k])
        moved = None if any(r.moved is None for r in rows) else np.array([r.moved for r in rows])
        return (np.array([r.q for r in rows]), np.array([r.qd for r in rows]),
                Contacts(np.array([r.forces for r in rows]), moved))

    def passive_impact(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Eqs. (8)-(9) at ``q`` from ``qd`` with MuJoCo's D_e and J2 (the ``extended`` export; a
        foot's spin row, with hip roll and yaw joints, the planner's), then the leg exchange."""
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
