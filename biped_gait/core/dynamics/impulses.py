"""Impulsive double support (docs/model.md section 4, paper eqs. 6-10) and its minimum-effort solution.

Unknowns, in this order (``ImpactLayout``; the sizes of the paper's 9-DOF model in brackets):
Xd^- (nX [12]), I^- (nA [7]), I_R1^- (c1 [3]), Xd^+ (nX), I_R2 (c2 [3]), I^+ (nA), I_R2^+ (c2), nX
the double-support coordinates, nA the actuated joints, c1 and c2 the rows of the contact
Jacobians J1 and J2 (the tips' positions, and with lateral hip joints the feet's spin, whose
reactions are moment impulses). Equations (3 nX + c1 + c2 [42]):

    (6)  D_e Xd^- - B_e I^- - J1^T I_R1^- = D_e Xd^b
    (7)  J1 Xd^- = J1 Xd^b
    (8)  D_e (Xd^+ - Xd^-) - J2^T I_R2 = 0
    (9)  J2 Xd^+ = 0
    (10) -D_e Xd^+ - B_e I^+ - J2^T I_R2^+ = -D_e Xd^a

When y = [z_d; 0; z_d; 0; z_d] is a left null vector (z_d the locked rotation about the
foot-to-foot line: always for legs of pitch joints, and for lateral hip joints when both feet's
spin axes are vertical, i.e. both ankle rolls are zero), the rank is one short, the system is
consistent only if y^T b = z_d^T D_e (Xd^b - Xd^a) = 0, and one dependent row is dropped; the
closure residual is checked and reported.

Effort ``l1``: W = sum |I^-| + |I^+| (N m s) as a linear program solved by HiGHS through
``highspy`` (global optimum; its dual certificate is checked). Effort ``l2``: sum of squared impulses by OSQP.
Impulses in N m s (joints) and N s (reactions); velocities in m/s and rad/s.

Options (``EffortOptions``, docs/model.md section 4.4): the friction cone of the floor on the
three reaction impulses, linearized as the inscribed octagonal pyramid (so that no impulse
needs more than ``friction``); a bound on the actuated joints' rates between the sub-phases
(Xd^-, Xd^+); and the effort's reading, on joint angles (``joint``, the paper's eq. 12) or on the
absolute angles of the links (``absolute``: each link's net torque impulse, its proximal
joint's minus its distal joints').
"""

from __future__ import annotations

import threading
import weakref
from functools import cached_property, lru_cache
import math
from dataclasses import dataclass, replace

import highspy
import numpy as np

from ..model.biped import BipedModel

EFFORTS = ("l1", "l2")
COORDINATES = ("joint", "absolute")
CONE_SIDES = 8  # the friction cone's inscribed pyramid
# N s: a reaction impulse this small is zero: its size is below what the plan knows of it (1e-8 at
# the unit scale, docs/model.md section 4.11), and its direction is rounding's (a touchdown at rest
# leaves I_R2 at about 1e-10 N s, whose friction ratio read anything from 0 to 0.5 from one grid to
# the next, and would read inf with a vertical component of -1e-16).
ZERO_REACTION = 1e-8


