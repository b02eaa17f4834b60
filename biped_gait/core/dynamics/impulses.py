"""Impulsive double support (docs/model.md section 4, paper eqs. 6-10) and its minimum-effort solution.

Unknowns (47), in this order: Xd^- (12), I^- (7), I_R1^- (3), Xd^+ (12), I_R2 (3), I^+ (7),
I_R2^+ (3). Equations (42):

    (6)  D_e Xd^- - B_e I^- - J1^T I_R1^- = D_e Xd^b
    (7)  J1 Xd^- = J1 Xd^b
    (8)  D_e (Xd^+ - Xd^-) - J2^T I_R2 = 0
    (9)  J2 Xd^+ = 0
    (10) -D_e Xd^+ - B_e I^+ - J2^T I_R2^+ = -D_e Xd^a

Their rank is 41: y = [z_d; 0; z_d; 0; z_d] is a left null vector (z_d the locked rotation
about the foot-to-foot line), so the system is consistent only if y^T b = z_d^T D_e (Xd^b -
Xd^a) = 0. One dependent row is dropped and the closure residual is checked and reported.

Effort ``l1``: W = sum |I^-| + |I^+| (N m s) as a linear program solved by HiGHS through
``highspy`` (global optimum; its dual certificate is checked). Effort ``l2``: sum of squared impulses by OSQP.
Impulses in N m s (joints) and N s (reactions); velocities in m/s and rad/s.

Options (``EffortOptions``, docs/model.md section 4.4): the friction cone of the floor on the
three reaction impulses, linearized as the inscribed octagonal pyramid (so that no impulse
needs more than ``friction``); a bound on the joint rates q3..q9 between the sub-phases (Xd^-,
Xd^+); and the effort's reading, on joint angles (``joint``, the paper's eq. 12) or on the
absolute angles of the links (``absolute``: each link's net torque impulse, its proximal
joint's minus its distal joints').
"""

from __future__ import annotations

import threading
from functools import lru_cache
import math
from dataclasses import dataclass, replace

import highspy
import numpy as np

N_UNKNOWN = 47
EFFORTS = ("l1", "l2")
COORDINATES = ("joint", "absolute")
# Slices of the unknown vector.
XD_MINUS = slice(0, 12)
I_MINUS = slice(12, 19)
IR1_MINUS = slice(19, 22)
XD_PLUS = slice(22, 34)
IR2 = slice(34, 37)
I_PLUS = slice(37, 44)
IR2_PLUS = slice(44, 47)
_B_E = np.vstack([np.zeros((5, 7)), np.eye(7)])


@dataclass(frozen=True)
class ImpactProblem:
    """The data of one double support: D_e, J1, J2 at q(T), Xd^b, Xd^a, and z_d."""

    mass_matrix: np.ndarray
    j1: np.ndarray
    j2: np.ndarray
    xd_b: np.ndarray
    xd_a: np.ndarray
    locked_rotation: np.ndarray

    def equations(self) -> tuple[np.ndarray, np.ndarray]:
        """The 42 x 47 matrix and right-hand side of eqs. (6)-(10), in the module's order."""
        d, j1, j2 = self.mass_matrix, self.j1, self.j2
        a = np.zeros((42, N_UNKNOWN))
        b = np.zeros(42)
        a[0:12, XD_MINUS], a[0:12, I_MINUS], a[0:12, IR1_MINUS] = d, -_B_E, -j1.T
        b[0:12] = d @ self.xd_b
        a[12:15, XD_MINUS] = j1
        b[12:15] = j1 @ self.xd_b
        a[15:27, XD_PLUS], a[15:27, XD_MINUS], a[15:27, IR2] = d, -d, -j2.T
        a[27:30, XD_PLUS] = j2
        a[30:42, XD_PLUS], a[30:42, I_PLUS], a[30:42, IR2_PLUS] = -d, -_B_E, -j2.T
        b[30:42] = -d @ self.xd_a
        return a, b

    def left_null_vector(self) -> np.ndarray:
        """y (42,) with y^T A = 0: the conserved momentum about the foot-to-foot line."""
        y = np.zeros(42)
        z = self.locked_rotation
        y[0:12], y[15:27], y[30:42] = z, z, z
        return y

    def closure_residual(self) -> float:
        """z_d^T D_e (Xd^a - Xd^b) (kg m^2/s): how far the equations are from consistent."""
        return float(self.locked_rotation @ self.mass_matrix @ (self.xd_a - self.xd_b))

    def reachable(self) -> tuple["ImpactProblem", float]:
        """The nearest consistent problem: Xd^a + s z_d with z_d^T D_e (Xd^a + s z_d - Xd^b) = 0,
        and s (rad/s), the correction along the locked rotation (docs/model.md section 4)."""
        z = self.locked_rotation
        s = -self.closure_residual() / float(z @ self.mass_matrix @ z)
        return replace(self, xd_a=self.xd_a + s * z), s


