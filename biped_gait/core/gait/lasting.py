"""A double support that lasts d seconds between the paper's two impulses (docs/model.md section 14).

The cycle, after the gait's ballistic single support (its arrival velocity Xd^b at the touchdown
configuration q_T):

1. I^-: impulsive joint torques, the old stance tip held (paper eqs. 6-7);
2. the touchdown, a passive impact with both tips held (``closed_chain.impact``'s equations): both
   tips' impulses press on the ground and lie in their friction pyramids;
3. d seconds of double support: the closed chain of section 12 under finite torques Gamma(t),
   both tips fixed, both reactions in their pyramids with non-negative normal force, every
   |Gamma_j| within the joint table's effort, the joints within their ranges;
4. I^+: impulsive joint torques at lift-off, the new tip held, the old one leaving with the
   velocity the next step starts with (paper eq. 10);
5. the next ballistic single support, from the lift-off posture to the touchdown posture in T.

The touchdown posture is the d = 0 gait's q_T; the lift-off posture is free on the closed chain
(project choice): the impulses cannot change the momentum about the feet line, and over the phase
only gravity does (m g times the integral of the centre of mass's distance from the line), so the
body rolls over the line and cannot be back at q_T. The next single support therefore starts from
the lift-off posture (legs exchanged) and must reach q_T in T: its start velocity is an unknown and
the planner's shooting flow, with its exact sensitivities, is a constraint of the same program
(``flow_function``). The kinds of program (``KINDS``): ``periodic`` that cycle; ``limit`` its
d -> 0+ limit (the impulses and the held impact, the held velocity one the closed chain can carry);
``stop`` from the gait's touchdown to rest in a standing posture on the same feet; ``start`` from
rest there onto the gait (a double support, then I^+).

The phase is transcribed by Hermite-Simpson collocation (compressed form) in inverse-dynamics
form: q, qd, qdd, Gamma and the new tip's reaction at every node and midpoint, the equations of
motion and the new tip's held acceleration as equality constraints at each (so that the forces are
those of the closed chain under the torques, which a walk tracking the plan feeds forward); where
the phase ends at a given posture (the stop, the start) also the tip's position and velocity at the
nodes, the defects corrected along the held rows (Posa, Kuindersma and Tedrake 2016); the old
tip's reaction is the double-support model's root rows. The impulses' equations are linear
at q_T (I^+'s, at the lift-off posture, are not). The whole is one nonlinear program solved by
IPOPT (CasADi's, with MUMPS) with exact first derivatives from ``core/dynamics/symbolic.py`` and
the flow's sensitivities. The effort minimized is

    E = Sum |I^-| + integral Sum |Gamma_j| dt + Sum |I^+|            (N m s, ``l1``)

or E2 = Sum (I^-)^2 + integral Gamma' Gamma dt + Sum (I^+)^2 (``l2``).

With lateral hip joints (``aoustin2013-hips``) the double-support model has the old stance foot's
spin among its root coordinates (``biped.STANCE_SPIN``, held at zero: its moment is a root row of
the inverse dynamics, as the old tip's force), and the new foot is held in x, y, z and in its
heading (``_held_quantities``), each with a reaction unknown (a spin moment for the heading); the
impulses' equations hold the same rows. The leg exchange is then ``KinematicExchange``'s, not
linear: the periodic program writes it in symbols (``_next_step``), the next start posture and
the velocity after I^+ unknowns tied to the lift-off posture by the landing shin's Euler angles.
Each spin moment (and moment impulse) stays within the feet's torsional friction, |M| <=
``mjcf.TORSIONAL_FRICTION`` F_z (0.05 m, MuJoCo's): the paper's pivot holds any, and with it free
the optimum twists the feet against the floor with the hips' yaw at its 200 N m limit.

Units SI, rad; forces N, impulses N s, joint impulses N m s.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.flow import BallisticFlow
from ..dynamics.impulses import pyramid
from ..dynamics.symbolic import SymbolicModel
from ..model.biped import STANCE_SPIN, STANCE_TIP, SWING_TIP, BipedModel
from ..model.exchange import MIRROR
from ..model.mjcf import TORSIONAL_FRICTION
from .flow_function import CoupledConstraints, FlowFunction
from .lasting_support import IMPULSE_TIME, LastingSupport
from .solve_cache import cached

# Hermite-Simpson intervals over d (2 n + 1 collocation points, nodes and midpoints), by kind. The
# stop and the start (a second or so) on 10: on 20 IPOPT did not finish either at d = 1 s (1,000
# iterations; infeasibility detected) where on 10 it does (about 120 and 330 iterations).
INTERVALS = {"periodic": 20, "stop": 10, "start": 10, "limit": 0}
# With lateral hip joints the walked cycle needs a finer mesh (docs/model.md 14.1). Walked by the
# hybrid engine from its lift-off (d = 0.1 s, the default gait), the touchdowns' distance to the
# plan grows by about 0.01 rad/s a step on 20 intervals, the stance foot slipping in the 20th step
# (0.585 > 0.5), though the plan's reference keeps 49.1 N between its points (50 at them); on 30 it
# stays within 1.6e-3 rad/s over 40 steps (on 40, 0.014 over 30: which mesh the walk follows best
# is measured, not monotone). Measured 2026-12-06; a cold solve takes about 80 s on 30, 40 s on 20.
LATERAL_HIPS_PERIODIC = 30
TOLERANCE = 1e-9  # IPOPT's tolerance on the scaled KKT conditions and on the constraint violation
MAX_ITERATIONS = 1000  # the solves that converge take 200 to 600
# The unknowns' magnitudes (``_Program.var``); forces and impulses scale with the weight.
TORQUE = 100.0  # N m
JOINT_IMPULSE = 10.0  # N m s
ACCELERATION = 10.0  # rad/s^2
CORRECTION = 1e-6  # m, m/s: the collocation defects' corrections along the held rows (the rule's error)
KINDS = ("periodic", "stop", "start", "limit")
# The margins a walked plan keeps (``LastingRequest.walkable``). Without them the least-effort plan
# rides its constraints (a foot's normal force down to 0, the friction used 0.49 of 0.5, the old foot
# leaving passively) and a walk that tracks it loses a foot, or its lift-off, at its first errors
# (docs/model.md 14.1). At the default gait and d = 0.1 s they cost E = 63.27 against 62.50 N m s.
WALK_LEAST_NORMAL_FORCE = 50.0  # N: about a tenth of the weight, on each foot throughout
WALK_FRICTION_MARGIN = 0.1  # the reactions and impulses within mu - 0.1
WALK_PUSH_OFF = 2.0  # N s: the old foot's least vertical impulse at I^+ (the weight over 4 ms)
# IPOPT started at a nearby solution with its multipliers: the barrier parameter from near its end,
# the point pushed off its bounds by as little as the multipliers are.
WARM_START = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6, "ipopt.warm_start_bound_push": 1e-9,
              "ipopt.warm_start_slack_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9}


def hermite_simpson(first, last, a_mid, h):
    """The Hermite-Simpson rule (compressed form) over one interval of ``h`` s from ``first`` to
    ``last`` (each (q, v, a)) with the midpoint's acceleration ``a_mid``: the midpoint's q and v and
    the interval's defects in q and v (zero on a solution)."""
    (q0, v0, a0), (q, v, a) = first, last
    q_mid = (q0 + q) / 2 + h / 8 * (v0 - v)
    v_mid = (v0 + v) / 2 + h / 8 * (a0 - a)
    return q_mid, v_mid, q - q0 - h / 6 * (v0 + 4 * v_mid + v), v - v0 - h / 6 * (a0 + 4 * a_mid + a)


