"""The walking biped as a hybrid system, in one place (docs/model.md section 8).

One step of the hybrid system has three parts, each documented with its inputs, state and
outputs (in the spirit of Drake's compass-gait example):

- **Flow** (``HybridStep.flow``, a ``flow.BallisticFlow``): the ballistic single support,
  D(q) qdd + C(q, qd) + G(q) = 0. State x = (q, qd) of the 9-DOF single-support model (rad,
  rad/s), stance leg 1 on the right with its tip at the origin; no input (no joint torque).
  Output: the state after a duration, optionally its sensitivities.
- **Guard** (``TouchdownGuard``): the witness function w(q) = height (m) of the swing-foot tip.
  The step ends where w crosses zero downward, or where it touches zero at a minimum (a grazing
  contact), once the guard is armed (half the planned step duration, so that the toe-off scuff
  at t = 0 does not count).
- **Reset** (``ImpactMap`` then ``exchange``): the instantaneous double support at the
  touchdown configuration q_T, eqs. (6)-(10): impulsive joint torques I^-, a passive impact,
  impulsive joint torques I^+. Input: the pre-impact velocity qd_b and the next step's
  initial velocity qd_a, which the impulses must reach; it is reachable only if the angular
  momentum about the foot-to-foot line is conserved (the closure, docs/model.md section 4),
  which ``closure_gap`` measures and ``closure_gradients`` linearizes. Then the leg exchange
  P (docs/model.md section 5) carries the state into the next step's coordinates (the mirror
  image: the stance leg is always the model's leg 1).

The shooting BVP (``bvp``), the walker (``walk``) and the analyses built on them all go
through this module.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.biped import BipedModel
from ..model.exchange import KinematicExchange, LinearExchange, leg_exchange
from .flow import BallisticFlow, hermite_samples
from .impulses import ImpactLayout, ImpactProblem
from .samples import SampleEvaluator

GRAZING_HEIGHT = 1e-8
"""Largest height (m) of a swing-tip minimum that counts as a touchdown: a tangential (grazing)
contact, where the tip meets the ground with zero vertical speed, comes out of the integration a
rounding error above or below the ground. The walker lands within 1e-9 (rad, rad/s) of the plan
(docs/model.md section 8.5), which puts the tip within about 1e-9 m (a lever arm under 2 m) of
where the plan puts it: 1e-8 m covers that tenfold, and stays far below any clearance the planner
reports (millimetres; section 6)."""


class TouchdownGuard:
    """The touchdown witness w(q) = swing-tip height (m) and its guard, armed for the integration
    steps that end later than ``armed_after`` s into the step (so that the toe-off scuff at t = 0,
    where w = 0, does not count). Over one integration step the guard fires

    - where w crosses zero downward: w <= 0 at the end of the step, or at an interior minimum of w
      (the tip dips under the ground and comes back up within the step: a touchdown that the end
      of the step misses, e.g. when the previous step ended on the ground to rounding);
    - at an interior minimum of w no higher than ``GRAZING_HEIGHT`` (a grazing contact).

    Both are found on the quintic Hermite interpolant of the step's nodes (t, q, qd, qdd): w's
    rate, the tip's vertical velocity, is exactly the derivative of w along it.
    """

    def __init__(self, samples: SampleEvaluator, armed_after: float) -> None:
        self.samples = samples
        self.armed_after = armed_after

    def motion(self, nodes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], t: float) -> tuple[float, float]:
        """w (m) and its rate (m/s) at time ``t`` (s in the step) on the interpolant of ``nodes``."""
        q, qd = hermite_samples(nodes, np.array([t]))
        height, rate = self.samples.swing_tip_motion(q, qd)
        return float(height[0]), float(rate[0])

    def touchdown(self, nodes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> float | None:
        """Time (s in the step, to 1e-14 s) of the touchdown within the integration step of
        ``nodes`` (t, q, qd, qdd at its start and end), or None if the guard does not fire in it."""
        t, q, qd = nodes[0], nodes[1], nodes[2]
        if not t[-1] > self.armed_after:
            return None
        (h_start, h_end), (rate_start, rate_end) = self.samples.swing_tip_motion(q[[0, -1]], qd[[0, -1]])
        if h_end <= 0.0:
            return self._crossing(nodes, h_start, t[-1])
        if not rate_start < 0.0 <= rate_end:  # no minimum of w inside the step
            return None
        t_min = _root(lambda s: self.motion(nodes, s)[1], t[0], t[-1])
        h_min = self.motion(nodes, t_min)[0]
        if h_min <= 0.0:
            return self._crossing(nodes, h_start, t_min)
        return t_min if h_min <= GRAZING_HEIGHT else None

    def _crossing(self, nodes: tuple[np.ndarray, ...], h_start: float, t_below: float) -> float:
        """Where w crosses zero downward between the step's start (height ``h_start``) and
        ``t_below`` (s), where w <= 0."""
        if h_start <= 0.0:  # already touching at the start of this integration step
            return float(nodes[0][0])
        return _root(lambda s: self.motion(nodes, s)[0], nodes[0][0], t_below)


def _root(f, a: float, b: float) -> float:
    """The root of ``f`` between ``a`` and ``b`` (s) to 1e-14, by SciPy's Brent method, imported
    here: the walker needs it (``walk`` loads it with itself), a plan never does, and importing
    ``scipy.optimize`` takes a plan process's time (tenths of a second)."""
    from scipy.optimize import brentq

    return brentq(f, a, b, xtol=1e-14, rtol=1e-14)


