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

Effort ``l1``: W = sum |I^-| + |I^+| (N m s) as a linear program solved by HiGHS (global
optimum; its dual certificate is checked). Effort ``l2``: sum of squared impulses by OSQP.
Impulses in N m s (joints) and N s (reactions); velocities in m/s and rad/s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import osqp
from scipy import sparse
from scipy.optimize import linprog

N_UNKNOWN = 47
EFFORTS = ("l1", "l2")
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


def _reduced_equations(problem: ImpactProblem) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. (6)-(10) less the one row the null vector y makes dependent (its largest entry)."""
    a, b = problem.equations()
    drop = int(np.argmax(np.abs(problem.left_null_vector())))
    keep = np.arange(42) != drop
    return a[keep], b[keep]


def _sign_constraints(problem: ImpactProblem) -> tuple[np.ndarray, np.ndarray]:
    """Rows G x <= 0: swing tip moving down before the impact, old stance tip up after it."""
    g = np.zeros((2, N_UNKNOWN))
    g[0, XD_MINUS] = problem.j2[2]
    g[1, XD_PLUS] = -problem.j1[2]
    return g, np.zeros(2)


def _reaction_bounds() -> list[tuple[float | None, float | None]]:
    """Vertical components of the three reaction impulses non-negative; the rest free."""
    bounds: list[tuple[float | None, float | None]] = [(None, None)] * N_UNKNOWN
    for sl in (IR1_MINUS, IR2, IR2_PLUS):
        bounds[sl.stop - 1] = (0.0, None)
    return bounds


def effort(x: np.ndarray) -> float:
    """W = sum |I^-| + |I^+| (N m s), paper eq. (12)."""
    return float(np.abs(x[I_MINUS]).sum() + np.abs(x[I_PLUS]).sum())


def _finish(problem: ImpactProblem, effort_name: str, x: np.ndarray, ok: bool, message: str, **kw) -> ImpulseSolution:
    a, b = problem.equations()
    return ImpulseSolution(
        success=ok,
        message=message,
        effort=effort_name,
        x=x,
        W=effort(x),
        equation_residual=float(np.max(np.abs(a @ x - b))),
        closure_residual=problem.closure_residual(),
        **kw,
    )


def solve_l1(problem: ImpactProblem) -> ImpulseSolution:
    """Minimize W = sum |I| as an LP in (x, t) with -t <= I <= t, by HiGHS; certify by duality."""
    a_eq, b_eq = _reduced_equations(problem)
    g, h = _sign_constraints(problem)
    joint_idx = np.r_[np.arange(12, 19), np.arange(37, 44)]
    n_t = joint_idx.size
    n = N_UNKNOWN + n_t
    c = np.concatenate([np.zeros(N_UNKNOWN), np.ones(n_t)])
    a_ub = np.zeros((2 * n_t + g.shape[0], n))
    for k, j in enumerate(joint_idx):
        a_ub[2 * k, j], a_ub[2 * k, N_UNKNOWN + k] = 1.0, -1.0
        a_ub[2 * k + 1, j], a_ub[2 * k + 1, N_UNKNOWN + k] = -1.0, -1.0
    a_ub[2 * n_t :, :N_UNKNOWN] = g
    b_ub = np.concatenate([np.zeros(2 * n_t), h])
    a_eq_full = np.hstack([a_eq, np.zeros((a_eq.shape[0], n_t))])
    bounds = _reaction_bounds() + [(0.0, None)] * n_t
    res = linprog(c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq_full, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status != 0 or res.x is None:
        return _finish(problem, "l1", np.full(N_UNKNOWN, np.nan), False, f"impulse LP: {res.message}")
    gap = duality_gap(c, a_ub, b_ub, a_eq_full, b_eq, bounds, res)
    return _finish(problem, "l1", res.x[:N_UNKNOWN], True, "optimal", duality_gap=gap)


def duality_gap(c, a_ub, b_ub, a_eq, b_eq, bounds, res) -> float:
    """Certificate of a HiGHS LP optimum: the larger of the primal-dual objective gap and the
    dual infeasibility (both relative to the objective's scale), from HiGHS's marginals."""
    y_eq = res.eqlin.marginals
    y_ub = res.ineqlin.marginals
    y_lo = res.lower.marginals
    y_up = res.upper.marginals
    lower = np.array([lo if lo is not None else 0.0 for lo, _ in bounds])
    upper = np.array([up if up is not None else 0.0 for _, up in bounds])
    dual_obj = b_eq @ y_eq + b_ub @ y_ub + lower @ y_lo + upper @ y_up
    stationarity = c - a_eq.T @ y_eq - a_ub.T @ y_ub - y_lo - y_up
    sign_violation = max(0.0, float(np.max(y_ub, initial=0.0)), float(-np.min(y_lo, initial=0.0)))
    scale = max(1.0, abs(res.fun))
    return max(abs(res.fun - dual_obj), float(np.max(np.abs(stationarity))), sign_violation) / scale


def solve_l2(problem: ImpactProblem) -> ImpulseSolution:
    """Minimize sum I_i^2 (N^2 m^2 s^2) under the same constraints, by OSQP (polished)."""
    a_eq, b_eq = _reduced_equations(problem)
    g, h = _sign_constraints(problem)
    weights = np.zeros(N_UNKNOWN)
    weights[I_MINUS] = weights[I_PLUS] = 2.0
    rows = [a_eq, g]
    lower = [b_eq, np.full(g.shape[0], -np.inf)]
    upper = [b_eq, h]
    for idx, (lo, _) in enumerate(_reaction_bounds()):
        if lo is not None:
            row = np.zeros((1, N_UNKNOWN))
            row[0, idx] = 1.0
            rows.append(row)
            lower.append(np.array([lo]))
            upper.append(np.array([np.inf]))
    solver = osqp.OSQP()
    solver.setup(
        P=sparse.diags(weights, format="csc"),
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
    return _finish(problem, "l2", x, ok, "optimal" if ok else f"impulse QP: {reason}")


def solve_impulses(problem: ImpactProblem, effort_name: str = "l1") -> ImpulseSolution:
    """Solve eqs. (6)-(10) for the effort ``l1`` (LP, HiGHS) or ``l2`` (QP, OSQP)."""
    if effort_name == "l1":
        return solve_l1(problem)
    if effort_name == "l2":
        return solve_l2(problem)
    raise ValueError(f"unknown effort {effort_name!r}: use 'l1' or 'l2'")