@dataclass(frozen=True)
class LastingRequest:
    """What the double support is asked: its duration (s), the effort to minimize (``l1`` or
    ``l2``), and the margins a walk tracking it needs (none by default): the least normal force
    each foot keeps over the phase (``least_normal_force``, N), how far within the floor's
    friction coefficient its reactions and impulses stay (``friction_margin``), and the least
    vertical impulse with which the old foot pushes off at I^+ (``push_off``, N s; 0: none, it
    leaves passively as the paper's; the periodic cycle only)."""

    duration: float
    effort: str = "l1"
    least_normal_force: float = 0.0
    friction_margin: float = 0.0
    push_off: float = 0.0

    @classmethod
    def walkable(cls, duration: float, effort: str = "l1") -> "LastingRequest":
        """The double support of ``duration`` s with the margins a walk tracking it needs
        (``WALK_LEAST_NORMAL_FORCE``, ``WALK_FRICTION_MARGIN``, ``WALK_PUSH_OFF``)."""
        return cls(duration, effort, WALK_LEAST_NORMAL_FORCE, WALK_FRICTION_MARGIN, WALK_PUSH_OFF)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.duration) and self.duration >= 0.0):
            raise ValueError(f"double_support must be a duration >= 0 s, got {self.duration!r}")
        if self.effort not in ("l1", "l2"):
            raise ValueError(f"effort must be l1 or l2, got {self.effort!r}")
        if not (math.isfinite(self.least_normal_force) and self.least_normal_force >= 0.0):
            raise ValueError(f"the least normal force must be >= 0 N, got {self.least_normal_force!r}")
        if not (math.isfinite(self.friction_margin) and self.friction_margin >= 0.0):
            raise ValueError(f"the friction margin must be >= 0, got {self.friction_margin!r}")
        if not (math.isfinite(self.push_off) and self.push_off >= 0.0):
            raise ValueError(f"the push-off must be >= 0 N s, got {self.push_off!r}")


@dataclass(frozen=True, eq=False)
class Boundary:
    """The ends of a double support: the gait's touchdown configuration q_T (rad, single-support
    coordinates), its arrival velocity Xd^b and the next step's start Xd^a (double-support
    coordinates X, this step's frame), the standing posture on the same two feet (rad; the stop's end,
    the start's beginning) and the gait's period T (s)."""

    q_t: np.ndarray
    xd_b: np.ndarray
    xd_a: np.ndarray
    q_rest: np.ndarray
    period: float


class _Program:
    """A nonlinear program being written: unknowns with bounds, constraints, cost terms."""

    def __init__(self) -> None:
        self.w, self.lbw, self.ubw, self.names = [], [], [], []
        self.g, self.lbg, self.ubg, self.cost = [], [], [], []
        self.scales: list[np.ndarray] = []
        self.size = 0
        self.where: dict[str, int] = {}  # the first offset of each unknown's name
        self.rows: list[str] = []  # what each constraint row is
        self.last_node_q = 0  # the offset of the phase's last node's q (``LastingProgram._phase``)

    def var(self, name: str, size: int, lower=-np.inf, upper=np.inf, scale: float = 1.0):
        """An unknown of ``size``; the program holds it divided by ``scale``, its magnitude (IPOPT
        does not scale unknowns: forces of hundreds of N beside angles of a fraction of a rad make
        its Newton steps ill-conditioned)."""
        v = ca.SX.sym(name, size)
        self.where.setdefault(name, self.size)
        self.size += size
        self.w.append(v)
        self.scales.append(np.full(size, scale))
        self.lbw.append(np.broadcast_to(lower, (size,)).astype(float) / scale)
        self.ubw.append(np.broadcast_to(upper, (size,)).astype(float) / scale)
        self.names.append((name, size))
        return scale * v

    def eq(self, expr, what: str) -> None:
        self.rows += [what] * expr.shape[0]
        self.g.append(expr)
        self.lbg.append(np.zeros(expr.shape[0]))
        self.ubg.append(np.zeros(expr.shape[0]))

    def le(self, expr, what: str, upper: float = 0.0) -> None:
        """expr <= upper."""
        self.within(expr, what, upper, -np.inf)

    def within(self, expr, what: str, upper: float, lower: float | None = None) -> None:
        """lower <= expr <= upper (lower None: -upper)."""
        self.rows += [what] * expr.shape[0]
        self.g.append(expr)
        self.lbg.append(np.full(expr.shape[0], -upper if lower is None else lower))
        self.ubg.append(np.full(expr.shape[0], upper))


