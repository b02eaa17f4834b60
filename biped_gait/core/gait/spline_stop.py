"""The stop's double support as one quintic B-spline (docs/model.md section 14, "The stop as a
B-spline"): from the gait's touchdown (I^- and the held impact, as ``LastingProgram``'s stop) to
rest in the standing posture, the motion q(t) one spline whose control points are the unknowns.

**Why a spline.** The Hermite-Simpson stop (``LastingProgram``, 10 intervals) converges, but its
reference between the collocation points is no motion of the chain (the feet pull by kilonewtons
there) and finer meshes did not converge. Here q, qd and qdd are linear in the control points: the
plan is a motion at every instant, and the walk tracks its samples every 5 ms (``held_support``).

**The rows** (``SplineMesh``). Knots graded from ``FIRST_INTERVAL`` at the touchdown by
``GROWTH`` to ``LONGEST_INTERVAL``. At samples every ``SAMPLE_STEP`` and at the closure points:
the closed chain's inverse dynamics with the torques and the new tip's reaction (its held rows)
unknown per sample, both reactions pressing by the least normal force within the friction
pyramid, the torques within the joint table's limits. The new tip held at the interior Greville
points (``closure``: as many as the control points left free by the ends). The rotation about the
feet line has no torque and, at the ankle roll 0, no reaction term: its row of the equations of
motion is a condition on the spline alone, imposed at the closure points, at the first sample and
at every sample within ``END_ROLL`` of either end (missed there, the motion asks the feet to pull),
never at the last sample (at rest there the rest rows imply it: with it the equality rows are
rank-deficient). The ends: the first posture and velocity the held impact's, the last posture
the standing one with velocity and acceleration zero.

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
TOLERANCE = 1e-6  # IPOPT's on the scaled KKT conditions and the constraint violation (N, N m)
# A solve from a solution of nearly the same program (``SplineStopProgram(near=True)``): IPOPT's
# start kept where it is (its default push off the bounds of 1e-2 costs 2e5 of violation there), and
# a point feasible to TOLERANCE whose scaled optimality error stays within 1e-4 for ten iterations
# taken (IPOPT's "acceptable": its restoration can fail at such a point, 2.8e-7 off its rows).
NEAR_START = {"ipopt.bound_push": 1e-8, "ipopt.bound_frac": 1e-8, "ipopt.mu_init": 1e-6, "ipopt.acceptable_tol": 1e-4,
              "ipopt.acceptable_constr_viol_tol": TOLERANCE, "ipopt.acceptable_iter": 10}


def kept_stop_path() -> Path:
    """The package's kept stop of the default gait (``studies/stop_study.py`` writes it)."""
    return Path(str(resources.files("biped_gait.core.data"))) / "stop" / "aoustin2013-default.npz"


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
    """The spline of a stop of ``duration`` s: its ``knots`` (in s = t / d, clamped), the
    ``samples`` where the rows are held (in s), of them those with the feet-line roll row
    (``roll``, booleans), and the ``closure`` points where the new tip is held (in s)."""

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



def spline_mesh(duration: float, end_roll: float = END_ROLL) -> SplineMesh:
    """The mesh of a stop of ``duration`` s (module docstring), the roll row at every sample within
    ``end_roll`` s of either end."""
    if not duration > 0.0:
        raise ValueError(f"a stop's double support needs a positive duration, got {duration!r}")
    intervals, total = [], 0.0
    while total < duration - 1e-12:
        h = min(FIRST_INTERVAL * GROWTH ** len(intervals), LONGEST_INTERVAL)
        if total + h > duration - 0.5 * h:  # the last interval takes what is left
            h = duration - total
        intervals.append(h)
        total += h
    breaks = np.concatenate([[0.0], np.cumsum(intervals)]) / duration
    breaks[-1] = 1.0
    knots = np.concatenate([np.zeros(DEGREE), breaks, np.ones(DEGREE)])
    count = len(knots) - DEGREE - 1
    greville = np.array([knots[i + 1:i + DEGREE + 1].mean() for i in range(count)])
    closure = greville[2:-3]  # three control points fixed at each end, two of them at the start
    dense = np.linspace(0.0, 1.0, int(round(duration / SAMPLE_STEP)) + 1)
    samples = np.unique(np.concatenate([dense, closure]))
    near_end = (samples * duration < end_roll) | (samples * duration > duration - end_roll)
    at_closure = np.array([np.min(np.abs(closure - s)) < 1e-12 for s in samples])
    roll = at_closure | near_end
    roll[0], roll[-1] = True, False
    return SplineMesh(duration, knots, samples, roll, closure)