def locked_rotation(bm: BipedModel, q_t: np.ndarray) -> np.ndarray:
    """z_d (nX,): unit-rate rigid rotation of the locked biped about the foot-to-foot line.

    Only the stance ankle's rates are non-zero (roll and pitch, and spin if the model has it);
    the rotation axis points from the old stance tip (origin) to the new one. Requires q1 = 0 for
    legs of pitch joints only, as every double-support configuration of theirs has.
    """
    tip = bm.swing_tip(q_t)
    axis = tip / np.linalg.norm(tip)
    z = np.zeros(bm.double_support.nv)
    if bm.spin:
        z[3:6] = np.linalg.solve(_ankle_axes(q_t), axis)
    else:
        z[3], z[4] = axis[0], axis[1]
    return z


def _ankle_axes(q: np.ndarray) -> np.ndarray:
    """The stance shin's angular velocity (columns, world axes) per unit rate of its ankle's roll,
    pitch and spin at ``q``."""
    cr, sr, cp, sp = np.cos(q[0]), np.sin(q[0]), np.cos(q[1]), np.sin(q[1])
    return np.array([[1.0, 0.0, sp], [0.0, cr, -sr * cp], [0.0, sr, cr * cp]])


class ImpactMap:
    """The double support at the touchdown configuration ``q_t`` (rad): D_e, the contact
    Jacobians J1, J2 and the locked rotation z_d there (the double-support model's coordinates X,
    this step's frame), and the maps that connect this step's end to the next step's start.

    J1 and J2 are the old and new stance tips' positions (3 rows each, m per unit of X); with
    lateral hip joints each has a fourth row, the foot's spin about its shin (rad/s), which the
    ground holds while the foot is down (docs/model.md section 5.2)."""

    def __init__(self, bm: BipedModel, exchange: LinearExchange | KinematicExchange, q_t: np.ndarray) -> None:
        self.bm, self.exchange, self.q_t = bm, exchange, q_t
        self.mass_matrix = bm.mass_matrix(q_t)
        self.j1, self.j2 = contact_jacobians(bm, exchange, q_t)
        self.locked_rotation = locked_rotation(bm, q_t)
        self.layout = ImpactLayout.of(bm)

    @property
    def momentum_row(self) -> np.ndarray:
        """z_d^T D_e (nX,): Xd -> angular momentum about the foot-to-foot line (kg m^2/s)."""
        return self.locked_rotation @ self.mass_matrix

    def next_step_velocity(self, qd_a: np.ndarray) -> np.ndarray:
        """Xd^a: the next step's initial joint velocity ``qd_a`` (its own coordinates, rad/s)
        in this step's double-support coordinates, the new stance tip at rest (docs/model.md
        section 5)."""
        return self.exchange.next_velocity(self.q_t, self.j2, qd_a)

    def problem(self, qd_b: np.ndarray, qd_a: np.ndarray) -> ImpactProblem:
        """Eqs. (6)-(10): this step ends with joint velocity ``qd_b``, the next starts with
        ``qd_a`` (in its own coordinates)."""
        return ImpactProblem(self.mass_matrix, self.j1, self.j2, self.bm.embed(qd_b), self.next_step_velocity(qd_a),
                             self.locked_rotation, self.layout)

    def closure_gap(self, qd_a: np.ndarray, qd_b: np.ndarray) -> float:
        """z_d^T D_e (Xd^a - Xd^b) (kg m^2/s): zero when the double support can close the cycle."""
        xd_b = self.bm.embed(qd_b)
        return float(self.locked_rotation @ self.mass_matrix @ (self.next_step_velocity(qd_a) - xd_b))

    def forward(self, qd_b: np.ndarray, i_minus: np.ndarray, i_plus: np.ndarray) -> np.ndarray:
        """The next step's initial joint velocity (its own coordinates, rad/s) when this step
        ends with ``qd_b`` and the double support applies the joint impulses ``i_minus`` and
        ``i_plus`` (N m s, the actuated joints) around the passive impact: eqs. (6)-(10) run
        forward as three impacts, the old stance tip keeping its velocity through I^-, the new
        one at rest after the impact and after I^+; then the leg exchange. ``qd_b`` may also be
        nq x k (k velocities, one per column: k results, as columns)."""
        bm = self.bm
        if qd_b.ndim == 1:
            xd_b = bm.embed(qd_b)
        else:
            xd_b = np.zeros((bm.double_support.nv, qd_b.shape[1]))
            xd_b[bm.ds_of_single] = qd_b
        xd_a = double_support(self.mass_matrix, self.j1, self.j2, xd_b, i_minus, i_plus, self.layout)
        return self.exchange.velocity(self.q_t, xd_a)

    def reset_jacobian(self, qd_b: np.ndarray, i_minus: np.ndarray, i_plus: np.ndarray) -> np.ndarray:
        """d (q', qd') / d (q, qd) (2 nq x 2 nq) of the reset (``forward`` and the exchange's
        ``configuration``) at this configuration and the pre-impact velocity ``qd_b``, the impulses
        held fixed: the velocity part exactly (the reset is linear in it), the configuration part
        differentiated analytically through the three impacts' linear systems (``impact_sensitivity``)
        with D_e's, J1's, J2's and the exchange's derivatives (``BipedModel.derivatives``,
        ``derivatives`` of the exchange)."""
        bm, n = self.bm, self.bm.nq
        d_mass, d_j1, d_j2 = bm.derivatives(self.q_t)
        configuration, d_velocity, d_spin = self.exchange.derivatives(self.q_t)
        if bm.spin:
            d_j1 = np.concatenate([d_j1, np.zeros((n, 1, d_j1.shape[2]))], axis=1)
            d_j2 = np.concatenate([d_j2, d_spin[:, None]], axis=1)
        rows, zero = self.layout.joints, np.zeros(self.layout.na)
        xd, d_xd = bm.embed(qd_b), np.zeros((bm.double_support.nv, n))
        for contact, d_contact, impulse, at_rest in ((self.j1, d_j1, i_minus, False), (self.j2, d_j2, zero, True),
                                                     (self.j2, d_j2, i_plus, True)):
            xd, d_xd = impact_sensitivity((self.mass_matrix, d_mass), (contact, d_contact), (xd, d_xd), impulse, rows,
                                          at_rest)
        out = np.zeros((2 * n, 2 * n))
        out[:n, :n] = configuration
        out[n:, :n] = self.exchange.velocity(self.q_t, d_xd) + np.einsum("kij,j->ik", d_velocity, xd)
        out[n:, n:] = self.forward(np.eye(n), zero, zero)
        return out

    def closure_gradients(self) -> tuple[np.ndarray, np.ndarray]:
        """d gap / d qd_a (in the next step's coordinates) and d gap / d qd_b, at this
        configuration (the gap is linear in both)."""
        row = self.momentum_row
        d_a = self.exchange.next_velocity_gain(self.q_t, self.j2, row)
        return d_a, -row[self.bm.ds_of_single]