# The reading of the effort on absolute link angles: rows of the net torque impulse on the stance
# thigh, the pelvis and trunk (pitch), the trunk (yaw), the two arms, the swing thigh and the
# swing shin, from the joint impulses q3..q9 (stance knee, stance hip, torso yaw, stance-side
# shoulder, swing-side shoulder, swing hip, swing knee). The stance shin's (-I3, the knee's
# reaction on a link whose own joint, the ankle, is passive) is not counted.
ABSOLUTE_READING = np.array([
    [1, -1, 0, 0, 0, 0, 0],
    [0, 1, 0, -1, -1, -1, 0],
    [0, 0, 1, 0, 0, 0, 0],
    [0, 0, 0, 1, 0, 0, 0],
    [0, 0, 0, 0, 1, 0, 0],
    [0, 0, 0, 0, 0, 1, -1],
    [0, 0, 0, 0, 0, 0, 1],
], dtype=float)
CONE_SIDES = 8  # the friction cone's inscribed pyramid


@dataclass(frozen=True)
class EffortOptions:
    """How the double support's impulses are chosen beyond eqs. (6)-(10): the floor's friction
    coefficient on the reaction impulses (inf: no cone), a bound (rad/s) on the joint rates
    q3..q9 of Xd^- and Xd^+ (inf: none), and the effort's reading (``joint``/``absolute``)."""

    friction: float = math.inf
    rate_bound: float = math.inf
    coordinates: str = "joint"

    def __post_init__(self) -> None:
        if math.isnan(self.friction) or not self.friction > 0:
            raise ValueError(f"friction coefficient must be positive (or inf), got {self.friction}")
        if math.isnan(self.rate_bound) or not self.rate_bound > 0:
            raise ValueError(f"joint-rate bound must be positive (or inf), got {self.rate_bound} rad/s")
        if self.coordinates not in COORDINATES:
            raise ValueError(f"unknown effort coordinates {self.coordinates!r}: use 'joint' or 'absolute'")

    @property
    def reading(self) -> np.ndarray:
        """The rows whose absolute values the effort sums, applied to I^- and to I^+ (7 columns)."""
        return ABSOLUTE_READING if self.coordinates == "absolute" else np.eye(7)


@dataclass(frozen=True)
class ImpulseSolution:
    """The chosen solution of eqs. (6)-(10); ``success`` False carries the solver's reason."""

    success: bool
    message: str
    effort: str
    x: np.ndarray
    W: float
    equation_residual: float
    closure_residual: float
    duality_gap: float = float("nan")

    xd_minus = property(lambda self: self.x[XD_MINUS], doc="Xd^-: after I^-, before the impact (12)")
    i_minus = property(lambda self: self.x[I_MINUS], doc="I^-: joint impulses before the impact (N m s)")
    ir1_minus = property(lambda self: self.x[IR1_MINUS], doc="I_R1^-: old stance tip's reaction (N s)")
    xd_plus = property(lambda self: self.x[XD_PLUS], doc="Xd^+: just after the passive impact (12)")
    ir2 = property(lambda self: self.x[IR2], doc="I_R2: the passive impact at the new stance tip (N s)")
    i_plus = property(lambda self: self.x[I_PLUS], doc="I^+: joint impulses after the impact (N m s)")
    ir2_plus = property(lambda self: self.x[IR2_PLUS], doc="I_R2^+: new stance tip's reaction to I^+ (N s)")


Equations = tuple[np.ndarray, np.ndarray]  # A (42 x 47) and b (42) of eqs. (6)-(10)


def _reduced_equations(problem: ImpactProblem, equations: Equations) -> Equations:
    """Eqs. (6)-(10) less the one row the null vector y makes dependent (its largest entry)."""
    a, b = equations
    drop = int(np.argmax(np.abs(problem.left_null_vector())))
    keep = np.arange(42) != drop
    return a[keep], b[keep]


def _sign_constraints(problem: ImpactProblem) -> tuple[np.ndarray, np.ndarray]:
    """Rows G x <= 0: swing tip moving down before the impact, old stance tip up after it."""
    g = np.zeros((2, N_UNKNOWN))
    g[0, XD_MINUS] = problem.j2[2]
    g[1, XD_PLUS] = -problem.j1[2]
    return g, np.zeros(2)


