"""The swing actuated at its two ends and ballistic between (docs/model.md section 15).

The paper's impulses I^- and I^+ are limits: spread over a few milliseconds they are kilonewton
metres (docs/model.md 11.4). Here the swing of duration T is actuated for its first and its last
tau seconds, with finite torques, and ballistic (no torque) between, as in Mochon and McMahon's
ballistic walking. The cycle, in the step's own frame (stance tip at the origin):

1. the actuated start of the swing: tau s of single support under torques Gamma(t), from the
   lift-off with the state continuous (the old stance foot leaving from rest);
2. the ballistic single support, T - 2 tau s, torque-free (the planner's shooting flow);
3. the actuated end of the swing: tau s of single support under torques, onto the touchdown posture
   q_T of the d = 0 gait;
4. the touchdown, a passive impact with both tips held: both impulses press within the pyramid
   (zero where the landing is soft);
5. d seconds of double support under torques (``lasting.py``'s phase; none at d = 0);
6. the lift-off with the state continuous, the legs exchanged: the next step's phase 1.

Every torque within the joint table's effort limit, every reaction pressing within the floor's
pyramid, the joints within their ranges, the swing tip above the ground over both actuated ends.
The actuated ends are transcribed as the double support is (Hermite-Simpson, inverse-dynamics form),
the ballistic part is the planner's flow with its exact sensitivities, and the whole is one program
for IPOPT. The effort E = integral Sum |Gamma_j| dt over the cycle (``l1``, N m s, the paper's W
read the same way), or the integral of Gamma' Gamma (``l2``). At tau -> 0 the ends tend to the
impulses I^+ and I^- (``lasting.py``).

Units SI, rad; forces N, impulses N s, torques N m.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..dynamics.flow import hermite_samples
from . import views
from .lasting import (ACCELERATION, TOLERANCE, TORQUE, WALK_FRICTION_MARGIN, WALK_LEAST_NORMAL_FORCE,
                      LastingProgram, LastingRequest, _Program, hermite_simpson)
from .lasting_support import LastingSupport

SWING_INTERVALS = 10  # Hermite-Simpson intervals over each actuated end of the swing (by default)
BETWEEN_POINTS = "the swing's torque between the points within its limit"
SWING_ENDS = ("start", "end")


@dataclass(frozen=True)
class SwingRequest:
    """What the cycle is asked: ``actuated_swing`` tau (s, > 0), the duration of each actuated end
    of the swing, and the double support (``LastingRequest``: its duration d >= 0, the effort
    minimized and the margins); ``within_limits`` False lifts the joint table's effort limits over the
    swing's two ends (not over the double support), to follow tau -> 0 onto the impulses.
    ``swing_intervals``: Hermite-Simpson intervals over each end; ``bounded_between``: each end's
    torques within their limits between the collocation points too, not at them only (the rule's
    torque over an interval is the quadratic through its node, midpoint and node, which overshoots:
    bounded by its Bernstein coefficients g0, 2 gm - (g0 + g1) / 2, g1; what a walk needs,
    docs/model.md 15.1)."""

    actuated_swing: float
    support: LastingRequest
    within_limits: bool = True  # False: the swing's ends free of the effort limits (the limit tau -> 0)
    swing_intervals: int = SWING_INTERVALS
    bounded_between: bool = False

    @classmethod
    def walkable(cls, actuated_swing: float, duration: float, effort: str = "l1") -> "SwingRequest":
        """The cycle a walk can track (docs/model.md 15.1): the double support's margins
        (``LastingRequest``'s least normal force and friction margin; no push-off, there is no I^+),
        20 intervals over each end, its torques bounded between the points; ``effort`` minimized."""
        support = LastingRequest(duration, effort, least_normal_force=WALK_LEAST_NORMAL_FORCE,
                                 friction_margin=WALK_FRICTION_MARGIN)
        return cls(actuated_swing, support, swing_intervals=2 * SWING_INTERVALS, bounded_between=True)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.actuated_swing) and self.actuated_swing > 0.0):
            raise ValueError(f"actuated_swing must be a duration > 0 s, got {self.actuated_swing!r}")
        if self.swing_intervals < 1:
            raise ValueError(f"swing_intervals must be >= 1, got {self.swing_intervals!r}")


@dataclass(frozen=True, eq=False)
class SwingEnd:
    """One actuated end of the swing, sampled at its collocation points (2 n + 1 instants, both ends
    included): ``t`` (s, from the step's start), ``x``, ``xd``, ``xdd`` in the double-support
    coordinates X (the stance tip held at the origin), ``torques`` (N m, actuated joints) and
    ``contact_forces`` (the stance tip's reaction, world axes, N, n x 3); with lateral hip joints
    ``spin_moments``, the stance foot's moment about the vertical (N m, n; None for legs of pitch
    joints, whose tips take none)."""

    t: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    xdd: np.ndarray
    torques: np.ndarray
    contact_forces: np.ndarray
    spin_moments: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class ActuatedSwingCycle:
    """A solved (or refused) cycle of ``actuated_swing`` tau: its two actuated ends (``start``,
    ``end``), its double support (``support``: the held touchdown's impulses, the phase's samples;
    its impulses I^-, I^+ are zero), the ballistic flow's start and end ([q; qd], the step's
    coordinates), the efforts over the whole cycle (N m s): ``effort_l1`` (E), ``effort_l2``."""

    actuated_swing: float
    success: bool
    message: str
    start: SwingEnd
    end: SwingEnd
    support: LastingSupport
    flow_start: np.ndarray
    flow_end: np.ndarray
    effort_l1: float
    effort_l2: float
    iterations: int
    solve_time_s: float
    solution: dict | None = None

    @property
    def peak_torque(self) -> np.ndarray:
        """The largest |Gamma_j| over the cycle, per actuated joint (N m)."""
        return np.max([np.abs(self.start.torques).max(axis=0), np.abs(self.end.torques).max(axis=0),
                       self.support.peak_torque], axis=0)

    @property
    def friction_used(self) -> float:
        """The largest |F_xy| / F_z of every reaction over the cycle."""
        swing = np.concatenate([self.start.contact_forces, self.end.contact_forces])
        return max(float(np.max(np.hypot(swing[:, 0], swing[:, 1]) / swing[:, 2])), self.support.friction_used)


def _simpson_weights(intervals: int, duration: float) -> np.ndarray:
    """Simpson's weights over the 2 n + 1 collocation points of ``intervals`` intervals."""
    return np.array([1.0] + [4.0, 2.0] * (intervals - 1) + [4.0, 1.0]) * (duration / intervals) / 6


class ActuatedSwingProgram(LastingProgram):
    """The nonlinear program of the cycle (module docstring) for the model ``bm``: the double
    support on ``intervals`` collocation intervals (1 for d = 0: a phase of no duration, whose
    forces the held velocity must still allow), each actuated end of the swing on
    ``swing_intervals``, its torques bounded between the points if ``bounded_between``
    (``SwingRequest``). Built once, solved for any gait, tau and d (its parameters)."""

    # IPOPT's limited-memory Hessian stalls near the optimum here. Measured at tau = 0.1 s, d = 0: the
    # scaled dual infeasibility stays at 1.7e-5 from iteration 300 to 1,000 while E creeps from
    # 88.11555 to 88.11549 N m s, the constraints held to 1e-10. A point whose scaled optimality error
    # stays below 1e-4 for 10 iterations is taken (E then within about 1e-5 of its value at 1,000
    # iterations), the constraints still held to the module's 1e-9.
    SOLVER_OPTIONS = {"ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 10,
                      "ipopt.acceptable_constr_viol_tol": TOLERANCE}

    def __init__(self, bm, intervals: int, effort: str = "l1", friction: float = 0.5, exchange=None,
                 flow=None, swing_intervals: int = SWING_INTERVALS, bounded_between: bool = False) -> None:
        self.swing_intervals, self.bounded_between = swing_intervals, bounded_between
        super().__init__(bm, "periodic", intervals, effort, friction, exchange, flow)

    def _build(self) -> None:
        nq = self.nq
        self._functions()
        p_q, p_d, p_tau = ca.SX.sym("q_t", nq), ca.SX.sym("d"), ca.SX.sym("tau")
        p_least, p_mu = ca.SX.sym("least_normal_force"), ca.SX.sym("friction")
        tip_t, j2_t, j1_t = self.f_tip(self._embed(p_q))
        b = self._actuation()
        nlp = _Program()
        press, cost = self._terms(nlp, p_mu)
        terms = (b, press, cost, p_least)
        # The actuated start of the swing (its first state tied to the double support's end below),
        # then the ballistic flow's end, from which the actuated end of the swing reaches q_T.
        start, start_offsets = self._swing(nlp, p_tau, None, None, terms, "start")
        flow_end = nlp.var("flow_end", 2 * nq)
        end, _ = self._swing(nlp, p_tau, (flow_end[:nq], flow_end[nq:]), p_q, terms, "end")
        # The touchdown: the swing tip coming down, the passive impact with both tips held.
        xm = self._embed(end[-1][1])
        nlp.le(ca.mtimes(j2_t[2, :], xm), "the swing tip comes down")
        xh, p1, p2 = self._held_impact(nlp, xm, (self.f_mass(self._embed(p_q)), j1_t, j2_t), press)
        support = self._phase(nlp, p_d, p_q, xh[self.at.tolist()], None, False, tip_t, b, press, cost, p_least)
        # The lift-off, the state continuous: the next step's start is the phase's end exchanged.
        q_l, v_l = support[-1][0], support[-1][1]
        posture, velocity = self._exchanged(q_l, v_l, self._embed(v_l))
        nlp.eq(start[0][0] - posture, "the lift-off posture, legs exchanged")
        nlp.eq(start[0][1] - velocity, "the lift-off velocity, legs exchanged")
        outputs = {"p_old": p1, "p_new": p2, "flow_end": flow_end}
        for name, points, keys in (("start", start, ("q", "v", "a", "tau", "f")),
                                   ("end", end, ("q", "v", "a", "tau", "f")),
                                   ("support", support, ("q", "v", "a", "tau", "f_old", "f_new"))):
            outputs.update({f"{name}_{key}": ca.horzcat(*[pt[i] for pt in points]).T for i, key in enumerate(keys)})
        params = ca.vertcat(p_q, p_d, p_tau, p_least, p_mu)
        start_map = np.zeros((2 * nq, nlp.size))
        q_at, v_at = start_offsets
        start_map[:nq, q_at:q_at + nq] = np.eye(nq)
        start_map[nq:, v_at:v_at + nq] = np.eye(nq)
        self._finish(nlp, params, outputs, start_map)

    def _swing(self, nlp: _Program, p_tau, first, q_last, terms: tuple, name: str) -> tuple[list, tuple[int, int]]:
        """The collocation points (q, qd, qdd, Gamma, the stance tip's reaction) of an actuated end
        of the swing over ``p_tau`` s, nodes and midpoints in time order; its first state ``first``
        ((q, qd) expressions, None: unknowns), its last posture ``q_last`` (None: free). Also the
        offsets of its last node's q and qd among the unknowns."""
        nq, na, n_int = self.nq, self.na, self.swing_intervals
        b, press, cost, least = terms
        lower_q, upper_q = self._ranges()
        h = p_tau / n_int
        points, previous, last = [], None, (0, 0)
        for k in range(n_int + 1):
            if k == 0 and first is not None:
                q, v = first
            else:
                last = (nlp.size, nlp.size + nq)
                q, v = nlp.var(f"{name}_q", nq, lower_q, upper_q), nlp.var(f"{name}_v", nq)
            a = nlp.var(f"{name}_a", nq, scale=ACCELERATION)
            tau = nlp.var(f"{name}_tau", na, -self.effort_limits, self.effort_limits, TORQUE)
            if k > 0:
                a_m = nlp.var(f"{name}_a_mid", nq, scale=ACCELERATION)
                q_m, v_m, q_defect, v_defect = hermite_simpson(previous, (q, v, a), a_m, h)
                nlp.eq(q_defect, "collocation")
                nlp.eq(v_defect, "collocation")
                points.append((q_m, v_m, a_m, nlp.var(f"{name}_tau_mid", na, -self.effort_limits, self.effort_limits,
                                                       TORQUE), 4.0))
            points.append((q, v, a, tau, 1.0 if k in (0, n_int) else 2.0))
            previous = (q, v, a)
        if q_last is not None:
            nlp.eq(previous[0] - q_last, "the touchdown posture")
        out = []
        for k, (q, v, a, tau, weight) in enumerate(points):
            x = self._embed(q)
            generalized = self.f_rnea(x, self._embed(v), self._embed(a))
            nlp.eq(generalized[self.at.tolist()] - ca.mtimes(b[self.at.tolist(), :], tau),
                   "the single support's equations of motion")
            force = generalized[self.roots.tolist()]
            press(force, "the stance tip's reaction", least)
            if 0 < k < len(points) - 1:  # at the lift-off and the touchdown the tip is on the ground
                nlp.le(-self.f_tip(x)[0][2], "the swing tip above the ground")
            cost(tau, h / 6 * weight, TORQUE)
            out.append((q, v, a, tau, force))
        if self.bounded_between:  # each interval's quadratic torque within the convex hull of its Bernstein coefficients
            limits = ca.DM(self.effort_limits)
            for k in range(0, len(out) - 1, 2):
                middle = 2 * out[k + 1][3] - (out[k][3] + out[k + 2][3]) / 2
                nlp.le(middle - limits, BETWEEN_POINTS)
                nlp.le(-middle - limits, BETWEEN_POINTS)
        return out, last

    # Solving ----------------------------------------------------------------------------------------
    def sequences(self, solution: dict) -> dict[str, list[np.ndarray]]:
        """Every unknown of ``solution`` by name, in the order the program made them."""
        out: dict[str, list[np.ndarray]] = {}
        x, offset = solution["x"] * self.scale, 0
        for name, size in self.names:
            out.setdefault(name, []).append(x[offset:offset + size])
            offset += size
        return out

    def guess(self, values: dict[str, list]) -> np.ndarray:
        """The unknowns (scaled) from ``values``: for each name, its values in the order made (a
        name missing or short: zeros)."""
        w0, offset, used = np.zeros(len(self.lbw)), 0, {}
        for name, size in self.names:
            k = used.get(name, 0)
            if k < len(values.get(name, ())):
                w0[offset:offset + size] = values[name][k]
            used[name] = k + 1
            offset += size
        return w0 / self.scale

    def solve(self, gait_ends, request: SwingRequest, guess: dict[str, list]) -> ActuatedSwingCycle:
        """The cycle ``request`` asks between the gait's touchdown posture ``gait_ends`` ((q_T, T))
        from the unknowns ``guess`` (``guess``'s form)."""
        q_t, period = gait_ends
        tau, support = request.actuated_swing, request.support
        if 2 * tau >= period:
            raise ValueError(f"actuated_swing must be below half the period ({period / 2:g} s), got {tau:g} s")
        self.flow_function.evaluation.period = period - 2 * tau
        friction = max(self.friction - support.friction_margin, 0.0) if math.isfinite(self.friction) else 0.0
        params = np.concatenate([q_t, [support.duration, tau, support.least_normal_force, friction]])
        lower, upper = self.lbw, self.ubw
        if not request.within_limits:
            lower, upper = lower.copy(), upper.copy()
            offset = 0
            for name, size in self.names:
                if name in ("start_tau", "start_tau_mid", "end_tau", "end_tau_mid"):
                    lower[offset:offset + size], upper[offset:offset + size] = -np.inf, np.inf
                offset += size
        begin = time.perf_counter()
        result = self.solver(x0=self.guess(guess), p=params, lbx=lower, ubx=upper, lbg=self.lbg, ubg=self.ubg)
        elapsed = time.perf_counter() - begin
        stats = self.solver.stats()
        out = dict(zip(self.outputs.name_out(), (np.array(v) for v in self.outputs(result["x"], params))))
        solution = {key: np.array(result[key]).ravel() for key in ("x", "lam_x", "lam_g", "g")}
        return self._cycle(request, q_t, period, stats, out, elapsed, solution)

    def _cycle(self, request: SwingRequest, q_t, period, stats, out, elapsed, solution) -> ActuatedSwingCycle:
        tau, d = request.actuated_swing, request.support.duration
        n_swing = 2 * self.swing_intervals + 1
        ends = {}
        for name, t0 in (("start", 0.0), ("end", period - tau)):
            reaction = out[f"{name}_f"]
            ends[name] = SwingEnd(t0 + np.linspace(0.0, tau, n_swing), self._embed_array(out[f"{name}_q"]),
                                  self._embed_array(out[f"{name}_v"]), self._embed_array(out[f"{name}_a"]),
                                  out[f"{name}_tau"], reaction[:, :3], None if self.lateral_free else reaction[:, 3])
        swing_weights = _simpson_weights(self.swing_intervals, tau)
        support_weights = _simpson_weights(self.intervals, d)
        tau_s = out["support_tau"]
        l1 = sum(float(swing_weights @ np.abs(ends[k].torques).sum(axis=1)) for k in SWING_ENDS)
        l2 = sum(float(swing_weights @ (ends[k].torques ** 2).sum(axis=1)) for k in SWING_ENDS)
        support_l1 = float(support_weights @ np.abs(tau_s).sum(axis=1))
        support_l2 = float(support_weights @ (tau_s ** 2).sum(axis=1))
        none = np.zeros(self.na)
        forces, held, spin_moments = self._reactions({"f_old": out["support_f_old"], "f_new": out["support_f_new"],
                                                      "p_old": out["p_old"], "p_new": out["p_new"]})
        support = LastingSupport(
            d, bool(stats["success"]), "solved", np.linspace(0.0, d, 2 * self.intervals + 1),
            self._embed_array(out["support_q"]), self._embed_array(out["support_v"]),
            self._embed_array(out["support_a"]), tau_s, forces, none, none, held, support_l1, support_l2, support_l1,
            0, 0.0, spin_moments=spin_moments)
        success = bool(stats["success"])
        message = "solved" if success else (f"no cycle with a swing actuated for {tau:g} s at each end and a double "
                                            f"support of {d:g} s: IPOPT {stats['return_status']}; "
                                            f"{self._worst(solution)}")
        flow_start = np.concatenate([out["start_q"][-1], out["start_v"][-1]])
        return ActuatedSwingCycle(tau, success, message, ends["start"], ends["end"], support, flow_start,
                                  out["flow_end"].ravel(), l1 + support_l1, l2 + support_l2,
                                  int(stats["iter_count"]), elapsed, solution)


class ActuatedSwingPlanner:
    """The cycles with an actuated swing for one model, on a ``LastingPlanner``'s model, exchange and
    flow (``core/gait/planner.py``'s ``GaitPlanner.lasting``): their programs built once each."""

    def __init__(self, lasting) -> None:
        self.lasting = lasting
        self.programs: dict[tuple, ActuatedSwingProgram] = {}

    def program(self, lasts: bool, request: SwingRequest) -> ActuatedSwingProgram:
        key = (lasts, request.support.effort, request.swing_intervals, request.bounded_between)
        if key not in self.programs:
            lp = self.lasting
            self.programs[key] = ActuatedSwingProgram(lp.bm, lp.intervals("periodic") if lasts else 1,
                                                      request.support.effort, lp.friction, lp.exchange, lp.flow,
                                                      request.swing_intervals, request.bounded_between)
        return self.programs[key]

    def cycle(self, gait, request: SwingRequest, seed: LastingSupport | None = None,
              near: ActuatedSwingCycle | None = None) -> ActuatedSwingCycle:
        """``gait``'s cycle with the swing actuated for ``request.actuated_swing`` s at each end and a
        double support of ``request.support.duration`` s, started from a nearby cycle of the same
        program (``near``: another tau, gait or d > 0 on the same meshes), else from the impulsive cycle
        of the same d (``seed``, solved here if not given: ``LastingPlanner.periodic``)."""
        support = request.support
        boundary = self.lasting.boundary(gait)
        program = self.program(support.duration > 0.0, request)
        if near is not None and near.solution is not None and len(near.solution["x"]) == len(program.lbw):
            guess = program.sequences(near.solution)
        else:
            if seed is None:
                seed = self.lasting.periodic(gait, LastingRequest(support.duration, support.effort))
            if not seed.success:
                raise ValueError(f"no impulsive cycle to start from: {seed.message}")
            guess = self._guess(gait, request, seed)
        return program.solve((boundary.q_t, boundary.period), request, guess)

    def _guess(self, gait, request: SwingRequest, seed: LastingSupport) -> dict:
        """The unknowns of the impulsive cycle ``seed``: the swing its ballistic flow from the lift-off
        (sampled over both ends), the double support its phase (at d = 0: the touchdown posture
        moving with the held velocity)."""
        bm, tau, lasting = self.lasting.bm, request.actuated_swing, self.lasting
        boundary = lasting.boundary(gait)
        at, configuration = np.asarray(bm.ds_of_single), lasting.exchange.configuration
        lasts = seed.duration > 0.0
        seeded = lasting.program("periodic" if lasts else "limit", request.support.effort)
        held = seeded.values(seed.solution)
        if lasts:
            q0, qd0 = configuration(seed.x[-1, at]), seed.next_start_velocity
        else:  # the gait's own start
            q0, qd0 = configuration(boundary.q_t), lasting.exchange.velocity(boundary.q_t, boundary.xd_a)
        nodes = lasting.flow.propagate(q0, qd0, boundary.period, keep_nodes=True).nodes
        values: dict[str, list] = {"xd_held": [held["xd_held"]], "p_old": [held["p_old"]], "p_new": [held["p_new"]]}

        def sample(name: str, t0: float) -> tuple[np.ndarray, np.ndarray]:
            t = t0 + np.linspace(0.0, tau, 2 * request.swing_intervals + 1)
            q, qd = hermite_samples(nodes, t)
            step = 1e-4
            qdd = (hermite_samples(nodes, np.clip(t + step, 0.0, boundary.period))[1]
                   - hermite_samples(nodes, np.clip(t - step, 0.0, boundary.period))[1]) / (2 * step)
            values[f"{name}_q"], values[f"{name}_v"] = list(q[0::2]), list(qd[0::2])
            values[f"{name}_a"], values[f"{name}_a_mid"] = list(qdd[0::2]), list(qdd[1::2])
            return q, qd

        sample("start", 0.0)
        q_end, qd_end = sample("end", boundary.period - tau)
        values["flow_end"] = [np.concatenate([q_end[0], qd_end[0]])]
        values["end_q"], values["end_v"] = values["end_q"][1:], values["end_v"][1:]  # its first state: the flow's end
        weight = np.zeros(seeded.reaction_size)  # the new tip's reaction: half the weight, no spin moment
        weight[2] = bm.total_mass * bm.params.gravity / 2
        if lasts:
            x, xd, xdd, torques = seed.x[:, at], seed.xd[:, at], seed.xdd[:, at], seed.torques
            forces = seed.contact_forces[:, 1]
            if seed.spin_moments is not None:  # lateral hips: the new tip's reaction holds its spin moment
                forces = np.concatenate([forces, seed.spin_moments[0][:, 1:2]], axis=1)
            values.update(q=list(x[0::2]), v=list(xd[0::2]), a=list(xdd[0::2]), a_mid=list(xdd[1::2]),
                          tau=list(torques[0::2]), tau_mid=list(torques[1::2]),
                          f_new=list(forces[0::2]), f_new_mid=list(forces[1::2]))
        else:
            values.update(q=[boundary.q_t] * 2, v=[held["xd_held"][at]] * 2, f_new=[weight] * 2, f_new_mid=[weight])
        return values


def cycle_view(cycle: ActuatedSwingCycle) -> dict:
    """The cycle as the plan's JSON has it: ``swing_phases`` (its two actuated ends, in the plan's
    ``double_support_coordinates`` with the stance tip held at the origin, and ``actuated_joints``),
    ``double_support_phase`` (the held touchdown and the phase; no impulse), ``peak_torque`` over
    the cycle (N m) and its efforts (N m s)."""
    ends = {name: {"t": end.t, "X": end.x, "Xd": end.xd, "Xdd": end.xdd, "torques": end.torques,
                   "contact_forces": end.contact_forces}
            for name, end in (("start", cycle.start), ("end", cycle.end))}
    return views.clean({"actuated_swing": cycle.actuated_swing,
                        "swing_phases": {"success": cycle.success, "message": cycle.message, **ends},
                        "double_support_phase": views.double_support_phase(cycle.support, math.nan),
                        "peak_torque": cycle.peak_torque, "effort_total": cycle.effort_l1,
                        "effort_l2": cycle.effort_l2, "friction_used": cycle.friction_used,
                        "iterations": cycle.iterations, "solve_time_s": cycle.solve_time_s})
