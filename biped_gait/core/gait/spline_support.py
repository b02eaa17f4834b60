"""The stop's and the start's double support as one quintic B-spline (docs/model.md section 14,
"The stop as a B-spline", "The start as a B-spline"): the stop from the gait's touchdown (I^- and the
held impact, as ``LastingProgram``'s stop) to rest in the standing posture; the start from rest in
that posture to the gait's touchdown posture, then I^+ onto the gait's next step (as
``LastingProgram``'s start). The motion q(t) is one spline whose control points are the unknowns.

**Why a spline.** The Hermite-Simpson stop (``LastingProgram``, 10 intervals) converges, but its
reference between the collocation points is no motion of the chain (the feet pull by kilonewtons
there) and finer meshes did not converge. Here q, qd and qdd are linear in the control points: the
plan is a motion at every instant, and the walk tracks its samples every 5 ms (``held_support``).

**The rows** (``SplineMesh``). Knots graded from ``FIRST_INTERVAL`` at the phase's moving end (the
stop's touchdown, the start's lift-off) by ``GROWTH`` to ``LONGEST_INTERVAL``. At samples every
``SAMPLE_STEP`` and at the closure points: the closed chain's inverse dynamics with the torques and
the new tip's reaction (its held rows) unknown per sample, both reactions pressing by the least
normal force within the friction pyramid, the torques within the joint table's limits. The new tip
held at the interior Greville points (``closure``: as many as the control points left free by the
ends). The rotation about the feet line has no torque and, at the ankle roll 0, no reaction term:
its row of the equations of motion is a condition on the spline alone, imposed at the closure
points, at the moving end's sample and at every sample within ``END_ROLL`` of either end (missed
there, the motion asks the feet to pull), never at the end at rest (there the rest rows imply it:
with it the equality rows are rank-deficient). The ends: the stop's first posture and velocity the
held impact's, its last the standing posture with velocity and acceleration zero; the start's first
the standing posture at rest (velocity and acceleration zero), its last the gait's touchdown
posture with the new tip at rest and the velocity free (I^+ takes it onto the gait's).

**Solving.** From a least-acceleration spline through the ends and the closure (``seed``), IPOPT
converges only with the friction lifted and pulling allowed; ``STAGES`` then brings the friction
coefficient down and the margins up, each solve started from the last (``continuation``).

Times in s; the spline's parameter s = t / d in [0, 1]. Units SI, rad.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.interpolate import BSpline

from ..dynamics.closed_chain import ClosedChain
from .lasting import TORQUE, Boundary, LastingProgram
from .lasting_support import LastingSupport

DEGREE = 5  # quintic: qdd is C^2, the torques' reference continuous
FIRST_INTERVAL = 0.005  # s: the knot interval at the touchdown, where the held impact's velocity dies
GROWTH = 1.15  # each knot interval this much longer than the one before ...
LONGEST_INTERVAL = 0.025  # s: ... up to this
SAMPLE_STEP = 0.005  # s: the rows are held this often (and at the closure points)
END_ROLL = 0.1  # s: the feet-line roll row at every sample this close to either end
MAX_ITERATIONS = 3000  # a stage from the last takes 200 to 500; the free start 1,500
# The start's seed: the weight (1/s) of its lift-off velocity's squared distance from the collocation
# start's beside the integral of the squared acceleration (rad^2/s^3).
LIFT_OFF_WEIGHT = 1e3
KINDS = ("stop", "start")  # the phases planned as a spline: each has one end at rest, the other moving
TOLERANCE = 1e-6  # IPOPT's on the scaled KKT conditions and the constraint violation (N, N m)
# A solve from a solution of nearly the same program (``SplineProgram(near=True)``): IPOPT's
# start kept where it is (its default push off the bounds of 1e-2 costs 2e5 of violation there), and
# a point feasible to TOLERANCE whose scaled optimality error stays within 1e-4 for ten iterations
# taken (IPOPT's "acceptable": its restoration can fail at such a point, 2.8e-7 off its rows).
NEAR_START = {"ipopt.bound_push": 1e-8, "ipopt.bound_frac": 1e-8, "ipopt.mu_init": 1e-6, "ipopt.acceptable_tol": 1e-4,
              "ipopt.acceptable_constr_viol_tol": TOLERANCE, "ipopt.acceptable_iter": 10}


def kept_path(kind: str = "stop") -> Path:
    """The package's kept stop or start (``kind``) of the default gait (``studies/spline_study.py``
    writes them)."""
    return Path(str(resources.files("biped_gait.core.data"))) / kind / "aoustin2013-default.npz"


@dataclass(frozen=True)
class Stage:
    """One solve of the continuation: the least normal force (N; negative: pulling allowed) and
    the friction coefficient of the pyramid (the floor's less a margin)."""

    least_normal_force: float
    friction: float


# The continuation at the floor's mu = 0.5 (docs/model.md 14): free, the friction brought down,
# then the margins up. Measured stage by stage at the default gait, d = 2 s, not yet in one run: to
# 25 N as here; 27 and 35 N with the shoulders' range widened (they then left it), the kept plan
# re-solved from there within it (42 N and mu - 0.085 stalled).
STAGES = (Stage(-1e5, 1000.0), Stage(0.0, 100.0), Stage(0.0, 20.0), Stage(0.0, 5.0), Stage(0.0, 2.0),
          Stage(0.0, 1.0), Stage(0.0, 0.5), Stage(5.0, 0.49), Stage(10.0, 0.48), Stage(15.0, 0.47),
          Stage(20.0, 0.46), Stage(27.0, 0.445), Stage(35.0, 0.43))


@dataclass(frozen=True, eq=False)
class SplineMesh:
    """The spline of a ``kind`` of phase (``KINDS``) of ``duration`` s: its ``knots`` (in s = t / d,
    clamped), the ``samples`` where the rows are held (in s), of them those with the feet-line roll
    row (``roll``, booleans), and the ``closure`` points where the new tip is held (in s)."""

    kind: str
    duration: float
    knots: np.ndarray
    samples: np.ndarray
    roll: np.ndarray
    closure: np.ndarray

    @property
    def control_points(self) -> int:
        return len(self.knots) - DEGREE - 1

    def basis(self, points: np.ndarray, derivative: int = 0) -> np.ndarray:
        """The spline's basis functions (or their ``derivative`` in s) at ``points`` (in s):
        len(points) x control_points; at s = 1 the limit from the left."""
        spline = BSpline(self.knots, np.eye(self.control_points), DEGREE)
        return (spline.derivative(derivative) if derivative else spline)(np.asarray(points, dtype=float))



def spline_mesh(duration: float, end_roll: float = END_ROLL, kind: str = "stop") -> SplineMesh:
    """The mesh of a ``kind`` of phase of ``duration`` s (module docstring), the roll row at every
    sample within ``end_roll`` s of either end. The start's is the stop's reversed in time."""
    if kind not in KINDS:
        raise ValueError(f"a spline phase is one of {', '.join(KINDS)}, got {kind!r}")
    if not duration > 0.0:
        raise ValueError(f"a {kind}'s double support needs a positive duration, got {duration!r}")
    intervals, total = [], 0.0
    while total < duration - 1e-12:
        h = min(FIRST_INTERVAL * GROWTH ** len(intervals), LONGEST_INTERVAL)
        if total + h > duration - 0.5 * h:  # the last interval takes what is left
            h = duration - total
        intervals.append(h)
        total += h
    if kind == "start":  # graded towards the lift-off
        intervals.reverse()
    breaks = np.concatenate([[0.0], np.cumsum(intervals)]) / duration
    breaks[-1] = 1.0
    knots = np.concatenate([np.zeros(DEGREE), breaks, np.ones(DEGREE)])
    count = len(knots) - DEGREE - 1
    greville = np.array([knots[i + 1:i + DEGREE + 1].mean() for i in range(count)])
    # The control points the ends fix: the stop's posture and velocity at its start, posture,
    # velocity and acceleration at its end; the start's three at its start, its last posture.
    closure = greville[2:-3] if kind == "stop" else greville[3:-1]
    dense = np.linspace(0.0, 1.0, int(round(duration / SAMPLE_STEP)) + 1)
    samples = np.unique(np.concatenate([dense, closure]))
    near_end = (samples * duration < end_roll) | (samples * duration > duration - end_roll)
    at_closure = np.array([np.min(np.abs(closure - s)) < 1e-12 for s in samples])
    roll = at_closure | near_end
    roll[0], roll[-1] = (True, False) if kind == "stop" else (False, True)
    return SplineMesh(kind, duration, knots, samples, roll, closure)


class SplineProgram(LastingProgram):
    """``LastingProgram``'s stop or start (``mesh.kind``) with its phase the spline of ``mesh``
    (module docstring); ``near``: every solve starts from a solution of nearly the same program
    (``NEAR_START``)."""

    SOLVER_OPTIONS = {"ipopt.max_iter": MAX_ITERATIONS, "ipopt.tol": TOLERANCE, "ipopt.constr_viol_tol": TOLERANCE}

    def __init__(self, bm, mesh: SplineMesh, effort: str = "l1", friction: float = 0.5, exchange=None,
                 flow=None, near: bool = False) -> None:
        self.mesh = mesh
        if near:
            self.SOLVER_OPTIONS = {**SplineProgram.SOLVER_OPTIONS, **NEAR_START}
        super().__init__(bm, mesh.kind, 1, effort, friction, exchange, flow)

    def _phase(self, nlp, p_d, q_first, v_first, q_last, rest_last, tip_t, b, press, cost, least) -> list:
        mesh, nq, na, rows, at = self.mesh, self.nq, self.na, self.rows, self.at.tolist()
        lower, upper = self._ranges()
        n = mesh.control_points
        control = ca.reshape(nlp.var("P", n * nq, np.tile(lower, n), np.tile(upper, n)), nq, n).T
        q_s, v_s, a_s = (ca.mtimes(ca.DM(mesh.basis(mesh.samples, k)), control) for k in range(3))
        for row, what in _kinematic_rows(self, control, p_d, (q_first, v_first, q_last), tip_t[rows]):
            nlp.eq(row, what)
        weights = _trapezoid(mesh.samples)
        out = []
        for j in range(len(mesh.samples)):
            q, v, a = q_s[j, :].T, v_s[j, :].T / p_d, a_s[j, :].T / p_d ** 2
            tau = nlp.var("tau", na, -self.effort_limits, self.effort_limits, TORQUE)
            f2 = nlp.var("f_new", self.reaction_size, scale=self.weight)
            x = self._embed(q)
            _, j2, _ = self.f_tip(x)
            generalized = self.f_rnea(x, self._embed(v), self._embed(a))
            held = at if mesh.roll[j] else at[1:]
            nlp.eq(generalized[held] - ca.mtimes(j2[rows, held].T, f2[rows]) - ca.mtimes(b[held, :], tau),
                   "the closed chain's equations of motion")
            f1 = generalized[self.roots.tolist()] - ca.mtimes(j2[:, self.roots.tolist()].T, f2)
            press(f1, "the old tip's reaction", least)
            press(f2, "the new tip's reaction", least)
            cost(tau, p_d * weights[j], TORQUE)
            out.append((q, v, a, tau, f1, f2))
        return out

    def _grid(self, duration: float) -> tuple[np.ndarray, np.ndarray]:
        """The samples (s) and the trapezoidal rule's weights (s) of the effort over them."""
        return self.mesh.samples * duration, _trapezoid(self.mesh.samples) * duration

    def solve_stage(self, boundary: Boundary, stage: Stage, x0: np.ndarray) -> LastingSupport:
        """The phase between ``boundary``'s ends at ``stage``'s margins, IPOPT started at ``x0``
        (scaled unknowns: ``seed``'s or a solution's ``x``)."""
        params = np.concatenate([boundary.q_t, boundary.q_rest, boundary.xd_b, boundary.xd_a,
                                 [self.mesh.duration, stage.least_normal_force, stage.friction]])
        begin = time.perf_counter()
        result = self.solver(x0=x0, p=params, lbx=self.lbw, ubx=self.ubw, lbg=self.lbg, ubg=self.ubg)
        elapsed = time.perf_counter() - begin
        stats = self.solver.stats()
        out = dict(zip(self.outputs.name_out(), (np.array(v) for v in self.outputs(result["x"], params))))
        solution = {key: np.array(result[key]).ravel() for key in ("x", "lam_x", "lam_g", "g")}
        return self._support(self.mesh.duration, stats, out, elapsed, solution)


def _kinematic_rows(program: SplineProgram, control, duration, ends: tuple, tip) -> list[tuple]:
    """The rows on the spline's control points alone, each with what it says: the first and the
    last posture; the stop's first velocity and rest at its end (velocity and acceleration), the
    start's rest at its beginning and its new tip at rest at its end; the new tip at ``tip`` (its held rows) at the closure points.
    ``control``: control_points x nq (CasADi); ``duration`` (s, a number or a symbol); ``ends``: the
    first posture, the stop's first velocity (the start's: None), the last posture."""
    mesh = program.mesh
    q_first, v_first, q_last = ends

    def at(points, derivative=0):
        return ca.mtimes(ca.DM(mesh.basis(points, derivative)), control)

    rows = [(at([0.0]).T - q_first, "the first posture"), (at([1.0]).T - q_last, "the last posture")]
    if mesh.kind == "stop":
        rows += [(at([0.0], 1).T / duration - v_first, "the first velocity"),
                 (ca.vertcat(at([1.0], 1).T, at([1.0], 2).T), "at rest")]
    else:
        rows.append((ca.vertcat(at([0.0], 1).T, at([0.0], 2).T), "at rest"))
        _, j2, _ = program.f_tip(program._embed(q_last))
        rows.append((ca.mtimes(j2[program.rows, :], program._embed(at([1.0], 1).T / duration)), "the new tip at rest"))
    closure = at(mesh.closure)
    rows += [(program.f_tip(program._embed(closure[j, :].T))[0][program.rows] - tip, "the new tip held")
             for j in range(len(mesh.closure))]
    return rows


def _trapezoid(points: np.ndarray) -> np.ndarray:
    """The trapezoidal rule's weights over ``points`` (in s: times the duration for seconds)."""
    weights = np.zeros(len(points))
    steps = np.diff(points)
    weights[:-1] += steps / 2
    weights[1:] += steps / 2
    return weights


def seed(program: SplineProgram, boundary: Boundary, impulsive: dict[str, np.ndarray], velocity: np.ndarray) -> np.ndarray:
    """The scaled unknowns IPOPT starts the free stage from: the spline of least squared
    acceleration through the ends and the closure (a small IPOPT program on the control points), its
    moving end's velocity ``velocity`` (rad/s: the stop's first, the start's last; a solved
    collocation phase's), the impulses those of ``impulsive`` (``values`` of that phase: the stop's
    I^- and held impact, the start's I^+); per sample the torques and the new tip's reaction that
    satisfy the equations of motion other than the roll in least squares."""
    mesh, nq, at = program.mesh, program.nq, program.at
    n, d = mesh.control_points, mesh.duration
    p = ca.SX.sym("P", n * nq)
    control = ca.reshape(p, nq, n).T
    acceleration = ca.mtimes(ca.DM(mesh.basis(mesh.samples, 2)), control) / d ** 2
    objective = ca.sum1(ca.DM(_trapezoid(mesh.samples) * d) * ca.sum2(acceleration ** 2))
    tip = program.f_tip(program._embed(ca.DM(boundary.q_t)))[0][program.rows]
    stop = mesh.kind == "stop"
    ends = (boundary.q_t, velocity, boundary.q_rest) if stop else (boundary.q_rest, None, boundary.q_t)
    rows = [row for row, _ in _kinematic_rows(program, control, d, ends, tip)]
    if not stop:  # the lift-off's velocity near ``velocity``: some of it may leave the joints' ranges
        last = ca.mtimes(ca.DM(mesh.basis([1.0], 1)), control).T / d
        objective += LIFT_OFF_WEIGHT * ca.sumsqr(last - velocity)
    lower, upper = program._ranges()
    kinematic = ca.nlpsol("least_acceleration", "ipopt", {"x": p, "f": objective, "g": ca.vertcat(*rows)},
                          {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})
    start = np.linspace(ends[0], ends[2], n).ravel()
    solved = kinematic(x0=start, lbx=np.tile(lower, n), ubx=np.tile(upper, n), lbg=0, ubg=0)
    control = np.array(solved["x"]).reshape(n, nq)
    chain = ClosedChain(program.bm, program.exchange)
    q_s, v_s, a_s = (mesh.basis(mesh.samples, k) @ control / d ** k for k in range(3))
    # The effort's slacks in the program's order: the stop's I^- before the phase, the start's I^+ after.
    per_sample: dict[str, list] = {"P": [control.ravel()], "tau": [], "f_new": [],
                                   "s": [np.abs(impulsive["i_minus"])] if stop else []}
    for q, v, a in zip(q_s, v_s, a_s):
        x = np.zeros(program.nx)
        x[at] = q
        xd, xdd = np.zeros(program.nx), np.zeros(program.nx)
        xd[at], xdd[at] = v, a
        generalized = np.array(program.f_rnea(x, xd, xdd)).ravel()[at]
        j2 = np.array(program.f_tip(x)[1])[program.rows][:, at]
        columns = np.hstack([chain.selection, j2.T])
        solved = np.linalg.lstsq(columns[1:], generalized[1:], rcond=None)[0]  # the roll row left out
        tau = np.clip(solved[:program.na], -program.effort_limits, program.effort_limits)
        force = np.zeros(program.reaction_size)
        force[program.rows] = solved[program.na:]
        per_sample["tau"].append(tau)
        per_sample["f_new"].append(force)
        per_sample["s"].append(np.abs(tau))
    if not stop:
        per_sample["s"].append(np.abs(impulsive["i_plus"]))
    w0, offset, seen = np.zeros(len(program.lbw)), 0, {}
    for name, size in program.names:
        k = seen.get(name, 0)
        seen[name] = k + 1
        if name in per_sample:
            w0[offset:offset + size] = per_sample[name][k]
        elif name in impulsive:
            w0[offset:offset + size] = impulsive[name]
        offset += size
    return w0 / program.scale


def continuation(program: SplineProgram, boundary: Boundary, x0: np.ndarray, stages=STAGES,
                 report=None) -> LastingSupport:
    """The phase at the last of ``stages``, each solved from the one before (the first from ``x0``);
    the first stage that fails is returned as it is, unless its last iterate is feasible to
    ``TOLERANCE`` (IPOPT's restoration can fail at such a point near the optimum: the next stage
    goes on from it). ``report(stage, support)`` after each."""
    support = None
    for stage in stages:
        support = program.solve_stage(boundary, stage, x0)
        if report is not None:
            report(stage, support)
        if not usable(program, support):
            return support
        x0 = support.solution["x"]
    return support


def usable(program: SplineProgram, support: LastingSupport) -> bool:
    """Whether ``support`` (a solve of ``program``) can start the next stage: solved, or its last
    iterate feasible to ``TOLERANCE``."""
    return support.success or float(program.excess(support.solution).max()) <= TOLERANCE


def load_plan(path: Path, bm) -> tuple[LastingSupport, dict]:
    """A kept stop or start (``studies/spline_study.save``'s file at ``path``; its ``meta`` says
    which) of the model ``bm`` as the ``LastingSupport`` it was, with its ``meta`` (the gait, the
    margins, the solve, date and commit); its ``solution`` holds the unknowns ``x`` only."""
    with np.load(path) as kept:
        arrays = {key: kept[key] for key in kept.files}
    meta = json.loads(str(arrays["meta"]))
    at = np.asarray(bm.ds_of_single)

    def embedded(rows: np.ndarray) -> np.ndarray:
        out = np.zeros((len(rows), bm.double_support.nv))
        out[:, at] = rows
        return out

    t, torques = arrays["t"], arrays["torques"]
    weights = _trapezoid(t)
    l1 = float(weights @ np.abs(torques).sum(axis=1))
    none = np.zeros(torques.shape[1])
    support = LastingSupport(meta["duration"], meta["success"], meta["message"], t, embedded(arrays["q"]),
                             embedded(arrays["qd"]), embedded(arrays["qdd"]), torques, arrays["contact_forces"],
                             arrays.get("i_minus", none), arrays.get("i_plus", none), arrays["held_impulses"], l1,
                             float(weights @ (torques ** 2).sum(axis=1)), meta["effort_total"], meta["iterations"],
                             0.0, None, None, {"x": arrays["x"]}, None)
    return support, meta