@dataclass(frozen=True)
class ImpactLayout:
    """The shape of one model's double-support problem: ``nx`` coordinates X, the actuated ones
    at ``joint_rows`` of X, ``contact_old`` and ``contact_new`` rows of J1 and J2, and the
    absolute reading of the effort (``absolute_rows``, one row over the actuated joints per
    link). Everything hashable, so that the effort's parts are cached per layout."""

    nx: int
    joint_rows: tuple[int, ...]
    contact_old: int
    contact_new: int
    absolute_rows: tuple[tuple[float, ...], ...]

    @classmethod
    def of(cls, bm: BipedModel) -> "ImpactLayout":
        """The layout of ``bm``'s double support (made once per model)."""
        layout = _LAYOUTS.get(bm)
        if layout is None:
            contacts = 4 if bm.spin else 3
            layout = _LAYOUTS[bm] = _layout(bm.double_support.nv, tuple(int(k) for k in bm.ds_actuated), contacts,
                                            contacts, absolute_reading(bm))
        return layout

    @property
    def na(self) -> int:
        return len(self.joint_rows)

    @cached_property
    def joints(self) -> np.ndarray | slice:
        """Rows of X of the actuated joints (a slice when they are contiguous)."""
        rows = self.joint_rows
        contiguous = rows == tuple(range(rows[0], rows[0] + len(rows)))
        return slice(rows[0], rows[-1] + 1) if contiguous else np.array(rows)

    @cached_property
    def _span_list(self) -> tuple[slice, ...]:
        sizes = (self.nx, self.na, self.contact_old, self.nx, self.contact_new, self.na, self.contact_new)
        ends = np.cumsum(sizes)
        return tuple(slice(int(e - n), int(e)) for e, n in zip(ends, sizes))

    xd_minus = property(lambda self: self._span_list[0], doc="Xd^-: after I^-, before the impact")
    i_minus = property(lambda self: self._span_list[1], doc="I^-: joint impulses before the impact")
    ir1_minus = property(lambda self: self._span_list[2], doc="I_R1^-: the old stance tip's reaction")
    xd_plus = property(lambda self: self._span_list[3], doc="Xd^+: just after the passive impact")
    ir2 = property(lambda self: self._span_list[4], doc="I_R2: the passive impact at the new stance tip")
    i_plus = property(lambda self: self._span_list[5], doc="I^+: joint impulses after the impact")
    ir2_plus = property(lambda self: self._span_list[6], doc="I_R2^+: the new stance tip's reaction to I^+")

    @property
    def unknowns(self) -> int:
        return self._span_list[6].stop

    @property
    def equations(self) -> int:
        return 3 * self.nx + self.contact_old + self.contact_new

    @property
    def reactions(self) -> tuple[slice, slice, slice]:
        """The three reaction impulses (forces first, then a spin moment impulse if any)."""
        return self.ir1_minus, self.ir2, self.ir2_plus

    @property
    def b_e(self) -> np.ndarray:
        """B_e (nX x nA): joint impulses act on the actuated coordinates."""
        out = np.zeros((self.nx, self.na))
        out[list(self.joint_rows), range(self.na)] = 1.0
        return out

    @property
    def absolute(self) -> np.ndarray:
        return np.array(self.absolute_rows, dtype=float)


_LAYOUTS: "weakref.WeakKeyDictionary[BipedModel, ImpactLayout]" = weakref.WeakKeyDictionary()


@lru_cache(maxsize=16)
def _layout(nx: int, joint_rows: tuple[int, ...], contact_old: int, contact_new: int,
            absolute_rows: tuple[tuple[float, ...], ...]) -> ImpactLayout:
    return ImpactLayout(nx, joint_rows, contact_old, contact_new, absolute_rows)


def absolute_reading(bm: BipedModel) -> tuple[tuple[float, ...], ...]:
    """The effort read on the links' absolute angles (docs/model.md section 4.4): per actuated
    joint, the net torque impulse on the link it drives, its own impulse less those of the nearest
    joints beyond that turn about the same axis (found through joints about other axes, which do
    not change that angle at the double support). The stance shin's (the knee's reaction on a link
    whose own joint, the ankle, is passive) is not counted."""
    coordinates, parents = bm.coordinates, bm.single.parents  # joint k + 1 is coordinate k
    children: dict[int, list[int]] = {}
    for k in range(len(coordinates)):
        children.setdefault(parents[k + 1] - 1, []).append(k)
    actuated = [k for k, c in enumerate(coordinates) if c.actuated]
    rows = []
    for k in actuated:
        row, frontier = [0.0] * len(actuated), list(children.get(k, []))
        row[actuated.index(k)] = 1.0
        while frontier:
            j = frontier.pop(0)
            if coordinates[j].axis == coordinates[k].axis:
                row[actuated.index(j)] = -1.0
            else:
                frontier += children.get(j, [])
        rows.append(tuple(row))
    return tuple(rows)