def contact_jacobians(bm: BipedModel, exchange: LinearExchange | KinematicExchange,
                      q_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """J1, J2 at the touchdown configuration ``q_t`` (rad): the old and new stance tips' positions
    (3 rows each, m per unit of X), each with a fourth row with lateral hip joints, the foot's
    spin about its shin (rad/s; ``ImpactMap``)."""
    j1, j2 = bm.tip_jacobians(q_t)
    if bm.spin:
        spin = np.zeros(bm.double_support.nv)
        spin[5] = 1.0
        j1, j2 = np.vstack([j1, spin]), np.vstack([j2, exchange.spin_row(q_t)])
    return j1, j2


def double_support(mass_matrix: np.ndarray, j1: np.ndarray, j2: np.ndarray, xd_b: np.ndarray, i_minus: np.ndarray,
                   i_plus: np.ndarray, layout: ImpactLayout) -> np.ndarray:
    """Xd^a (double-support coordinates) after eqs. (6)-(10) run forward from ``xd_b`` as three
    impacts (``ImpactMap.forward``): I^- (N m s) with the old stance tip (``j1``) keeping its
    velocity, the passive impact and I^+ with the new one (``j2``) at rest. The arguments are
    ``impact_with``'s."""
    rows = layout.joints
    xd_minus = impact_with(mass_matrix, j1, xd_b, i_minus, rows, at_rest=False)
    xd_plus = impact_with(mass_matrix, j2, xd_minus, np.zeros(layout.na), rows, at_rest=True)
    return impact_with(mass_matrix, j2, xd_plus, i_plus, rows, at_rest=True)


def impact_with(mass_matrix: np.ndarray, contact: np.ndarray, xd: np.ndarray, joint_impulse: np.ndarray,
                rows: np.ndarray | slice, at_rest: bool) -> np.ndarray:
    """The double-support velocity after one impulsive sub-phase: D_e (Xd' - Xd) = B_e I + J^T I_R
    with the contact of ``contact`` (J, c x nX) at rest after it (``at_rest``) or keeping its
    velocity (J Xd' = J Xd); ``joint_impulse`` I on the actuated coordinates, rows ``rows`` of X
    (N m s). ``xd`` may be nX x k (k velocities as columns, the same impulse added to each)."""
    kkt, rhs = _impact_system(mass_matrix, contact, xd, joint_impulse, rows, at_rest)
    return np.linalg.solve(kkt, rhs)[: mass_matrix.shape[0]]


def _impact_system(mass_matrix: np.ndarray, contact: np.ndarray, xd: np.ndarray, joint_impulse: np.ndarray,
                   rows: np.ndarray | slice, at_rest: bool) -> tuple[np.ndarray, np.ndarray]:
    """``impact_with``'s linear system [D_e, -J^T; J, 0] [Xd'; I_R] = [D_e Xd + B_e I; J Xd or 0]."""
    n, c = mass_matrix.shape[0], contact.shape[0]
    kkt = np.zeros((n + c, n + c))
    kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = mass_matrix, -contact.T, contact
    held = np.zeros((c,) + xd.shape[1:]) if at_rest else contact @ xd
    rhs = np.concatenate([mass_matrix @ xd, held])
    rhs[rows] += joint_impulse if xd.ndim == 1 else joint_impulse[:, None]
    return kkt, rhs


def impact_sensitivity(mass: tuple[np.ndarray, np.ndarray], contacts: tuple[np.ndarray, np.ndarray],
                       velocity: tuple[np.ndarray, np.ndarray], joint_impulse: np.ndarray, rows: np.ndarray | slice,
                       at_rest: bool) -> tuple[np.ndarray, np.ndarray]:
    """``impact_with`` for one double support and the derivative of its result along k parameters,
    each given as (value, derivative): ``mass`` D_e and its derivative (k x nX x nX), ``contacts`` J
    and its (k x c x nX), ``velocity`` Xd (nX,) and its (nX x k); the joint impulse held. Differentiating the system
    [D_e, -J^T; J, 0] [Xd'; I_R] = [D_e Xd + B_e I; J Xd or 0] gives the same matrix on the right-hand
    side D_e' (Xd - Xd') + J'^T I_R + D_e dXd over J' (Xd - Xd') + J dXd (the contact keeping its
    velocity) or -J' Xd' (at rest). Returns Xd' (nX,) and its derivative (nX x k)."""
    (mass_matrix, d_mass), (contact, d_contact), (xd, d_xd) = mass, contacts, velocity
    n = mass_matrix.shape[0]
    kkt, rhs = _impact_system(mass_matrix, contact, xd, joint_impulse, rows, at_rest)
    solved = np.linalg.solve(kkt, rhs)
    after, reaction = solved[:n], solved[n:]
    top = np.einsum("kij,j->ik", d_mass, xd - after) + np.einsum("kci,c->ik", d_contact, reaction) + mass_matrix @ d_xd
    if at_rest:
        bottom = -np.einsum("kcj,j->ck", d_contact, after)
    else:
        bottom = np.einsum("kcj,j->ck", d_contact, xd - after) + contact @ d_xd
    return after, np.linalg.solve(kkt, np.vstack([top, bottom]))[:n]


@dataclass(frozen=True, eq=False)
class PassiveImpact:
    """The passive impact at a touchdown configuration (eqs. 8-9): the velocity after it (X
    coordinates), the reaction impulse at the new stance foot (N s, world axes of the step) and the
    old stance foot's vertical velocity after it (m/s, >= 0: it leaves the ground)."""

    xd_plus: np.ndarray
    reaction: np.ndarray
    old_foot_vz: float


def passive_impact(impact: ImpactMap, qd: np.ndarray) -> PassiveImpact:
    """Eqs. (8)-(9) at ``impact``'s configuration from the single-support velocity ``qd``."""
    bm = impact.bm
    xd_b = bm.embed(qd)
    rows = impact.layout.joints
    xd_plus = impact_with(impact.mass_matrix, impact.j2, xd_b, np.zeros(impact.layout.na), rows, at_rest=True)
    reaction = np.linalg.lstsq(impact.j2.T, impact.mass_matrix @ (xd_plus - xd_b), rcond=None)[0]
    return PassiveImpact(xd_plus, reaction[:3], float(impact.j1[2] @ xd_plus))


class HybridStep:
    """The hybrid step of one biped: its flows (one per RK8 grid), guard, reset maps, and the
    evaluation of its samples (``samples``)."""

    def __init__(self, bm: BipedModel) -> None:
        self.bm = bm
        self.samples = SampleEvaluator(bm)
        self.exchange = leg_exchange(bm)
        self._flows: dict[int, BallisticFlow] = {}

    def flow(self, steps: int) -> BallisticFlow:
        """The ballistic flow on a grid of ``steps`` RK8 steps per call (built once per grid)."""
        if steps not in self._flows:
            self._flows[steps] = BallisticFlow(self.bm.single, steps)
        return self._flows[steps]

    def guard(self, armed_after: float) -> TouchdownGuard:
        """The touchdown guard, armed ``armed_after`` s into the step."""
        return TouchdownGuard(self.samples, armed_after)

    def impact(self, q_t: np.ndarray) -> ImpactMap:
        """The reset's double support at touchdown configuration ``q_t``."""
        return ImpactMap(self.bm, self.exchange, q_t)