def _reaction_lower_bounds() -> np.ndarray:
    """Lower bounds of the unknowns: the vertical components of the three reaction impulses
    non-negative (N s), the rest free (-inf)."""
    lower = np.full(N_UNKNOWN, -np.inf)
    for sl in (IR1_MINUS, IR2, IR2_PLUS):
        lower[sl.stop - 1] = 0.0
    return lower


def effort(x: np.ndarray, reading: np.ndarray | None = None) -> float:
    """W = sum |I^-| + |I^+| (N m s), paper eq. (12); with ``reading``, the sum of the absolute
    values of ``reading @ I^-`` and ``reading @ I^+``."""
    if reading is None:
        return float(np.abs(x[I_MINUS]).sum() + np.abs(x[I_PLUS]).sum())
    return float(np.abs(reading @ x[I_MINUS]).sum() + np.abs(reading @ x[I_PLUS]).sum())


def friction_ratios(x: np.ndarray) -> np.ndarray:
    """|horizontal| / vertical of the three reaction impulses I_R1^-, I_R2, I_R2^+: the friction
    coefficient each needs (inf where the vertical component is zero and the horizontal not)."""
    out = np.empty(3)
    for k, sl in enumerate((IR1_MINUS, IR2, IR2_PLUS)):
        fx, fy, fz = x[sl]
        horizontal = math.hypot(fx, fy)
        out[k] = horizontal / fz if fz > 0 else (0.0 if horizontal == 0 else math.inf)
    return out


def _cone_rows(options: EffortOptions) -> np.ndarray:
    """Rows G x <= 0 of the inscribed octagonal pyramid of the friction cone on each reaction
    impulse: cos(a) Ix + sin(a) Iy <= mu cos(pi/8) Iz for eight directions a (none for mu = inf)."""
    if not math.isfinite(options.friction):
        return np.zeros((0, N_UNKNOWN))
    rows = []
    apothem = options.friction * math.cos(math.pi / CONE_SIDES)
    for sl in (IR1_MINUS, IR2, IR2_PLUS):
        for k in range(CONE_SIDES):
            angle = 2 * math.pi * k / CONE_SIDES
            row = np.zeros(N_UNKNOWN)
            row[sl] = (math.cos(angle), math.sin(angle), -apothem)
            rows.append(row)
    return np.array(rows)