@dataclass(frozen=True, eq=False)
class ImpactProblem:
    """The data of one double support: D_e, J1, J2 at q(T), Xd^b, Xd^a, z_d, and the layout."""

    mass_matrix: np.ndarray
    j1: np.ndarray
    j2: np.ndarray
    xd_b: np.ndarray
    xd_a: np.ndarray
    locked_rotation: np.ndarray
    layout: ImpactLayout

    def equations(self) -> tuple[np.ndarray, np.ndarray]:
        """The matrix and right-hand side of eqs. (6)-(10), in the module's order."""
        d, j1, j2, lay = self.mass_matrix, self.j1, self.j2, self.layout
        n, c1, c2 = lay.nx, lay.contact_old, lay.contact_new
        b_e = lay.b_e
        rows = np.cumsum([0, n, c1, n, c2, n])
        a = np.zeros((lay.equations, lay.unknowns))
        b = np.zeros(lay.equations)
        r6, r7, r8, r9, r10 = (slice(int(rows[k]), int(rows[k + 1])) for k in range(5))
        a[r6, lay.xd_minus], a[r6, lay.i_minus], a[r6, lay.ir1_minus] = d, -b_e, -j1.T
        b[r6] = d @ self.xd_b
        a[r7, lay.xd_minus] = j1
        b[r7] = j1 @ self.xd_b
        a[r8, lay.xd_plus], a[r8, lay.xd_minus], a[r8, lay.ir2] = d, -d, -j2.T
        a[r9, lay.xd_plus] = j2
        a[r10, lay.xd_plus], a[r10, lay.i_plus], a[r10, lay.ir2_plus] = -d, -b_e, -j2.T
        b[r10] = -d @ self.xd_a
        return a, b

    def left_null_vector(self) -> np.ndarray:
        """y with y^T A = 0 when the momentum about the foot-to-foot line is conserved: z_d on
        the rows of eqs. (6), (8) and (10)."""
        lay = self.layout
        y = np.zeros(lay.equations)
        z = self.locked_rotation
        n, c1, c2 = lay.nx, lay.contact_old, lay.contact_new
        y[0:n], y[n + c1: 2 * n + c1], y[2 * n + c1 + c2:] = z, z, z
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


@dataclass(frozen=True)
class EffortOptions:
    """How the double support's impulses are chosen beyond eqs. (6)-(10): the floor's friction
    coefficient on the reaction impulses (inf: no cone), a bound (rad/s) on the actuated joints'
    rates in Xd^- and Xd^+ (inf: none), and the effort's reading (``joint``/``absolute``)."""

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

    def reading(self, layout: ImpactLayout) -> np.ndarray:
        """The rows whose absolute values the effort sums, applied to I^- and to I^+ (a column per
        actuated joint)."""
        return layout.absolute if self.coordinates == "absolute" else np.eye(layout.na)