class LastingProgram:
    """The nonlinear program of a double support of ``intervals`` collocation intervals for the
    model ``bm`` (built once, solved for any gait and duration: those are its parameters)."""

    SOLVER_OPTIONS: dict = {}  # IPOPT's options beyond the module's (a program with more phases sets its own)

    def __init__(self, bm: BipedModel, kind: str, intervals: int, effort: str = "l1",
                 friction: float = 0.5, exchange=None, flow: BallisticFlow | None = None) -> None:
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
        if (kind == "limit") != (intervals == 0):
            raise ValueError("the limit d -> 0+ has no phase between its impulses (intervals 0), the others some")
        self.bm, self.kind, self.intervals, self.effort, self.friction = bm, kind, intervals, effort, friction
        if kind == "periodic" and (exchange is None or flow is None):
            raise ValueError("a periodic double support needs the leg exchange and the ballistic flow")
        self.exchange, self.flow = exchange, flow
        self.sym = SymbolicModel(bm.double_support)
        self.nq, self.nx, self.na = bm.nq, bm.double_support.nv, len(bm.actuated)
        self.at = np.asarray(bm.ds_of_single)
        self.roots = np.setdiff1d(np.arange(self.nx), self.at)
        self.lateral_free = not bm.params.joints.lateral_hips
        # The new tip's held rows: x and z with legs of pitch joints (section 12); with lateral hip
        # joints x, y, z and the new foot's heading (``_held_quantities``).
        self.rows = [0, 2] if self.lateral_free else [0, 1, 2, 3]
        self.reaction_size = 3 if self.lateral_free else 4  # a tip's reaction: force, and spin moment with lateral hips
        self.actuated = np.asarray(bm.actuated)
        self.effort_limits = np.array([bm.coordinates[k].spec.limits.effort for k in self.actuated])  # N m
        self.weight = bm.total_mass * bm.params.gravity
        self.impulse_scale = self.weight * IMPULSE_TIME
        self._build()

    # The model's pieces as CasADi functions --------------------------------------------------------
    def _embed(self, q):
        x = ca.SX.zeros(self.nx)
        x[self.at.tolist()] = q
        return x

    def _functions(self) -> None:
        """The tips' positions and Jacobians, the inverse dynamics, the new tip's acceleration and
        the mass matrix over X, as CasADi functions."""
        nx = self.nx
        xs, vs, a_s = ca.SX.sym("x", nx), ca.SX.sym("v", nx), ca.SX.sym("a", nx)
        tip = self._held_quantities(xs)
        old = ca.jacobian(self.sym.frame_position(xs, STANCE_TIP), xs)
        if not self.lateral_free:  # the old foot's spin, a coordinate of X, held at zero
            old = ca.vertcat(old, ca.DM(np.eye(nx)[[self.bm.ds_names.index(STANCE_SPIN)]]))
        self.f_tip = ca.Function("tip", [xs], [tip, ca.jacobian(tip, xs), old])
        if not self.lateral_free:  # the landing shin's roll and pitch, and their rates
            angles = ca.vertcat(*self._landing(xs)[1:])
            self.f_landing = ca.Function("landing", [xs, vs], [angles, ca.jtimes(angles, xs, vs)])
        self.f_rnea = ca.Function("rnea", [xs, vs, a_s], [self.sym.rnea(xs, vs, a_s)])
        # The new tip's acceleration J a + (d(J v)/dX) v: held at every collocation point.
        self.f_tip_acceleration = ca.Function("tip_acceleration", [xs, vs, a_s], [
            ca.jtimes(tip, xs, a_s) + ca.jtimes(ca.jtimes(tip, xs, vs), xs, vs)])
        self.f_mass = ca.Function("mass", [xs], [ca.jacobian(self.sym.rnea(xs, ca.SX.zeros(nx), a_s), a_s)])

    def _landing(self, x) -> tuple:
        """(phi, roll, pitch) of the new stance shin at X: its mirror image M R M = Rz(phi)
        Rx(roll) Ry(pitch) (``KinematicExchange._landing``), as CasADi expressions."""
        shin = self.bm.double_support.getJointId(self.bm.names[self.bm.index("knee", "swing")])
        r = self.sym.placements(x)[shin - 1][0]
        landing = ca.mtimes([ca.DM(MIRROR), r, ca.DM(MIRROR)])
        return (ca.atan2(-landing[0, 1], landing[1, 1]), ca.asin(landing[2, 1]),
                ca.atan2(-landing[2, 0], landing[2, 2]))

    def _held_quantities(self, x):
        """What the ground holds of the new foot at X: its tip's position (m), and with lateral hip
        joints its heading phi (rad), the new stance shin's turn about the vertical, which the
        ground's spin moment keeps at its touchdown value (its rate is zero where
        ``KinematicExchange.spin_row``'s is: both say the shin turns about its pivot's roll and
        pitch axes only)."""
        tip = self.sym.frame_position(x, SWING_TIP)
        return tip if self.lateral_free else ca.vertcat(tip, self._landing(x)[0])

    def _terms(self, nlp: "_Program", p_mu):
        """``press(force, what, least=0)``: a reaction that presses (by ``least``, N) within the
        floor's pyramid of coefficient ``p_mu`` (the impulses' inscribed one, section 4.4);
        ``cost(values, weight, scale)``: the effort term of ``values`` (``l1`` through slacks)."""
        sides = None
        if math.isfinite(self.friction):
            unit = pyramid(1.0)
            sides = ca.horzcat(ca.DM(unit[:, :2]), p_mu * ca.DM(unit[:, 2]))

        def press(force, what, least=0.0):
            nlp.le(least - force[2], f"{what} presses")
            if sides is not None:
                nlp.le(ca.mtimes(sides, force[:3]), f"{what} within the friction pyramid")
            if force.shape[0] == 4:  # a spin moment: within the foot's torsional friction
                nlp.le(ca.vertcat(force[3], -force[3]) - TORSIONAL_FRICTION * force[2],
                       f"{what}'s spin moment within the torsional friction")

        def cost(values, weight, scale):
            if self.effort == "l1":
                s = nlp.var("s", values.shape[0], 0.0, scale=scale)
                nlp.le(values - s, "effort")
                nlp.le(-values - s, "effort")
                nlp.cost.append(weight * ca.sum1(s))
            else:
                nlp.cost.append(weight * ca.sumsqr(values))

        return press, cost

    def _actuation(self) -> ca.DM:
        """B: the actuated joints' columns in X's rows (nX x na)."""
        b = np.zeros((self.nx, self.na))
        b[self.at[self.actuated], np.arange(self.na)] = 1.0
        return ca.DM(b)

    def _build(self) -> None:
        nq, nx, na, n_int = self.nq, self.nx, self.na, self.intervals
        at = self.at.tolist()
        periodic = self.kind == "periodic"
        arrives, departs = self.kind in ("stop", "limit", "periodic"), self.kind in ("start", "limit", "periodic")
        self._functions()

        # Parameters: the gait's touchdown q_T, Xd^b and Xd^a there, the posture at rest, d.
        p_q, p_rest = ca.SX.sym("q_t", nq), ca.SX.sym("q_rest", nq)
        p_xb, p_xa = ca.SX.sym("xd_b", nx), ca.SX.sym("xd_a", nx)
        p_d = ca.SX.sym("d")
        # The margins: the least normal force at each tip over the phase (N), the friction
        # coefficient the reactions and impulses keep within.
        p_least, p_mu = ca.SX.sym("least_normal_force"), ca.SX.sym("friction")
        tip_t, j2_t, j1_t = self.f_tip(self._embed(p_q))
        d_t = self.f_mass(self._embed(p_q))
        b = self._actuation()
        nlp = _Program()
        press, cost = self._terms(nlp, p_mu)

        outputs = {}
        if periodic:
            # The next step's start velocity (its own coordinates) and the ballistic flow's end
            # [q(T); qd(T)] from the lift-off posture, tied to the flow outside the SX program.
            qd_next = nlp.var("qd_next", nq)
            flow_end = nlp.var("flow_end", 2 * nq)
            nlp.eq(flow_end[:nq] - p_q, "the single support reaches the touchdown posture")
            p_xb = self._embed(flow_end[nq:])
            outputs.update(qd_next=qd_next, flow_end=flow_end)
        if arrives:
            # I^-: the old tip held (eqs. 6-7), the swing tip coming down onto the ground.
            xm, im = nlp.var("xd_minus", nx), nlp.var("i_minus", na, scale=JOINT_IMPULSE)
            r1m = nlp.var("r1_minus", self.reaction_size, scale=self.impulse_scale)
            nlp.eq(ca.mtimes(d_t, xm - p_xb) - ca.mtimes(b, im) - ca.mtimes(j1_t.T, r1m), "I^- (eq. 6)")
            nlp.eq(ca.mtimes(j1_t, xm), "I^- (eq. 7)")
            press(r1m, "the old tip's reaction to I^-")
            nlp.le(ca.mtimes(j2_t[2, :], xm), "the swing tip comes down")
            cost(im, 1.0, JOINT_IMPULSE)
            xh, p1, p2 = self._held_impact(nlp, xm, (d_t, j1_t, j2_t), press)
            outputs.update(i_minus=im, p_old=p1, p_new=p2)
        x_end = xh if self.kind == "limit" else None
        if self.kind == "limit":
            # The held velocity must be one the closed chain can carry for an instant: some torques
            # within their limits keep both reactions pressing (what any d > 0 asks from its start).
            effort_limit = self.effort_limits
            self._held(nlp, p_q, xh[at], nlp.var("a", nq, scale=ACCELERATION),
                       nlp.var("tau", na, -effort_limit, effort_limit, TORQUE),
                       nlp.var("f_new", self.reaction_size, scale=self.weight), b, press, p_least)
        if n_int > 0:
            points = self._phase(nlp, p_d, p_q if arrives else p_rest, xh[at] if arrives else None,
                                 None if periodic else (p_q if departs else p_rest), not departs, tip_t, b, press, cost,
                                 p_least)
            outputs.update({key: ca.horzcat(*[pt[i] for pt in points]).T
                            for i, key in enumerate(("q", "v", "a", "tau", "f_old", "f_new"))})
            x_end = self._embed(points[-1][1])
        if departs:
            # I^+: the new tip held, onto Xd^a (eq. 10), at the lift-off posture.
            ip = nlp.var("i_plus", na, scale=JOINT_IMPULSE)
            r2p = nlp.var("r2_plus", self.reaction_size, scale=self.impulse_scale)
            d_l, j2_l, xd_a = d_t, j2_t, p_xa
            push = ca.DM.zeros(nx)
            if periodic:
                q_l = points[-1][0]
                _, j2_l, j1_l = self.f_tip(self._embed(q_l))
                d_l = self.f_mass(self._embed(q_l))
                if self.lateral_free:
                    qd = ca.mtimes(ca.DM(self.exchange.inverse), qd_next)
                    xd_a = ca.vertcat(-ca.mtimes(j2_l[:, 3:], qd), qd)  # LinearExchange.next_velocity
                else:
                    xd_a = self._next_step(nlp, q_l, j2_l, qd_next)
                nlp.le(-xd_a[2], "the old tip leaves the ground")
                # The old tip's push-off, if the request asks for one (its bounds, ``solve``): a force
                # impulse (the foot leaves, its spin free).
                r1p = nlp.var("r1_plus", 3, scale=self.impulse_scale)
                press(r1p, "the old tip's push-off")
                push = ca.mtimes(j1_l[:3, :].T, r1p)
                outputs["push_off"] = r1p
            nlp.eq(ca.mtimes(d_l, xd_a - x_end) - ca.mtimes(b, ip) - ca.mtimes(j2_l.T, r2p) - push, "I^+ (eq. 10)")
            press(r2p, "the new tip's reaction to I^+")
            cost(ip, 1.0, JOINT_IMPULSE)
            outputs["i_plus"] = ip
        params = ca.vertcat(p_q, p_rest, ca.SX.sym("xd_b", nx) if periodic else p_xb, p_xa, p_d, p_least, p_mu)
        start_map = None
        if periodic:  # the flow starts from the lift-off posture exchanged, with the next step's velocity
            start_map = np.zeros((2 * nq, nlp.size))
            if self.lateral_free:
                start_map[:nq, nlp.last_node_q:nlp.last_node_q + nq] = self.exchange.matrix
            else:
                start_map[:nq, nlp.where["q_next"]:nlp.where["q_next"] + nq] = np.eye(nq)
            start_map[nq:, nlp.where["qd_next"]:nlp.where["qd_next"] + nq] = np.eye(nq)
        self._finish(nlp, params, outputs, start_map)

    def _next_step(self, nlp: "_Program", q_l, j2_l, qd_next):
        """With lateral hip joints, the leg exchange at the lift-off posture ``q_l`` written into the
        program (``KinematicExchange``'s maps, symbolic): the next step's start posture ``q_next``,
        an unknown, is the joint map of ``q_l`` with the new stance ankle's roll and pitch those of
        the landing shin (``_landing``); the velocity after I^+ (X, returned), an unknown, holds the
        new tip at rest and its foot's heading (``j2_l``), and maps onto ``qd_next`` by the joint
        map and the rates of the landing shin's roll and pitch. The heading phi itself is the new
        foot's, held from the touchdown (zero on a straight gait: the cycle does not turn)."""
        q_next, xd_a = nlp.var("q_next", self.nq), nlp.var("xd_next", self.nx)
        posture, velocity = self._exchanged(q_l, xd_a[self.at.tolist()], xd_a)
        nlp.eq(q_next - posture, "the next step's start posture (the leg exchange)")
        nlp.eq(qd_next - velocity, "the next step's start velocity (the leg exchange)")
        nlp.eq(ca.mtimes(j2_l, xd_a), "the new tip at rest after I^+, its foot not turning")
        return xd_a

    def _exchanged(self, q_l, v_l, xd):
        """The leg exchange at the lift-off (symbolic): the next step's start posture and velocity
        from the lift-off posture ``q_l`` and joint rates ``v_l`` (X's velocity ``xd``, whose old
        tip may be leaving). Legs of pitch joints: the exchange's matrix; with lateral hips: its
        joint map, the new stance ankle's roll and pitch those of the landing shin."""
        if self.lateral_free:
            matrix = ca.DM(self.exchange.matrix)
            return ca.mtimes(matrix, q_l), ca.mtimes(matrix, v_l)
        angles, rates = self.f_landing(self._embed(q_l), xd)
        ankle = [self.bm.index("ankle_roll"), self.bm.index("ankle_pitch")]
        posture, velocity = [None] * self.nq, [None] * self.nq
        for i, j, sign in self.exchange.joints:
            posture[i], velocity[i] = sign * q_l[j], sign * v_l[j]
        for k, i in enumerate(ankle):
            posture[i], velocity[i] = angles[k], rates[k]
        return ca.vertcat(*posture), ca.vertcat(*velocity)

    def _finish(self, nlp: "_Program", params, outputs: dict, start_map: np.ndarray | None) -> None:
        """The program written (``nlp``, its parameters ``params``) made a solver, with the
        ballistic flow's constraint if ``start_map`` (the unknowns to the flow's start) is given,
        its end the unknown ``flow_end``; ``outputs`` a function of the solution."""
        self.names = nlp.names
        self.lbw, self.ubw = np.concatenate(nlp.lbw), np.concatenate(nlp.ubw)
        self.lbg, self.ubg = np.concatenate(nlp.lbg), np.concatenate(nlp.ubg)
        self.row_names = nlp.rows
        self.scale = np.concatenate(nlp.scales)
        w = ca.vertcat(*nlp.w)
        problem = {"x": w, "f": sum(nlp.cost), "g": ca.vertcat(*nlp.g), "p": params}
        self.where = nlp.where
        options = {"ipopt.tol": TOLERANCE, "ipopt.constr_viol_tol": TOLERANCE, "ipopt.print_level": 0,
                   "ipopt.max_iter": MAX_ITERATIONS, "print_time": False, "ipopt.sb": "yes", **self.SOLVER_OPTIONS}
        if start_map is not None:
            problem = self._with_flow(problem, nlp, start_map)
            # The ballistic flow's second derivatives are not computed. Measured: the exact Hessian
            # of the rest with the flow's curvature left out stalls (3000 iterations at d = 0.1 s
            # at the default gait), where the limited-memory approximation converges (about 200).
            options["ipopt.hessian_approximation"] = "limited-memory"
        self.solver = ca.nlpsol(f"{self.kind}_double_support", "ipopt", problem, options)
        self._warm = (problem, {**options, **WARM_START})
        self.outputs = ca.Function("outputs", [w, params], list(outputs.values()), ["w", "p"], list(outputs))

    def _held_impact(self, nlp: "_Program", xm, at_touchdown: tuple, press) -> tuple:
        """The passive impact from the velocity ``xm`` with both tips held (``at_touchdown``: the
        mass matrix and the old and new tip's Jacobians there): the held velocity and both tips'
        impulses, each pressing within the pyramid."""
        d_t, j1_t, j2_t = at_touchdown
        xh = nlp.var("xd_held", self.nx)
        p1 = nlp.var("p_old", self.reaction_size, scale=self.impulse_scale)
        p2 = nlp.var("p_new", self.reaction_size, scale=self.impulse_scale)
        nlp.eq(ca.mtimes(d_t, xh - xm) - ca.mtimes(j1_t.T, p1) - ca.mtimes(j2_t.T, p2), "the held impact")
        nlp.eq(ca.mtimes(j1_t, xh), "the held impact: old tip at rest")
        nlp.eq(ca.mtimes(j2_t[self.rows, :], xh), "the held impact: new tip at rest")
        press(p1, "the held impact's old tip impulse")
        press(p2, "the held impact's new tip impulse")
        return xh, p1, p2

    def _with_flow(self, problem: dict, nlp: "_Program", start_map: np.ndarray) -> dict:
        """The SX program with the ballistic flow's constraint added: the flow's end, unknowns of the
        program (``flow_end``), equals the flow from ``start_map`` times the unknowns
        (``flow_function.CoupledConstraints``)."""
        nq, nw = self.nq, problem["x"].shape[0]
        inner = ca.Function("inner", [problem["x"], problem["p"]], [problem["g"]])
        end_map = np.zeros((2 * nq, nw))
        end = self.where["flow_end"]
        end_map[:, end:end + 2 * nq] = np.eye(2 * nq)
        scale = np.concatenate(nlp.scales)
        self.flow_function = FlowFunction("ballistic_flow", self.flow, math.nan, nq)
        self.constraints = CoupledConstraints("constraints", inner, self.flow_function, start_map * scale,
                                              end_map * scale)
        self.row_names = self.row_names + ["the ballistic flow"] * (2 * nq)
        self.lbg = np.concatenate([self.lbg, np.zeros(2 * nq)])
        self.ubg = np.concatenate([self.ubg, np.zeros(2 * nq)])
        w, p = ca.MX.sym("w", nw), ca.MX.sym("p", problem["p"].shape[0])
        cost = ca.Function("cost", [problem["x"], problem["p"]], [problem["f"]])
        return {"x": w, "f": cost(w, p), "g": self.constraints(w, p), "p": p}

    def _phase(self, nlp: "_Program", p_d, q_first, v_first, q_last, rest_last: bool, tip_t, b, press, cost,
               least) -> list:
        """The collocation points (q, qd, qdd, Gamma, old and new tip's reactions) over [0, d], nodes
        and midpoints in time order; the first node at ``q_first`` with velocity ``v_first`` (None: at
        rest), the last at ``q_last`` (at rest when ``rest_last``); every reaction pressing by
        ``least`` (N)."""
        nq, na, n_int, rows, at = self.nq, self.na, self.intervals, self.rows, self.at.tolist()
        effort_limit = self.effort_limits
        lower_q, upper_q = self._ranges()
        h = p_d / n_int
        points, previous = [], None
        for k in range(n_int + 1):
            nlp.last_node_q = nlp.size
            q, v, a = nlp.var("q", nq, lower_q, upper_q), nlp.var("v", nq), nlp.var("a", nq, scale=ACCELERATION)
            tau = nlp.var("tau", na, -effort_limit, effort_limit, TORQUE)
            f2 = nlp.var("f_new", self.reaction_size, scale=self.weight)
            if k == 0:
                nlp.eq(q - q_first, "the first posture")
                nlp.eq(v if v_first is None else v - v_first, "the first velocity")
                if v_first is None:
                    nlp.eq(a, "at rest")
            else:
                a_m = nlp.var("a_mid", nq, scale=ACCELERATION)
                q_m, v_m, q_defect, v_defect = hermite_simpson(previous, (q, v, a), a_m, h)
                if q_last is not None:
                    # A phase that ends at a given posture: the tip also held at the nodes in
                    # position and velocity, the defects corrected along the held rows (Posa,
                    # Kuindersma and Tedrake 2016) by what the rule's error alone makes non-zero.
                    tip_k, j2_k, _ = self.f_tip(self._embed(q))
                    nlp.eq(tip_k[rows] - tip_t[rows], "the new tip held")
                    nlp.eq(ca.mtimes(j2_k[rows, :], self._embed(v)), "the new tip at rest")
                    held_rows = j2_k[rows, at].T
                    q_defect -= ca.mtimes(held_rows, nlp.var("gamma_q", len(rows), scale=CORRECTION))
                    v_defect -= ca.mtimes(held_rows, nlp.var("gamma_v", len(rows), scale=CORRECTION))
                nlp.eq(q_defect, "collocation")
                nlp.eq(v_defect, "collocation")
                tau_m = nlp.var("tau_mid", na, -effort_limit, effort_limit, TORQUE)
                points.append([q_m, v_m, a_m, tau_m,
                               nlp.var("f_new_mid", self.reaction_size, scale=self.weight), 4.0])
            points.append([q, v, a, tau, f2, 1.0 if k in (0, n_int) else 2.0])
            previous = (q, v, a)
        if q_last is not None:
            nlp.eq(previous[0] - q_last, "the last posture")
        if rest_last:
            nlp.eq(previous[1], "at rest")
            nlp.eq(previous[2], "at rest")
        out = []
        resting = {0} if v_first is None else set()  # where the acceleration is set to zero (at rest)
        if rest_last:
            resting.add(len(points) - 1)
        for k, (q, v, a, tau, f2, weight) in enumerate(points):
            out.append((q, v, a, tau, self._held(nlp, q, v, a, tau, f2, b, press, least, k not in resting), f2))
            cost(tau, h / 6 * weight, TORQUE)
        return out

    def _held(self, nlp: "_Program", q, v, a, tau, f2, b, press, least=0.0, accelerating: bool = True):
        """The closed chain's equations of motion at one instant, the new tip's acceleration held
        (unless ``accelerating`` is False: the acceleration is set to zero there), both reactions
        pressing (by ``least``, N) within the floor's pyramid; the old tip's reaction (the root rows
        less the new tip's share)."""
        at, roots, rows = self.at.tolist(), self.roots.tolist(), self.rows
        x = self._embed(q)
        _, j2_k, _ = self.f_tip(x)
        generalized = self.f_rnea(x, self._embed(v), self._embed(a))
        nlp.eq(generalized[at] - ca.mtimes(j2_k[rows, at].T, f2[rows]) - ca.mtimes(b[at, :], tau),
               "the closed chain's equations of motion")
        if accelerating:
            nlp.eq(self.f_tip_acceleration(x, self._embed(v), self._embed(a))[rows], "the new tip held (its acceleration)")
        f1 = generalized[roots] - ca.mtimes(j2_k[:, roots].T, f2)  # the new tip's share of the root rows
        press(f1, "the old tip's reaction", least)
        press(f2, "the new tip's reaction", least)
        return f1

    @cached_property
    def warm_solver(self) -> ca.Function:
        """The program's solver for a start at a nearby solution (``WARM_START``), made when first
        needed."""
        problem, options = self._warm
        return ca.nlpsol(f"{self.kind}_double_support_warm", "ipopt", problem, options)

    def _ranges(self) -> tuple[np.ndarray, np.ndarray]:
        """The joint table's ranges on q (rad): a stance-leg coordinate is its joint inverted."""
        lower, upper = [], []
        for c in self.bm.coordinates:
            lim = c.spec.limits
            lo, hi = (-lim.upper, -lim.lower) if c.inverted else (lim.lower, lim.upper)
            lower.append(lo)
            upper.append(hi)
        return np.array(lower), np.array(upper)

    # Solving ----------------------------------------------------------------------------------------
    def values(self, solution: dict) -> dict[str, np.ndarray]:
        """The unknowns of ``solution`` (``LastingSupport.solution``) that occur once, by name."""
        counts: dict[str, int] = {}
        for name, _size in self.names:
            counts[name] = counts.get(name, 0) + 1
        out, offset = {}, 0
        x = solution["x"] * self.scale
        for name, size in self.names:
            if counts[name] == 1:
                out[name] = x[offset:offset + size]
            offset += size
        return out

    def initial_guess(self, boundary: Boundary, impulsive: dict[str, np.ndarray] | None = None) -> np.ndarray:
        """The unknowns along the straight line between the phase's two postures at rest, the
        impulses zero, the weight shared by the feet; or, given the impulsive limit's unknowns
        (``values`` of the ``limit`` program's solution), its impulses, and the phase at the
        touchdown posture moving with the held impact's velocity."""
        w0 = np.zeros(len(self.lbw))
        offset, node = 0, 0
        impulsive = impulsive or {}
        moving = None
        if "xd_held" in impulsive:  # the closed chain's own motion from the held velocity, torque-free
            qd = impulsive["xd_held"][self.at]
            qdd, held = ClosedChain(self.bm, self.exchange).forward(boundary.q_t, qd, np.zeros(self.na))
            if self.lateral_free:  # x and z held, no lateral force
                held = [held[0], 0.0, held[1]]
            moving = {"v": qd, "a": qdd, "a_mid": qdd, "f_new": held, "f_new_mid": held}
        weight = self.bm.total_mass * self.bm.params.gravity
        first, last = {"stop": (boundary.q_t, boundary.q_rest), "start": (boundary.q_rest, boundary.q_t)}.get(
            self.kind, (boundary.q_t, boundary.q_t))
        for name, size in self.names:
            if name == "q":
                w0[offset:offset + size] = first + (last - first) * node / max(self.intervals, 1)
                node += 1
            elif name in ("f_new", "f_new_mid"):
                w0[offset + 2] = weight / 2
            elif name in ("p_old", "p_new"):
                w0[offset + 2] = 1.0
            elif name == "qd_next":
                w0[offset:offset + size] = self.exchange.velocity(boundary.q_t, boundary.xd_a)
            elif name == "q_next":
                w0[offset:offset + size] = self.exchange.configuration(boundary.q_t)
            elif name == "xd_next":
                w0[offset:offset + size] = boundary.xd_a
            elif name == "flow_end":
                w0[offset:offset + size] = np.concatenate([boundary.q_t, boundary.xd_b[self.at]])
            if moving is not None and name in moving:
                w0[offset:offset + size] = moving[name]
            if name in impulsive:
                w0[offset:offset + size] = impulsive[name]
            offset += size
        return w0 / self.scale

    def solve(self, boundary: Boundary, request: LastingRequest, start: dict | None = None,
              impulsive: dict[str, np.ndarray] | None = None) -> LastingSupport:
        """The double support ``request`` asks (its duration and margins; the program's effort)
        between the gait's ends; ``start`` a nearby solution's unknowns and multipliers
        (``LastingSupport.solution``), else ``initial_guess`` (with ``impulsive``)."""
        if self.kind == "periodic":
            self.flow_function.evaluation.period = boundary.period
        duration = request.duration
        friction = max(self.friction - request.friction_margin, 0.0) if math.isfinite(self.friction) else 0.0
        params = np.concatenate([boundary.q_t, boundary.q_rest, boundary.xd_b, boundary.xd_a,
                                 [duration, request.least_normal_force, friction]])
        args = dict(p=params, lbx=self.lbw, ubx=self.ubw, lbg=self.lbg, ubg=self.ubg)
        if "r1_plus" in self.where:  # the push-off: none (zero), or at least the request's upwards
            at = self.where["r1_plus"]
            lower, upper = self.lbw.copy(), self.ubw.copy()
            lower[at:at + 3], upper[at:at + 3] = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
            if request.push_off > 0.0:
                lower[at:at + 3] = (-np.inf, -np.inf, request.push_off / self.scale[at + 2])
                upper[at:at + 3] = np.inf
            args.update(lbx=lower, ubx=upper)
        solver = self.solver
        if start is None:
            args["x0"] = self.initial_guess(boundary, impulsive)
        else:
            args.update(x0=start["x"], lam_x0=start["lam_x"], lam_g0=start["lam_g"])
            solver = self.warm_solver
        begin = time.perf_counter()
        result = solver(**args)
        elapsed = time.perf_counter() - begin
        stats = solver.stats()
        out = dict(zip(self.outputs.name_out(), (np.array(v) for v in self.outputs(result["x"], params))))
        solution = {key: np.array(result[key]).ravel() for key in ("x", "lam_x", "lam_g", "g")}
        return self._support(duration, stats, out, elapsed, solution)

    def _support(self, duration: float, stats: dict, out: dict, elapsed: float, solution: dict) -> LastingSupport:
        embed = self._embed_array
        if self.intervals > 0:
            t, weights = self._grid(duration)
            x, xd, xdd = embed(out["q"]), embed(out["v"]), embed(out["a"])
            tau = out["tau"]
            l1 = float(weights @ np.abs(tau).sum(axis=1))
            l2 = float(weights @ (tau ** 2).sum(axis=1))
        else:
            t = np.zeros(0)
            x = xd = xdd = np.zeros((0, self.nx))
            tau = np.zeros((0, self.na))
            out = {"f_old": np.zeros((0, self.reaction_size)), "f_new": np.zeros((0, self.reaction_size)), **out}
            l1 = l2 = 0.0
        none = np.zeros(self.na)
        i_minus, i_plus = out.get("i_minus", none).ravel(), out.get("i_plus", none).ravel()
        forces, held, spin_moments = self._reactions(out)
        total = float(np.abs(i_minus).sum() + np.abs(i_plus).sum() + l1)
        success = bool(stats["success"])
        message = "solved" if success else (f"no {self.kind} double support of {duration:g} s: IPOPT "
                                            f"{stats['return_status']}; {self._worst(solution)}")
        next_start = out["qd_next"].ravel() if "qd_next" in out else None
        push_off = out["push_off"].ravel() if "push_off" in out else None
        return LastingSupport(duration, success, message, t, x, xd, xdd, tau, forces, i_minus, i_plus, held, l1,
                              l2, total, int(stats["iter_count"]), elapsed, next_start, push_off, solution,
                              spin_moments)

    def _grid(self, duration: float) -> tuple[np.ndarray, np.ndarray]:
        """The phase's points (s: nodes and midpoints in time order) and the weights (s) of the
        effort's integral over them (Simpson's rule, the collocation's own)."""
        t = np.linspace(0.0, duration, 2 * self.intervals + 1)
        weights = np.array([1.0] + [4.0, 2.0] * (self.intervals - 1) + [4.0, 1.0]) * (duration / self.intervals) / 6
        return t, weights

    def _reactions(self, out: dict) -> tuple[np.ndarray, np.ndarray, tuple | None]:
        """The phase's reactions from the program's outputs ``f_old``, ``f_new`` (at the points) and
        ``p_old``, ``p_new`` (the held impact's; zero where absent): the tips' forces (n x 2 x 3,
        N), the held impulses (2 x 3, N s) and, with lateral hips, the spin moments about the
        vertical (``LastingSupport.spin_moments``; None for legs of pitch joints)."""
        reactions = np.stack([out["f_old"], out["f_new"]], axis=1)
        held = (np.stack([out["p_old"].ravel(), out["p_new"].ravel()]) if "p_old" in out
                else np.zeros((2, self.reaction_size)))
        spin_moments = None if self.lateral_free else (reactions[..., 3], held[:, 3])
        return reactions[..., :3], held[:, :3], spin_moments

    def excess(self, solution: dict) -> np.ndarray:
        """How far ``solution``'s iterate is outside each constraint's bounds (its rows' units)."""
        g = np.asarray(solution["g"])
        return np.maximum(self.lbg - g, 0.0) + np.maximum(g - self.ubg, 0.0)

    def _worst(self, solution: dict) -> str:
        """What the last iterate violates most, in the constraints' words and units."""
        excess = self.excess(solution)
        worst = int(np.argmax(excess))
        return f"its last iterate misses '{self.row_names[worst]}' by {excess[worst]:.3g}"

    def _embed_array(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros((q.shape[0], self.nx))
        out[:, self.at] = q
        return out


class LastingPlanner:
    """The double supports that last for one model: the programs (``LastingProgram``, built once
    each, a few seconds), solved for a planned gait (``core/gait/planner.py``'s ``Gait``)."""

    def __init__(self, bm: BipedModel, exchange, flow: BallisticFlow, friction: float) -> None:
        self.bm, self.exchange, self.flow, self.friction = bm, exchange, flow, friction
        self.programs: dict[tuple[str, str], LastingProgram] = {}

    def intervals(self, kind: str) -> int:
        """The collocation intervals of this model's program of ``kind`` (``INTERVALS``; the periodic
        cycle of lateral hips on ``LATERAL_HIPS_PERIODIC``)."""
        if kind == "periodic" and self.bm.params.joints.lateral_hips:
            return LATERAL_HIPS_PERIODIC
        return INTERVALS[kind]

    def program(self, kind: str, effort: str) -> LastingProgram:
        key = (kind, effort)
        if key not in self.programs:
            self.programs[key] = LastingProgram(self.bm, kind, self.intervals(kind), effort, self.friction,
                                                self.exchange, self.flow)
        return self.programs[key]

    def boundary(self, gait, q_rest: np.ndarray | None = None) -> Boundary:
        """The ends of ``gait``'s double support (a solved, straight gait)."""
        ds = gait.double_support
        if ds is None or not gait.step.converged:
            raise ValueError(f"no double support for a gait that was not solved: {gait.message}")
        q_t = gait.step.q_target
        return Boundary(q_t, ds.xd_b, ds.xd_a, q_t if q_rest is None else q_rest, gait.problem.period)

    def limit(self, gait, effort: str = "l1") -> LastingSupport:
        """The limit d -> 0+: I^-, the held impact pressing, I^+ (its effort is E(0+))."""
        return self.program("limit", effort).solve(self.boundary(gait), LastingRequest(0.0, effort))

    @property
    def program_key(self) -> tuple:
        """What decides this planner's programs and their solutions besides a gait's ends and a
        request: the model's parameters, the flow's steps and kind, the friction (``solve_cache``)."""
        return self.bm.params, self.flow.steps, self.flow.native is not None, self.friction

    def periodic(self, gait, request: LastingRequest, start: dict | None = None,
                 limit: LastingSupport | None = None) -> LastingSupport:
        """The periodic cycle of ``gait``'s single support (from the lift-off posture the phase
        ends in) and a double support of ``request.duration`` s; ``start`` a nearby solution, else
        started from the impulsive limit (``limit``: ``gait``'s own, solved here if not given), that
        start's solution kept on disk and answered from there when asked again (``solve_cache``)."""
        if request.duration == 0.0:
            return limit or self.limit(gait, request.effort)
        program = self.program("periodic", request.effort)
        boundary = self.boundary(gait)
        if start is not None:
            return program.solve(boundary, request, start)

        def solve() -> LastingSupport:
            seed = self.program("limit", request.effort).values((limit or self.limit(gait, request.effort)).solution)
            return program.solve(boundary, request, None, seed)

        return cached("lasting_cycle", (self.program_key, boundary, request), solve)

    def stop(self, gait, request: LastingRequest, rest: np.ndarray) -> LastingSupport:
        """From ``gait``'s touchdown to rest in the standing posture ``rest`` (rad, on the same two
        feet: ``core/walking/balance.standing_pose`` at the gait's step length and width): I^-, the
        held impact, a double support of ``request.duration`` s ending at rest (docs/model.md 14)."""
        return self.program("stop", request.effort).solve(self.boundary(gait, rest), request)

    def start(self, gait, request: LastingRequest, rest: np.ndarray) -> LastingSupport:
        """From rest in the standing posture ``rest`` onto ``gait``: a double support of
        ``request.duration`` s from rest to the gait's touchdown posture, then I^+ onto its next step."""
        return self.program("start", request.effort).solve(self.boundary(gait, rest), request)
