"""A double support that lasts: the impulses of docs/model.md section 4.3 replaced by bounded joint
torques over a phase of duration d, planned so that the gait is exactly periodic, and walked with
feedback (docs/model.md section 10; the planning part).

**The phase.** Around the touchdown, d / 2 on each side (project choice: the paper's three
sub-phases (6)-(10) with their impulses spread over time; the feet are on the ground positions
of the impulsive double support to within the distance they move in d / 2, millimetres):

- the pre-impact pulse, the last d / 2 of the single support: constant joint torques u^- (N m,
  the actuated joints), the old stance foot on the ground, the swing foot coming down onto it at
  the touchdown (the gait's q_T);
- the passive impact at the touchdown (eqs. 8-9: the new foot lands, the old one leaves);
- the post-impact pulse, the first d / 2 of the next single support: constant torques u^+, the new
  stance foot on the ground, the old one lifting off.

Between the pulses the single support is ballistic. As d -> 0, (d / 2) u^- and (d / 2) u^+ become
the impulses I^- and I^+ of an impulsive double support of the same gait, and the effort
E = (d / 2) sum (|u^-| + |u^+|) (N m s, the torques' integral) becomes W.

**The plan** (``plan_finite_support``): unknowns z = (v_0, theta, u^+, u^-): the velocity just
after the impact and the leg exchange (rad/s, the step's own coordinates), the trunk pitch of the
boundary configurations (rad), the torques. The step, from (q_0(theta), v_0): the post-impact
pulse, the ballistic flow for T - d, the pre-impact pulse; the periodicity: the configuration at T
is q_T(theta) (nq equations) and the passive impact there, then the leg exchange, gives v_0 back
(nq). 2 nq equations in 2 nq + 1 + 2 nA unknowns: a linear program in the step of z, repeated
(sequential linear programming, the equations linearized by differences), minimizes E subject to
the linearized periodicity, the friction cone (the inscribed octagonal pyramid, as section 4.4) and
a positive normal force at the stance foot at every node of both pulses, the passive impact's
reaction impulse in the cone and pushing, the old stance foot leaving the ground; from the
impulsive gait (u = I / (d / 2)) until the equations hold to 1e-11.

**Status.** The sequential linear programs converge, by continuation in d from 0.25 ms, up to
d = 0.5 ms at the default gait (E within 1e-4 of W at 0.1 ms, tests/test_finite_support.py); from
1 ms on they stall (the trust region shrinks without the merit falling). Walking this phase with
feedback (the re-aim with the torques as its handles) and in MuJoCo is not built yet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg import null_space
from scipy.optimize import linprog

from ..dynamics.hybrid import HybridStep, ImpactMap, impact_with
from ..dynamics.impulses import CONE_SIDES
from ..dynamics.settings import DEFAULTS
from ..gait.configurations import boundary_configurations
from ..gait.gait import Gait
from ..model.exchange import exchange_matrix

PULSE_STEPS = 16  # RK4 steps per half pulse
FD_STEP = 1e-7  # the differences of the plan's and the re-aim's Jacobians
TOLERANCE = 1e-11  # rad, rad/s: the periodicity the plan reaches
SLP_ITERATIONS = 60


class FiniteSupportFailed(Exception):
    """The finite double support has no plan: the message says why."""


def ground_reaction(hybrid: HybridStep, q: np.ndarray, qd: np.ndarray, torque: np.ndarray) -> np.ndarray:
    """[Fx, Fy, Fz] (N, world axes of the step's model) at the stance tip, the joints driven by
    ``torque`` (nq, zero on the ankle): the extended model's inverse dynamics with the tip held."""
    bm = hybrid.bm
    qdd = pin.aba(bm.single, bm.single_data, q, qd, torque)
    x, xd, xdd = bm.extended_state(q), np.concatenate([np.zeros(3), qd]), np.concatenate([np.zeros(3), qdd])
    return pin.rnea(bm.extended, bm.extended_data, x, xd, xdd)[:3].copy()


def pulse(hybrid: HybridStep, q: np.ndarray, qd: np.ndarray, torque: np.ndarray, duration: float,
          steps: int = PULSE_STEPS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The single support driven by constant joint torques ``torque`` (nq: zero on the passive
    ankle, N m) for ``duration`` (s), RK4 in ``steps`` steps: the end (q, qd) and the ground
    reaction at the steps' nodes (steps + 1 rows of [Fx, Fy, Fz], N)."""
    bm = hybrid.bm
    model, data = bm.single, bm.single_data
    h = duration / steps

    def f(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return pin.aba(model, data, a, b, torque)

    forces = [ground_reaction(hybrid, q, qd, torque)]
    for _ in range(steps):
        k1v, k1a = qd, f(q, qd)
        k2v, k2a = qd + h / 2 * k1a, f(q + h / 2 * k1v, qd + h / 2 * k1a)
        k3v, k3a = qd + h / 2 * k2a, f(q + h / 2 * k2v, qd + h / 2 * k2a)
        k4v, k4a = qd + h * k3a, f(q + h * k3v, qd + h * k3a)
        q = q + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        qd = qd + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
        forces.append(ground_reaction(hybrid, q, qd, torque))
    return q, qd, np.array(forces)


@dataclass(frozen=True, eq=False)
class Impact:
    """The passive impact at a touchdown configuration: the velocity after it (X coordinates), the
    reaction impulse at the new stance foot (N s, world axes of the step) and the old stance foot's
    vertical velocity after it (m/s, >= 0: it leaves the ground)."""

    xd_plus: np.ndarray
    reaction: np.ndarray
    old_foot_vz: float


def passive_impact(impact: ImpactMap, qd: np.ndarray) -> Impact:
    """Eqs. (8)-(9) at ``impact``'s configuration from the single-support velocity ``qd``."""
    bm = impact.bm
    xd_b = bm.embed(qd)
    rows = impact.layout.joints
    xd_plus = impact_with(impact.mass_matrix, impact.j2, xd_b, np.zeros(impact.layout.na), rows, at_rest=True)
    reaction = np.linalg.lstsq(impact.j2.T, impact.mass_matrix @ (xd_plus - xd_b), rcond=None)[0]
    return Impact(xd_plus, reaction[:3], float(impact.j1[2] @ xd_plus))


def cone_rows(force: np.ndarray, friction: float) -> np.ndarray:
    """The inscribed octagonal pyramid of the friction cone on ``force`` (N or N s; [Fx, Fy, Fz],
    or rows of them): values <= 0 inside (section 4.4), and -Fz (the normal force positive); none
    of the cone's for mu = inf. One row of values per force."""
    force = np.asarray(force, dtype=float)
    fx, fy, fz = force[..., 0], force[..., 1], force[..., 2]
    rows = [-fz]
    if math.isfinite(friction):
        apothem = friction * math.cos(math.pi / CONE_SIDES)
        rows += [math.cos(a) * fx + math.sin(a) * fy - apothem * fz
                 for a in 2 * math.pi * np.arange(CONE_SIDES) / CONE_SIDES]
    return np.stack(rows, axis=-1)


def friction_ratio(forces: np.ndarray) -> float:
    """The largest |F_xy| / F_z of the rows of ``forces`` (inf where F_z <= 0)."""
    fz = forces[:, 2]
    horizontal = np.hypot(forces[:, 0], forces[:, 1])
    return float(np.max(np.where(fz > 0, horizontal / np.where(fz > 0, fz, 1.0), np.inf)))


@dataclass(frozen=True, eq=False)
class FiniteSupport:
    """A periodic gait with a double support of ``duration`` d (s): the step's start just after the
    leg exchange (q0, v0), its touchdown (q_t, and qd_t just before the impact), the trunk pitch
    theta (rad), the torques u^+ and u^- (N m, the actuated joints), the state at the decision
    point (the pre-impact pulse's start, T - d/2), the effort E (N m s) beside the impulsive gait's
    W, the friction the phase needs (the largest |F_xy| / F_z at the stance foot over both pulses,
    and of the impact's reaction impulse), the largest torque (N m), the periodicity's residual,
    and whether E is the least (the sequential LPs converged; else the periodic phase Gauss-Newton
    found nearest the shorter phase's, its effort not minimized)."""

    duration: float
    period: float
    q0: np.ndarray
    v0: np.ndarray
    q_t: np.ndarray
    qd_t: np.ndarray
    theta: float
    u_plus: np.ndarray
    u_minus: np.ndarray
    q_decision: np.ndarray
    qd_decision: np.ndarray
    effort: float
    impulsive_effort: float
    friction_needed: float
    peak_torque: float
    residual: float
    iterations: int
    minimized: bool = True

    @property
    def ballistic(self) -> float:
        """The ballistic part's duration T - d (s)."""
        return self.period - self.duration


class _Periodic:
    """The plan's equations and constraints as functions of z = (v0, theta, u^+, u^-)."""

    def __init__(self, hybrid: HybridStep, gait: Gait, duration: float) -> None:
        self.hybrid, self.gait, self.duration = hybrid, gait, duration
        bm = hybrid.bm
        self.n, self.na, self.actuated = bm.nq, len(bm.actuated), bm.actuated
        self.free = self.n + 1  # the unknowns before the torques: v0, theta
        self.flow = hybrid.flow(DEFAULTS.fine_steps)  # the planner's fine grid
        self.configurations = boundary_configurations(bm)
        self.friction = bm.params.friction if math.isinf(gait.problem.options.friction) else gait.problem.options.friction

    def torque(self, u: np.ndarray) -> np.ndarray:
        out = np.zeros(self.n)
        out[self.actuated] = u
        return out

    def split(self, z: np.ndarray) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
        n, na = self.n, self.na
        return z[:n], float(z[n]), z[n + 1: n + 1 + na], z[n + 1 + na:]

    def boundary(self, theta: float) -> tuple[np.ndarray, np.ndarray]:
        g = self.gait
        return self.configurations(g.step_length, g.arm_amplitude, g.mode, theta, g.problem.step_width)

    def scale(self, z: np.ndarray) -> np.ndarray:
        """The unknowns' units for Gauss-Newton: rad/s, rad, and the largest torque (N m)."""
        return np.concatenate([np.ones(self.n + 1), np.full(2 * self.na, max(1.0, float(np.max(np.abs(z[self.free:])))))])

    def stacked(self, z: np.ndarray) -> np.ndarray:
        """The residual and the constraints of ``evaluate``, one vector."""
        residual, constraints, _ = self.evaluate(z)
        return np.concatenate([residual, constraints])

    def evaluate(self, z: np.ndarray):
        """The residual (2 nq), the constraints (<= 0) and what the plan reports, at z."""
        v0, theta, u_plus, u_minus = self.split(z)
        q0, q_t = self.boundary(theta)
        half = self.duration / 2
        q, qd, forces_plus = pulse(self.hybrid, q0, v0, self.torque(u_plus), half)
        run = self.flow.propagate(q, qd, self.gait.period - self.duration)
        q_dec, qd_dec = run.q, run.qd
        q, qd, forces_minus = pulse(self.hybrid, q_dec, qd_dec, self.torque(u_minus), half)
        impact = self.hybrid.impact(q_t)
        landing = passive_impact(impact, qd)
        residual = np.concatenate([q - q_t, self.hybrid.exchange.velocity(q_t, landing.xd_plus) - v0])
        forces = np.vstack([forces_plus, forces_minus])
        arrival = float(impact.j2[2] @ self.hybrid.bm.embed(qd))  # the swing tip's vertical velocity at T
        constraints = np.concatenate([*(cone_rows(f * half, self.friction) for f in forces),  # N s, as impulses
                                      cone_rows(landing.reaction, self.friction), [-landing.old_foot_vz, arrival]])
        return residual, constraints, (q0, q_t, qd, q_dec, qd_dec, forces, landing)


def _jacobian(f, z: np.ndarray, base: np.ndarray) -> np.ndarray:
    columns = []
    for k in range(len(z)):
        dz = np.zeros(len(z))
        dz[k] = FD_STEP * max(1.0, abs(z[k]))
        columns.append((f(z + dz) - base) / dz[k])
    return np.array(columns).T


SLACK = 1e-6  # N s, m/s: how far Gauss-Newton's result may violate a constraint (second-order effects)
MARGIN = 1e-7  # N s, m/s: Gauss-Newton's steps meet the linearized constraints with this margin
VIOLATION_COST = 1e3  # per N s (m/s) of a linearized constraint violated, against the step's scaled l1 norm
GAUSS_NEWTON_STEPS = 30
HALVINGS = 12  # of a Gauss-Newton step at most, until the merit falls


def gauss_newton(evaluate, jacobian, z: np.ndarray, scale, tolerance: float,
                 fresh: bool = True) -> tuple[np.ndarray, int]:
    """z meeting the equations of ``evaluate`` (z -> residual, constraints <= 0, anything) to
    ``tolerance`` and its constraints to ``SLACK``, from ``z``, and the steps taken. Each step is
    the least (in the units ``scale(z)`` gives, one per unknown) that meets the linearized equations, moved
    in their null space by the least (l1) that meets the linearized constraints (with ``MARGIN``;
    their violations paid at ``VIOLATION_COST``: a linear program), halved until the merit
    sum |residual| + sum max(constraint - SLACK, 0) falls. ``jacobian(z, residual, constraints,
    fresh)``: d(residual, constraints) / dz, ``fresh`` asking for all of it anew (else it may reuse
    what does not change much); asked fresh again when a step cannot lower the merit.
    ``FiniteSupportFailed`` if no step can, or after ``GAUSS_NEWTON_STEPS``."""
    residual, constraints, _ = evaluate(z)

    def merit(r: np.ndarray, c: np.ndarray) -> float:
        return float(np.abs(r).sum() + np.maximum(c - SLACK, 0.0).sum()) if np.all(np.isfinite(r)) else math.inf

    jac, steps = None, 0
    while True:
        if np.max(np.abs(residual)) < tolerance and np.max(constraints) <= SLACK:
            return z, steps
        if steps == GAUSS_NEWTON_STEPS:
            break
        if jac is None:
            with np.errstate(all="ignore"):
                jac = jacobian(z, residual, constraints, fresh)
            if not np.all(np.isfinite(jac)):
                raise FiniteSupportFailed(f"Gauss-Newton's Jacobian is not finite at residual "
                                          f"{np.max(np.abs(residual)):.2e}")
        units = scale(z)
        scaled = jac * units
        j_eq, j_in = scaled[:len(residual)], scaled[len(residual):]
        y = np.linalg.lstsq(j_eq, -residual, rcond=None)[0]
        free = null_space(j_eq)
        y = y + free @ _least_move(j_in @ free, -constraints - j_in @ y - MARGIN)
        step, now = units * y, merit(residual, constraints)
        for _ in range(HALVINGS):
            with np.errstate(all="ignore"):
                trial = evaluate(z + step)
            if merit(trial[0], trial[1]) < now:
                break
            step = step / 2
        else:
            if fresh:
                break
            jac, fresh = None, True
            continue
        z, (residual, constraints, _) = z + step, trial
        steps, fresh, jac = steps + 1, False, None
    raise FiniteSupportFailed(f"Gauss-Newton stalls at residual {np.max(np.abs(residual)):.2e}, "
                              f"constraint {np.max(constraints):.2e}")


def _least_move(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The w of least l1 norm with a w <= b, its violations paid at ``VIOLATION_COST`` (HiGHS;
    w = 0 when it meets them)."""
    m, k = a.shape
    if np.all(b >= 0.0):
        return np.zeros(k)
    cost = np.concatenate([np.ones(2 * k), np.full(m, VIOLATION_COST)])
    lp = linprog(cost, A_ub=np.hstack([a, -a, -np.eye(m)]), b_ub=b, bounds=(0, None), method="highs")
    if lp.status != 0:
        raise FiniteSupportFailed(f"the linearized constraints have no least move ({lp.message})")
    return lp.x[:k] - lp.x[k:2 * k]


FIRST_DURATION = 2.5e-4  # s: the continuation in d starts here, from the impulsive gait
LINE_SEARCH = 8  # shrinkings of the trust region per linear program at most
PENALTY = 1e4  # N m s per unit of residual (rad, rad/s) or of a violated constraint (N, N s, m/s)
RADIUS = 0.5  # the trust region's largest radius: rad/s, rad, and fractions of the largest torque
DESCENT_STEPS = 12  # of the effort's descent at most, at the duration asked
PASSING_DESCENT = 4  # at the continuation's durations on the way (keeping to the low-effort branch)
DESCENT_GAIN = 1e-4  # relative: the descent stops when a step lowers E by less


def plan_finite_support(hybrid: HybridStep, gait: Gait, duration: float,
                        descent_steps: int = DESCENT_STEPS) -> FiniteSupport:
    """The periodic gait of ``gait`` (an impulsive plan, admissible) with a double support of
    ``duration`` s (module docstring), by continuation in d from ``FIRST_DURATION`` (doubling; the
    torques scaled to keep their integrals): the least effort by sequential linear programs while
    they converge; from the first duration where they stall, the periodic phase by Gauss-Newton
    (``_restore``) and its effort lowered along the periodic phases (``_descend``, at most
    ``descent_steps`` at ``duration``, ``PASSING_DESCENT`` on the way; ``FiniteSupport.minimized``
    false). ``FiniteSupportFailed`` if Gauss-Newton cannot meet the equations."""
    if not duration > 0 or not duration < gait.period:
        raise ValueError(f"the double support's duration must be in (0, T = {gait.period:g}) s, got {duration:g} s")
    bm = hybrid.bm
    n = bm.nq
    first = min(duration, FIRST_DURATION)
    impulses = gait.double_support.impulses
    v0 = hybrid.exchange.velocity(gait.step.q_target, impulses.xd_plus)
    # I^+ acts on this step's coordinates, u^+ on the next step's: the exchange's joint map (a
    # signed permutation of the actuated joints, its own inverse transpose) carries it over.
    joints = exchange_matrix(bm.coordinates)[np.ix_(bm.actuated, bm.actuated)]
    z = np.concatenate([v0, [gait.step.theta], 2 * joints @ impulses.i_plus / first, 2 * impulses.i_minus / first])
    stages = [first]
    while stages[-1] < duration:
        stages.append(min(duration, 2 * stages[-1]))
    minimized = True  # while the sequential LPs converge; after that, Gauss-Newton and the descent
    for k, stage in enumerate(stages):
        if k:
            z[n + 1:] *= stages[k - 1] / stage
        eq = _Periodic(hybrid, gait, stage)
        if minimized:
            try:
                z, iterations = _sequential_lp(eq, z)
                continue
            except FiniteSupportFailed:
                minimized = False
        z, iterations = _descend(eq, _restore(eq, z), descent_steps if stage == duration else PASSING_DESCENT)
    return _finish(_Periodic(hybrid, gait, duration), z, iterations, minimized)




def _restore(eq: _Periodic, z: np.ndarray) -> np.ndarray:
    """The periodic phase nearest ``z`` (``gauss_newton``, its Jacobian by differences)."""
    def jacobian(x: np.ndarray, residual: np.ndarray, constraints: np.ndarray, fresh: bool) -> np.ndarray:
        return _jacobian(eq.stacked, x, np.concatenate([residual, constraints]))

    return gauss_newton(eq.evaluate, jacobian, z, eq.scale, TOLERANCE)[0]


def _descend(eq: _Periodic, z: np.ndarray, most: int) -> tuple[np.ndarray, int]:
    """From the periodic phase ``z``, lower its effort E along the periodic phases: each step goes
    down E's gradient projected on the null space of the equations' Jacobian (scaled), by a
    length that grows by half after a success and halves after a failure, and ``_restore`` brings
    it back onto the equations (and the constraints); kept if E fell. Until a step gains less than
    ``DESCENT_GAIN``, or ``most`` steps: towards a local minimum of E over the periodic phases. The
    descent's steps taken, beside z."""
    half, free = eq.duration / 2, eq.free

    def effort(x: np.ndarray) -> float:
        return float(half * np.abs(x[free:]).sum())

    length, steps = 0.05, 0
    for steps in range(1, most + 1):
        residual, constraints, _ = eq.evaluate(z)
        scale = eq.scale(z)
        jac = _jacobian(eq.stacked, z, np.concatenate([residual, constraints]))[:len(residual)] * scale
        gradient = np.zeros(len(z))
        gradient[free:] = half * np.sign(z[free:]) * scale[free:]
        basis = null_space(jac)
        direction = -basis @ (basis.T @ gradient)
        direction /= max(np.max(np.abs(direction)), 1e-300)
        now = effort(z)
        while length > 1e-4:
            try:
                trial = _restore(eq, z + length * scale * direction)
            except FiniteSupportFailed:
                trial = None
            if trial is not None and effort(trial) < now:
                z, length = trial, 1.5 * length
                break
            length /= 2
        else:
            break
        if now - effort(z) < DESCENT_GAIN * now:
            break
    return z, steps


def _merit(eq: _Periodic, z: np.ndarray, residual: np.ndarray, constraints: np.ndarray) -> float:
    """The l1 merit of z: its effort plus ``PENALTY`` times the residual's and the violations' sums."""
    torques = z[eq.free:]
    return float(eq.duration / 2 * np.abs(torques).sum()
                 + PENALTY * (np.abs(residual).sum() + np.maximum(constraints, 0.0).sum()))


def _sequential_lp(eq, z: np.ndarray, tolerance: float = TOLERANCE) -> tuple[np.ndarray, int]:
    """z solving ``eq`` (its equations to ``tolerance``, constraints met) from ``z``: linear
    programs in the step of z with elastic constraints (violations paid at ``PENALTY``), within a
    trust region that shrinks until the step lowers the l1 merit. ``eq``: a ``_Periodic``, or
    anything with its ``free`` (the unknowns before the 2 ``na`` torques, which end z),
    ``duration`` and ``evaluate`` (residual, constraints <= 0, anything)."""
    na, half, duration = eq.na, eq.duration / 2, eq.duration
    torques = slice(eq.free, eq.free + 2 * na)
    residual, constraints, _ = eq.evaluate(z)
    radius = RADIUS
    for iteration in range(1, SLP_ITERATIONS + 1):
        if np.max(np.abs(residual)) < tolerance and np.max(constraints) <= 1e-9:
            return z, iteration

        def stacked(x: np.ndarray) -> np.ndarray:
            r, c, _ = eq.evaluate(x)
            return np.concatenate([r, c])

        jac = _jacobian(stacked, z, np.concatenate([residual, constraints]))
        e = len(residual)
        j_eq, j_in = jac[:e], jac[e:]
        size, m = len(z), len(constraints)
        # variables: dz, t >= |u + du| (2 na), s >= 0 (the inequalities' slack), s+, s- >= 0 (the equations')
        width = size + 2 * na + m + 2 * e
        cost = np.concatenate([np.zeros(size), np.full(2 * na, half), np.full(m + 2 * e, PENALTY)])
        a_in = np.zeros((m, width))
        a_in[:, :size], a_in[:, size + 2 * na: size + 2 * na + m] = j_in, -np.eye(m)
        rows, rhs = [a_in], [-constraints]
        for sign in (1.0, -1.0):
            block = np.zeros((2 * na, width))
            block[:, torques] = sign * np.eye(2 * na)
            block[:, size: size + 2 * na] = -np.eye(2 * na)
            rows.append(block)
            rhs.append(-sign * z[torques])
        a_eq = np.zeros((e, width))
        a_eq[:, :size], a_eq[:, width - 2 * e: width - e], a_eq[:, width - e:] = j_eq, -np.eye(e), np.eye(e)
        scale = np.concatenate([np.ones(eq.free), np.full(2 * na, max(1.0, float(np.max(np.abs(z[torques])))))])
        merit = _merit(eq, z, residual, constraints)
        for _ in range(LINE_SEARCH):
            bounds = [(-radius * w, radius * w) for w in scale] + [(0, None)] * (width - size)
            lp = linprog(cost, A_ub=np.vstack(rows), b_ub=np.concatenate(rhs), A_eq=a_eq, b_eq=-residual,
                         bounds=bounds, method="highs")
            if lp.status == 0:
                with np.errstate(all="ignore"):
                    trial = eq.evaluate(z + lp.x[:size])
                if np.all(np.isfinite(trial[0])) and _merit(eq, z + lp.x[:size], trial[0], trial[1]) < merit:
                    radius = min(2 * radius, RADIUS)
                    break
            radius /= 4
        else:
            raise FiniteSupportFailed(f"the finite double support of {duration * 1e3:g} ms has no plan: "
                                      f"no step of the linear programs lowers the merit ({lp.message})")
        z, (residual, constraints, _) = z + lp.x[:size], trial
    raise FiniteSupportFailed(f"the finite double support of {duration * 1e3:g} ms did not converge in "
                              f"{SLP_ITERATIONS} linear programs")


def _finish(eq: _Periodic, z: np.ndarray, iterations: int, minimized: bool) -> FiniteSupport:
    residual, constraints, (q0, q_t, qd_t, q_dec, qd_dec, forces, landing) = eq.evaluate(z)
    v0, theta, u_plus, u_minus = eq.split(z)
    gait, duration, half = eq.gait, eq.duration, eq.duration / 2
    return FiniteSupport(
        duration=duration, period=gait.period, q0=q0, v0=v0, q_t=q_t, qd_t=qd_t, theta=theta, u_plus=u_plus,
        u_minus=u_minus, q_decision=q_dec, qd_decision=qd_dec,
        effort=float(half * (np.abs(u_plus).sum() + np.abs(u_minus).sum())), impulsive_effort=gait.W,
        friction_needed=max(friction_ratio(forces), friction_ratio(landing.reaction[None, :])),
        peak_torque=float(np.max(np.abs(np.concatenate([u_plus, u_minus])))),
        residual=float(np.max(np.abs(residual))), iterations=iterations, minimized=minimized,
    )