@dataclass(frozen=True, eq=False)
class ImpulseSolution:
    """The chosen solution of eqs. (6)-(10); ``success`` False carries the solver's reason."""

    success: bool
    message: str
    effort: str
    x: np.ndarray
    W: float
    equation_residual: float
    closure_residual: float
    layout: ImpactLayout
    duality_gap: float = float("nan")
    basis: tuple[np.ndarray, np.ndarray] | None = None  # the l1 LP's optimal basis (HiGHS's column and row statuses)

    xd_minus = property(lambda self: self.x[self.layout.xd_minus], doc="Xd^-: after I^-, before the impact")
    i_minus = property(lambda self: self.x[self.layout.i_minus], doc="I^-: joint impulses before the impact (N m s)")
    ir1_minus = property(lambda self: self.x[self.layout.ir1_minus][:3], doc="I_R1^-: old stance tip's reaction (N s)")
    xd_plus = property(lambda self: self.x[self.layout.xd_plus], doc="Xd^+: just after the passive impact")
    ir2 = property(lambda self: self.x[self.layout.ir2][:3], doc="I_R2: the passive impact at the new stance tip (N s)")
    i_plus = property(lambda self: self.x[self.layout.i_plus], doc="I^+: joint impulses after the impact (N m s)")
    ir2_plus = property(lambda self: self.x[self.layout.ir2_plus][:3], doc="I_R2^+: new stance tip's reaction to I^+ (N s)")

    @property
    def spin_impulses(self) -> np.ndarray:
        """The ground's moment impulses (N m s) about the feet's spin axes in I_R1^-, I_R2 and
        I_R2^+ (empty for legs of pitch joints, whose model holds the spin implicitly)."""
        lay = self.layout
        if lay.contact_old == 3:
            return np.zeros(0)
        return np.array([self.x[sl][3] for sl in lay.reactions])

    def foot_line_moment(self, problem: "ImpactProblem") -> float:
        """y^T A x (kg m^2/s): the momentum about the feet line the ground's spin moment impulses
        of this solution change (zero where the feet's spin axes are vertical, and with the
        paper's nine joints). The double support is consistent when the closure gap, z_d^T D_e
        (Xd^a - Xd^b), equals minus this."""
        if self.layout.contact_old == 3:
            return 0.0
        a, _ = problem.equations()
        return float(problem.left_null_vector() @ a @ self.x)

    @property
    def joint_rates(self) -> np.ndarray:
        """The actuated joints' rates in Xd^- and Xd^+ (rad/s)."""
        rows = self.layout.joints
        return np.concatenate([self.xd_minus[rows], self.xd_plus[rows]])


Equations = tuple[np.ndarray, np.ndarray]  # A and b of eqs. (6)-(10)


def _reduced_equations(problem: ImpactProblem, equations: Equations) -> Equations:
    """Eqs. (6)-(10) less the row of the largest entry of y, the combination that carries the
    momentum about the feet line: with the feet's spin axes vertical it depends on the others;
    with them tilted (legs leaning), it says how much of that momentum the ground's spin moments
    change, and the gait's closure is solved to match what they do (``foot_line_moment``,
    docs/model.md section 5.2)."""
    a, b = equations
    drop = int(np.argmax(np.abs(problem.left_null_vector())))
    keep = np.arange(len(b)) != drop
    return a[keep], b[keep]


def _sign_constraints(problem: ImpactProblem) -> tuple[np.ndarray, np.ndarray]:
    """Rows G x <= 0: swing tip moving down before the impact, old stance tip up after it."""
    lay = problem.layout
    g = np.zeros((2, lay.unknowns))
    g[0, lay.xd_minus] = problem.j2[2]
    g[1, lay.xd_plus] = -problem.j1[2]
    return g, np.zeros(2)


def _reaction_lower_bounds(layout: ImpactLayout) -> np.ndarray:
    """Lower bounds of the unknowns: the vertical components of the three reaction impulses
    non-negative (N s), the rest free (-inf)."""
    lower = np.full(layout.unknowns, -np.inf)
    for sl in layout.reactions:
        lower[sl.start + 2] = 0.0
    return lower


def effort(x: np.ndarray, layout: ImpactLayout, reading: np.ndarray | None = None) -> float:
    """W = sum |I^-| + |I^+| (N m s), paper eq. (12); with ``reading``, the sum of the absolute
    values of ``reading @ I^-`` and ``reading @ I^+``."""
    i_minus, i_plus = x[layout.i_minus], x[layout.i_plus]
    if reading is None:
        return float(np.abs(i_minus).sum() + np.abs(i_plus).sum())
    return float(np.abs(reading @ i_minus).sum() + np.abs(reading @ i_plus).sum())


def friction_ratios(solution: ImpulseSolution) -> np.ndarray:
    """|horizontal| / vertical of the three reaction impulses I_R1^-, I_R2, I_R2^+: the friction
    coefficient each needs (inf where the vertical component is zero and the horizontal not; 0
    for a reaction within ``ZERO_REACTION`` of zero, whose direction is rounding's)."""
    out = np.empty(3)
    for k, force in enumerate((solution.ir1_minus, solution.ir2, solution.ir2_plus)):
        fx, fy, fz = force
        horizontal = math.hypot(fx, fy)
        if math.hypot(horizontal, fz) <= ZERO_REACTION:
            out[k] = 0.0
        else:
            out[k] = horizontal / fz if fz > 0 else (0.0 if horizontal == 0 else math.inf)
    return out