class SplineStopProgram(LastingProgram):
    """``LastingProgram``'s stop with its phase the spline of ``mesh`` (module docstring); ``near``:
    every solve starts from a solution of nearly the same program (``NEAR_START``)."""

    SOLVER_OPTIONS = {"ipopt.max_iter": MAX_ITERATIONS, "ipopt.tol": TOLERANCE, "ipopt.constr_viol_tol": TOLERANCE}

    def __init__(self, bm, mesh: SplineMesh, effort: str = "l1", friction: float = 0.5, exchange=None,
                 flow=None, near: bool = False) -> None:
        self.mesh = mesh
        if near:
            self.SOLVER_OPTIONS = {**SplineStopProgram.SOLVER_OPTIONS, **NEAR_START}
        super().__init__(bm, "stop", 1, effort, friction, exchange, flow)

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
        """The stop between ``boundary``'s ends at ``stage``'s margins, IPOPT started at ``x0``
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


def _kinematic_rows(program: SplineStopProgram, control, duration, ends: tuple, tip) -> list[tuple]:
    """The rows on the spline's control points alone, each with what it says: the first posture
    and velocity, the last posture, at rest there (velocity and acceleration), the new tip at
    ``tip`` (its held rows) at the closure points. ``control``: control_points x nq (CasADi);
    ``duration`` (s, a number or a symbol); ``ends``: the first posture and velocity, the last posture."""
    mesh = program.mesh
    q_first, v_first, q_last = ends

    def at(points, derivative=0):
        return ca.mtimes(ca.DM(mesh.basis(points, derivative)), control)

    rows = [(at([0.0]).T - q_first, "the first posture"), (at([0.0], 1).T / duration - v_first, "the first velocity"),
            (at([1.0]).T - q_last, "the last posture"), (ca.vertcat(at([1.0], 1).T, at([1.0], 2).T), "at rest")]
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


def seed(program: SplineStopProgram, boundary: Boundary, impulsive: dict[str, np.ndarray]) -> np.ndarray:
    """The scaled unknowns IPOPT starts the free stage from: the spline of least squared
    acceleration through the ends and the closure (a small IPOPT program on the control points),
    the first velocity the held velocity of ``impulsive`` (``values`` of a solved collocation stop,
    whose I^- and held impact it also lends); per sample the torques and the new tip's reaction
    that satisfy the equations of motion other than the roll in least squares."""
    mesh, nq, at = program.mesh, program.nq, program.at
    n, d = mesh.control_points, mesh.duration
    p = ca.SX.sym("P", n * nq)
    control = ca.reshape(p, nq, n).T
    acceleration = ca.mtimes(ca.DM(mesh.basis(mesh.samples, 2)), control) / d ** 2
    objective = ca.sum1(ca.DM(_trapezoid(mesh.samples) * d) * ca.sum2(acceleration ** 2))
    tip = program.f_tip(program._embed(ca.DM(boundary.q_t)))[0][program.rows]
    ends = (boundary.q_t, impulsive["xd_held"][at], boundary.q_rest)
    rows = [row for row, _ in _kinematic_rows(program, control, d, ends, tip)]
    lower, upper = program._ranges()
    kinematic = ca.nlpsol("least_acceleration", "ipopt", {"x": p, "f": objective, "g": ca.vertcat(*rows)},
                          {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})
    start = np.linspace(boundary.q_t, boundary.q_rest, n).ravel()
    solved = kinematic(x0=start, lbx=np.tile(lower, n), ubx=np.tile(upper, n), lbg=0, ubg=0)
    control = np.array(solved["x"]).reshape(n, nq)
    chain = ClosedChain(program.bm, program.exchange)
    q_s, v_s, a_s = (mesh.basis(mesh.samples, k) @ control / d ** k for k in range(3))
    per_sample: dict[str, list] = {"P": [control.ravel()], "tau": [], "f_new": [], "s": [np.abs(impulsive["i_minus"])]}
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


def continuation(program: SplineStopProgram, boundary: Boundary, x0: np.ndarray, stages=STAGES,
                 report=None) -> LastingSupport:
    """The stop at the last of ``stages``, each solved from the one before (the first from ``x0``);
    the first stage that fails is returned as it is. ``report(stage, support)`` after each."""
    support = None
    for stage in stages:
        support = program.solve_stage(boundary, stage, x0)
        if report is not None:
            report(stage, support)
        if not support.success:
            return support
        x0 = support.solution["x"]
    return support


def load_stop(path: Path, bm) -> tuple[LastingSupport, dict]:
    """A kept stop (``studies/stop_study.save``'s file at ``path``) of the model ``bm`` as the
    ``LastingSupport`` it was, with its ``meta`` (the gait, the margins, the solve, date and commit);
    its ``solution`` holds the unknowns ``x`` only."""
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
    support = LastingSupport(meta["duration"], meta["success"], meta["message"], t, embedded(arrays["q"]),
                             embedded(arrays["qd"]), embedded(arrays["qdd"]), torques, arrays["contact_forces"],
                             arrays["i_minus"], np.zeros_like(arrays["i_minus"]), arrays["held_impulses"], l1,
                             float(weights @ (torques ** 2).sum(axis=1)), meta["effort_total"], meta["iterations"],
                             0.0, None, None, {"x": arrays["x"]}, None)
    return support, meta