def _unknown_bounds(options: EffortOptions) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of the unknowns: the reactions' vertical components non-negative,
    the joint rates of Xd^- and Xd^+ within the rate bound."""
    lower, upper = _reaction_lower_bounds(), np.full(N_UNKNOWN, np.inf)
    if math.isfinite(options.rate_bound):
        for sl in (XD_MINUS, XD_PLUS):
            joints = slice(sl.start + 5, sl.stop)
            lower[joints], upper[joints] = -options.rate_bound, options.rate_bound
    return lower, upper


def _finish(problem: ImpactProblem, equations: Equations, effort_name: str, options: EffortOptions, x: np.ndarray,
            ok: bool, message: str, **kw) -> ImpulseSolution:
    a, b = equations
    return ImpulseSolution(
        success=ok,
        message=message,
        effort=effort_name,
        x=x,
        W=effort(x, options.reading if options.coordinates != "joint" else None),
        equation_residual=float(np.max(np.abs(a @ x - b))),
        closure_residual=problem.closure_residual(),
        **kw,
    )


@dataclass(frozen=True)
class _Effort:
    """The parts of the effort LP that depend only on the options: its variables are x (47),
    then t (one per reading row of I^- and of I^+) bounding the absolute values summed; cost
    sum(t); bounds; the rows -t <= reading I <= t; the friction-cone rows."""

    cost: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    abs_rows: np.ndarray
    cone_rows: np.ndarray

    @property
    def size(self) -> int:
        return len(self.cost)


@lru_cache(maxsize=16)
def _effort_parts(options: EffortOptions) -> _Effort:
    reading = options.reading
    n_t = 2 * len(reading)
    size = N_UNKNOWN + n_t
    lower, upper = _unknown_bounds(options)
    abs_rows = np.zeros((2 * n_t, size))
    k = 0
    for block in (I_MINUS, I_PLUS):
        for row in reading:  # row . I - t_k <= 0 and -row . I - t_k <= 0
            abs_rows[2 * k, block], abs_rows[2 * k + 1, block] = row, -row
            abs_rows[2 * k: 2 * k + 2, N_UNKNOWN + k] = -1.0
            k += 1
    cone = np.zeros((0, size))
    cone_x = _cone_rows(options)
    if len(cone_x):
        cone = np.hstack([cone_x, np.zeros((len(cone_x), n_t))])
    return _Effort(np.concatenate([np.zeros(N_UNKNOWN), np.ones(n_t)]), np.concatenate([lower, np.zeros(n_t)]),
                   np.concatenate([upper, np.full(n_t, np.inf)]), abs_rows, cone)


@dataclass(frozen=True)
class _L1Program:
    """The effort LP in (x, t): minimize ``parts.cost`` (x, t) = sum(t) subject to
    a_ub (x, t) <= b_ub, a_eq (x, t) = b_eq and the parts' bounds. ``a`` and ``b`` hold the
    inequality rows (the absolute values, the sign rows, the cone), then the equality rows."""

    parts: _Effort
    a: np.ndarray
    b: np.ndarray
    inequalities: int

    a_ub = property(lambda self: self.a[: self.inequalities])
    b_ub = property(lambda self: self.b[: self.inequalities])
    a_eq = property(lambda self: self.a[self.inequalities :])
    b_eq = property(lambda self: self.b[self.inequalities :])


def _l1_program(problem: ImpactProblem, equations: Equations, options: EffortOptions) -> _L1Program:
    """The absolute-value rows, the sign rows, the cone rows, and eqs. (6)-(10) less one dependent row."""
    parts = _effort_parts(options)
    a_eq, b_eq = _reduced_equations(problem, equations)
    g, h = _sign_constraints(problem)
    n_abs, n_cone = len(parts.abs_rows), len(parts.cone_rows)
    inequalities = n_abs + len(g) + n_cone
    a = np.zeros((inequalities + len(a_eq), parts.size))
    a[:n_abs] = parts.abs_rows
    a[n_abs: n_abs + len(g), :N_UNKNOWN] = g
    a[n_abs + len(g): inequalities] = parts.cone_rows
    a[inequalities:, :N_UNKNOWN] = a_eq
    return _L1Program(parts, a, np.concatenate([np.zeros(n_abs), h, np.zeros(n_cone), b_eq]), inequalities)


_THREAD = threading.local()


def _highs() -> highspy.Highs:
    """This thread's HiGHS instance (a model is passed afresh for each solve): silent, dual
    simplex, presolve on - the settings of SciPy's ``linprog(method="highs")``, whose HiGHS
    version (1.12.0) is the one pinned, so the two give the same optimum to the last bit."""
    if not hasattr(_THREAD, "highs"):
        highs = highspy.Highs()
        highs.setOptionValue("output_flag", False)
        highs.setOptionValue("simplex_strategy", int(highspy.simplex_constants.SimplexStrategy.kSimplexStrategyDual))
        _THREAD.highs = highs
    return _THREAD.highs


def _pass_model(highs: highspy.Highs, lp: _L1Program) -> None:
    """Hand ``lp`` to HiGHS as SciPy's ``linprog`` does: rows a_ub (-inf <= . <= b_ub) then a_eq
    (b_eq <= . <= b_eq), the matrix column-wise without its zero entries (row indices increasing
    within a column), all columns continuous."""
    rows, cols = lp.a.shape
    column_major = lp.a.ravel(order="F")
    nonzero = np.flatnonzero(column_major)
    start = np.searchsorted(nonzero, rows * np.arange(cols + 1)).astype(np.int32)
    highs.passModel(
        cols, rows, nonzero.size, int(highspy.MatrixFormat.kColwise), int(highspy.ObjSense.kMinimize), 0.0,
        lp.parts.cost, lp.parts.lower, lp.parts.upper,
        np.concatenate([np.full(lp.inequalities, -np.inf), lp.b_eq]), lp.b,
        start, (nonzero % rows).astype(np.int32), column_major[nonzero], np.zeros(cols, np.int32),
    )


def solve_l1(problem: ImpactProblem, options: EffortOptions = EffortOptions()) -> ImpulseSolution:
    """Minimize W = sum |reading I| as an LP in (x, t) with -t <= reading I <= t, by HiGHS;
    certify by duality."""
    equations = problem.equations()
    lp = _l1_program(problem, equations, options)
    highs = _highs()
    _pass_model(highs, lp)
    highs.run()
    status = highs.getModelStatus()
    if status != highspy.HighsModelStatus.kOptimal:
        message = f"impulse LP: model status is {highs.modelStatusToString(status)}"
        return _finish(problem, equations, "l1", options, np.full(N_UNKNOWN, np.nan), False, message)
    solution = highs.getSolution()
    status = np.array(highs.getBasis().col_status, dtype=np.int8)
    row_dual = np.array(solution.row_dual)
    y_lower = np.where(status == int(highspy.HighsBasisStatus.kLower), solution.col_dual, 0.0)
    y_upper = np.where(status == int(highspy.HighsBasisStatus.kUpper), solution.col_dual, 0.0)
    gap = duality_gap(lp, highs.getInfo().objective_function_value, row_dual[lp.inequalities :],
                      row_dual[: lp.inequalities], y_lower, y_upper)
    return _finish(problem, equations, "l1", options, np.array(solution.col_value[:N_UNKNOWN]), True, "optimal",
                   duality_gap=gap)


def duality_gap(lp: _L1Program, objective: float, y_eq: np.ndarray, y_ub: np.ndarray, y_lower: np.ndarray,
                y_upper: np.ndarray) -> float:
    """Certificate of an LP optimum: the larger of the primal-dual objective gap and the dual
    infeasibility (both relative to the objective's scale), from the duals (marginals, SciPy's
    sign convention) of the equality rows, the inequality rows, the lower and the upper bounds."""
    lower = np.where(np.isfinite(lp.parts.lower), lp.parts.lower, 0.0)
    upper = np.where(np.isfinite(lp.parts.upper), lp.parts.upper, 0.0)
    dual_obj = lp.b_eq @ y_eq + lp.b_ub @ y_ub + lower @ y_lower + upper @ y_upper
    stationarity = lp.parts.cost - lp.a_eq.T @ y_eq - lp.a_ub.T @ y_ub - y_lower - y_upper
    sign_violation = max(0.0, float(np.max(y_ub, initial=0.0)), float(-np.min(y_lower, initial=0.0)),
                         float(np.max(y_upper, initial=0.0)))
    scale = max(1.0, abs(objective))
    return max(abs(objective - dual_obj), float(np.max(np.abs(stationarity))), sign_violation) / scale


def solve_l2(problem: ImpactProblem, options: EffortOptions = EffortOptions()) -> ImpulseSolution:
    """Minimize sum (reading I)_i^2 (N^2 m^2 s^2) under the same constraints, by OSQP (polished)."""
    import osqp  # here: only this effort needs OSQP and SciPy's sparse matrices (a tenth of a second to import)
    from scipy import sparse

    equations = problem.equations()
    a_eq, b_eq = _reduced_equations(problem, equations)
    g, h = _sign_constraints(problem)
    cone = _cone_rows(options)
    hessian = np.zeros((N_UNKNOWN, N_UNKNOWN))
    gram = 2.0 * options.reading.T @ options.reading
    hessian[I_MINUS, I_MINUS] = hessian[I_PLUS, I_PLUS] = gram
    rows = [a_eq, g, cone]
    lower = [b_eq, np.full(g.shape[0], -np.inf), np.full(len(cone), -np.inf)]
    upper = [b_eq, h, np.zeros(len(cone))]
    for idx, (lo, up) in enumerate(zip(*_unknown_bounds(options))):
        if np.isfinite(lo) or np.isfinite(up):
            row = np.zeros((1, N_UNKNOWN))
            row[0, idx] = 1.0
            rows.append(row)
            lower.append(np.array([lo]))
            upper.append(np.array([up]))
    solver = osqp.OSQP()
    solver.setup(
        P=sparse.csc_matrix(np.triu(hessian)),
        q=np.zeros(N_UNKNOWN),
        A=sparse.csc_matrix(np.vstack(rows)),
        l=np.concatenate(lower),
        u=np.concatenate(upper),
        eps_abs=1e-7,
        eps_rel=1e-7,
        max_iter=100000,
        polishing=True,
        polish_refine_iter=20,
        verbose=False,
    )
    # ADMM reaches 1e-7; polishing then solves the KKT system of the active set, which brings
    # the equations to rounding level. Without a successful polish the answer is refused.
    res = solver.solve(raise_error=False)
    status = str(res.info.status)
    ok = status == "solved" and res.info.status_polish == 1
    x = np.asarray(res.x, float) if ok else np.full(N_UNKNOWN, np.nan)
    reason = status if status != "solved" else "polishing failed"
    return _finish(problem, equations, "l2", options, x, ok, "optimal" if ok else f"impulse QP: {reason}")


def solve_impulses(problem: ImpactProblem, effort_name: str = "l1", options: EffortOptions = EffortOptions()) -> ImpulseSolution:
    """Solve eqs. (6)-(10) for the effort ``l1`` (LP, HiGHS) or ``l2`` (QP, OSQP) with ``options``."""
    if effort_name == "l1":
        return solve_l1(problem, options)
    if effort_name == "l2":
        return solve_l2(problem, options)
    raise ValueError(f"unknown effort {effort_name!r}: use 'l1' or 'l2'")