def pyramid(friction: float) -> np.ndarray:
    """The inscribed octagonal pyramid of the friction cone of coefficient ``friction`` (section
    4.4): rows G (CONE_SIDES x 3) with G f <= 0 for a force or impulse f = [fx, fy, fz] inside it,
    cos(a) fx + sin(a) fy <= mu cos(pi/8) fz for eight directions a; none for mu = inf."""
    if not math.isfinite(friction):
        return np.zeros((0, 3))
    angles = 2 * np.pi * np.arange(CONE_SIDES) / CONE_SIDES
    return np.column_stack([np.cos(angles), np.sin(angles), np.full(CONE_SIDES, -friction * math.cos(math.pi / CONE_SIDES))])


def _cone_rows(options: EffortOptions, layout: ImpactLayout) -> np.ndarray:
    """Rows G x <= 0 of the pyramid (``pyramid``) on each reaction impulse of the unknowns x."""
    sides = pyramid(options.friction)
    rows = np.zeros((len(sides) * len(layout.reactions), layout.unknowns))
    for k, sl in enumerate(layout.reactions):
        rows[k * len(sides):(k + 1) * len(sides), sl.start:sl.start + 3] = sides
    return rows


def _unknown_bounds(options: EffortOptions, layout: ImpactLayout) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of the unknowns: the reactions' vertical components non-negative,
    the actuated joints' rates in Xd^- and Xd^+ within the rate bound."""
    lower, upper = _reaction_lower_bounds(layout), np.full(layout.unknowns, np.inf)
    if math.isfinite(options.rate_bound):
        for sl in (layout.xd_minus, layout.xd_plus):
            joints = np.array(layout.joint_rows) + sl.start
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
        W=effort(x, problem.layout, options.reading(problem.layout) if options.coordinates != "joint" else None),
        equation_residual=float(np.max(np.abs(a @ x - b))),
        closure_residual=problem.closure_residual(),
        layout=problem.layout,
        **kw,
    )


@dataclass(frozen=True, eq=False)
class _Effort:
    """The parts of the effort LP that depend only on the options and the layout: its variables
    are x (the layout's unknowns), then t (one per reading row of I^- and of I^+) bounding the absolute values summed; cost
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
def _effort_parts(options: EffortOptions, layout: ImpactLayout) -> _Effort:
    reading = options.reading(layout)
    n_x = layout.unknowns
    n_t = 2 * len(reading)
    size = n_x + n_t
    lower, upper = _unknown_bounds(options, layout)
    abs_rows = np.zeros((2 * n_t, size))
    k = 0
    for block in (layout.i_minus, layout.i_plus):
        for row in reading:  # row . I - t_k <= 0 and -row . I - t_k <= 0
            abs_rows[2 * k, block], abs_rows[2 * k + 1, block] = row, -row
            abs_rows[2 * k: 2 * k + 2, n_x + k] = -1.0
            k += 1
    cone = np.zeros((0, size))
    cone_x = _cone_rows(options, layout)
    if len(cone_x):
        cone = np.hstack([cone_x, np.zeros((len(cone_x), n_t))])
    return _Effort(np.concatenate([np.zeros(n_x), np.ones(n_t)]), np.concatenate([lower, np.zeros(n_t)]),
                   np.concatenate([upper, np.full(n_t, np.inf)]), abs_rows, cone)


@dataclass(frozen=True, eq=False)
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
    parts = _effort_parts(options, problem.layout)
    n_x = problem.layout.unknowns
    a_eq, b_eq = _reduced_equations(problem, equations)
    g, h = _sign_constraints(problem)
    n_abs, n_cone = len(parts.abs_rows), len(parts.cone_rows)
    inequalities = n_abs + len(g) + n_cone
    a = np.zeros((inequalities + len(a_eq), parts.size))
    a[:n_abs] = parts.abs_rows
    a[n_abs: n_abs + len(g), :n_x] = g
    a[n_abs + len(g): inequalities] = parts.cone_rows
    a[inequalities:, :n_x] = a_eq
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


def _basis(statuses: tuple[np.ndarray, np.ndarray]) -> highspy.HighsBasis:
    """A HiGHS basis from its column and row statuses (``ImpulseSolution.basis``)."""
    basis = highspy.HighsBasis()
    basis.col_status = list(map(highspy.HighsBasisStatus, statuses[0].tolist()))
    basis.row_status = list(map(highspy.HighsBasisStatus, statuses[1].tolist()))
    basis.valid = True
    return basis


def solve_l1(problem: ImpactProblem, options: EffortOptions = EffortOptions(),
             start: tuple[np.ndarray, np.ndarray] | None = None) -> ImpulseSolution:
    """Minimize W = sum |reading I| as an LP in (x, t) with -t <= reading I <= t, by HiGHS;
    certify by duality. ``start``: the basis of a nearby LP of the same shape
    (``ImpulseSolution.basis``): where it is optimal for this LP too, the optimum is solved on it
    by one linear system and certified (``_on_basis``: a sixth of HiGHS's time from that basis, which
    then takes none of its iterations); else the simplex starts from it (a cold start takes about
    40 iterations). The optimum is the same, to rounding, where it is unique."""
    equations = problem.equations()
    lp = _l1_program(problem, equations, options)
    started = start is not None and start[0].size == lp.a.shape[1] and start[1].size == lp.a.shape[0]
    if started:
        on_basis = _on_basis(lp, start)
        if on_basis is not None:
            x, gap = on_basis
            return _finish(problem, equations, "l1", options, x[: problem.layout.unknowns], True, "optimal",
                           duality_gap=gap, basis=start)
    highs = _highs()
    _pass_model(highs, lp)
    if started:
        highs.setBasis(_basis(start))
    highs.run()
    status = highs.getModelStatus()
    if status != highspy.HighsModelStatus.kOptimal:
        message = f"impulse LP: model status is {highs.modelStatusToString(status)}"
        return _finish(problem, equations, "l1", options, np.full(problem.layout.unknowns, np.nan), False, message)
    solution = highs.getSolution()
    basis = highs.getBasis()
    status = np.array(basis.col_status, dtype=np.int8)
    row_dual = np.array(solution.row_dual)
    y_lower = np.where(status == int(highspy.HighsBasisStatus.kLower), solution.col_dual, 0.0)
    y_upper = np.where(status == int(highspy.HighsBasisStatus.kUpper), solution.col_dual, 0.0)
    gap = duality_gap(lp, highs.getInfo().objective_function_value, row_dual[lp.inequalities :],
                      row_dual[: lp.inequalities], y_lower, y_upper)
    return _finish(problem, equations, "l1", options, np.array(solution.col_value[: problem.layout.unknowns]), True,
                   "optimal", duality_gap=gap, basis=(status, np.array(basis.row_status, dtype=np.int8)))


CERTIFIED = 1e-9  # the largest primal infeasibility and duality gap (relative) a basis's solution may keep


def _on_basis(lp: _L1Program, statuses: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, float] | None:
    """The optimum of ``lp`` on the basis ``statuses`` (HiGHS's column and row statuses), if that
    basis is optimal for it: the nonbasic columns at their bounds and the nonbasic rows at theirs
    make a square system, whose solution must be feasible (within ``CERTIFIED``) and whose
    multipliers must have the signs of an optimum (the duality gap's certificate, ``duality_gap``,
    within ``CERTIFIED``). That is the vertex HiGHS's simplex would return from that basis without an
    iteration, by one linear solve instead of a model passed and factorized (a nearby LP's basis:
    the plan's double support on the estimate's grid, or an atlas node's). None: not optimal there
    (or degenerate: an equality row basic), the LP is left to HiGHS."""
    col, row = statuses
    basic, lower, upper = (int(s) for s in (highspy.HighsBasisStatus.kBasic, highspy.HighsBasisStatus.kLower,
                                            highspy.HighsBasisStatus.kUpper))
    n_cols = lp.a.shape[1]
    equality = np.arange(len(row)) >= lp.inequalities
    if np.any((row == basic) & equality):
        return None
    at_lower, at_upper = col == lower, col == upper
    fixed_cols = np.flatnonzero(at_lower | at_upper)
    tight_rows = np.flatnonzero(row != basic)
    if len(fixed_cols) + len(tight_rows) != n_cols or not np.all(np.isin(col[fixed_cols], (lower, upper))):
        return None
    bounds = np.where(at_lower, lp.parts.lower, lp.parts.upper)[fixed_cols]
    if not np.all(np.isfinite(bounds)):
        return None
    system = np.zeros((n_cols, n_cols))
    system[np.arange(len(fixed_cols)), fixed_cols] = 1.0
    system[len(fixed_cols):] = lp.a[tight_rows]
    try:
        x = np.linalg.solve(system, np.concatenate([bounds, lp.b[tight_rows]]))
        multipliers = np.linalg.solve(system.T, lp.parts.cost)
    except np.linalg.LinAlgError:
        return None
    scale = max(1.0, float(np.max(np.abs(x))))
    infeasible = max(float(np.max(lp.parts.lower - x, initial=0.0)), float(np.max(x - lp.parts.upper, initial=0.0)),
                     float(np.max(lp.a_ub @ x - lp.b_ub, initial=0.0)))
    on_rows = np.zeros(len(row))
    on_rows[tight_rows] = multipliers[len(fixed_cols):]
    on_cols = np.zeros(n_cols)
    on_cols[fixed_cols] = multipliers[: len(fixed_cols)]
    gap = duality_gap(lp, float(lp.parts.cost @ x), on_rows[lp.inequalities:], on_rows[: lp.inequalities],
                      np.where(at_lower, on_cols, 0.0), np.where(at_upper, on_cols, 0.0))
    return (x, gap) if infeasible <= CERTIFIED * scale and gap <= CERTIFIED else None


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
    lay = problem.layout
    n_x = lay.unknowns
    a_eq, b_eq = _reduced_equations(problem, equations)
    g, h = _sign_constraints(problem)
    cone = _cone_rows(options, lay)
    hessian = np.zeros((n_x, n_x))
    reading = options.reading(lay)
    gram = 2.0 * reading.T @ reading
    hessian[lay.i_minus, lay.i_minus] = hessian[lay.i_plus, lay.i_plus] = gram
    rows = [a_eq, g, cone]
    lower = [b_eq, np.full(g.shape[0], -np.inf), np.full(len(cone), -np.inf)]
    upper = [b_eq, h, np.zeros(len(cone))]
    for idx, (lo, up) in enumerate(zip(*_unknown_bounds(options, lay))):
        if np.isfinite(lo) or np.isfinite(up):
            row = np.zeros((1, n_x))
            row[0, idx] = 1.0
            rows.append(row)
            lower.append(np.array([lo]))
            upper.append(np.array([up]))
    solver = osqp.OSQP()
    solver.setup(
        P=sparse.csc_matrix(np.triu(hessian)),
        q=np.zeros(n_x),
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
    x = np.asarray(res.x, float) if ok else np.full(n_x, np.nan)
    reason = status if status != "solved" else "polishing failed"
    return _finish(problem, equations, "l2", options, x, ok, "optimal" if ok else f"impulse QP: {reason}")


def solve_impulses(problem: ImpactProblem, effort_name: str = "l1", options: EffortOptions = EffortOptions(),
                   start: tuple[np.ndarray, np.ndarray] | None = None) -> ImpulseSolution:
    """Solve eqs. (6)-(10) for the effort ``l1`` (LP, HiGHS; from the basis ``start``, if given)
    or ``l2`` (QP, OSQP) with ``options``."""
    if effort_name == "l1":
        return solve_l1(problem, options, start)
    if effort_name == "l2":
        return solve_l2(problem, options)
    raise ValueError(f"unknown effort {effort_name!r}: use 'l1' or 'l2'")
