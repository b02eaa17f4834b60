"""The walking biped as a hybrid system, in one place (docs/model.md section 8).

One step of the hybrid system has three parts, each documented with its inputs, state and
outputs (in the spirit of Drake's compass-gait example):

- **Flow** (``HybridStep.flow``, a ``flow.BallisticFlow``): the ballistic single support,
  D(q) qdd + C(q, qd) + G(q) = 0. State x = (q, qd) of the 9-DOF single-support model (rad,
  rad/s), stance leg 1 on the right with its tip at the origin; no input (no joint torque).
  Output: the state after a duration, optionally its sensitivities.
- **Guard** (``TouchdownGuard``): the witness function w(q) = height (m) of the swing-foot tip.
  The step ends where w crosses zero downward, once the guard is armed (half the planned step
  duration, so that the toe-off scuff at t = 0 does not count).
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

import numpy as np
from scipy.optimize import brentq

from .flow import BallisticFlow, hermite_samples
from .impulses import ImpactProblem
from .model import BipedModel

# The configuration map at double support, q' = P q (docs/model.md section 5): rows q1'..q9'.
P_MATRIX = np.zeros((9, 9))
for _row, _entries in enumerate(
    [{0: -1}, {1: 1, 2: 1, 3: 1, 7: 1, 8: 1}, {8: -1}, {7: -1}, {4: -1}, {6: 1}, {5: 1}, {3: -1}, {2: -1}]
):
    for _col, _val in _entries.items():
        P_MATRIX[_row, _col] = _val
P_INVERSE = np.linalg.inv(P_MATRIX)

MIRROR = np.diag([1.0, -1.0, 1.0])  # y -> -y: the next step is the mirror image of this one


def exchange(q: np.ndarray) -> np.ndarray:
    """The leg exchange P: a configuration or joint velocity at double support (this step's
    coordinates) in the next step's coordinates."""
    return P_MATRIX @ q


def mirror_for(stance_side: str) -> np.ndarray:
    """The map from a step's model frame (stance leg 1) to world axes: identity with the right
    foot in stance, the mirror y -> -y with the left."""
    if stance_side not in ("right", "left"):
        raise ValueError(f"stance side must be 'right' or 'left', got {stance_side!r}")
    return np.eye(3) if stance_side == "right" else MIRROR


def other_side(stance_side: str) -> str:
    """The stance side of the next step."""
    return "left" if stance_side == "right" else "right"


class TouchdownGuard:
    """The touchdown witness w(q) = swing-tip height (m), armed after ``armed_after`` s of the step."""

    def __init__(self, bm: BipedModel, armed_after: float) -> None:
        self.bm = bm
        self.armed_after = armed_after

    def height(self, q: np.ndarray) -> float:
        """w(q): height (m) of the swing-foot tip."""
        return float(self.bm.swing_tip(q)[2])

    def crossed(self, t_end: float, q_end: np.ndarray) -> bool:
        """Whether the guard fired by the end ``t_end`` (s in the step) of an integration step
        that ends at configuration ``q_end``."""
        return t_end > self.armed_after and self.height(q_end) <= 0.0

    def locate(self, nodes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> float:
        """Time (s in the step) where w crosses zero within one integration step, found on the
        quintic Hermite interpolant of its ``nodes`` (t, q, qd, qdd) to 1e-14 s."""
        t0, t1 = nodes[0][0], nodes[0][-1]

        def height(t: float) -> float:
            q, _ = hermite_samples(nodes, np.array([t]))
            return self.height(q[0])

        if height(t0) <= 0.0:  # already touching at the start of this integration step
            return t0
        return brentq(height, t0, t1, xtol=1e-14, rtol=1e-14)


def locked_rotation(bm: BipedModel, q_t: np.ndarray) -> np.ndarray:
    """z_d (12,): unit-rate rigid rotation of the locked biped about the foot-to-foot line.

    Only q1d and q2d are non-zero; the rotation axis points from the old stance tip (origin)
    to the new one. Requires q1 = 0, as every double-support configuration has.
    """
    tip = bm.swing_tip(q_t)
    axis = tip / np.linalg.norm(tip)
    z = np.zeros(12)
    z[3], z[4] = axis[0], axis[1]
    return z


class ImpactMap:
    """The double support at the touchdown configuration ``q_t`` (rad): D_e, J1, J2 and the
    locked rotation z_d there (extended coordinates X = [x0, y0, z0, q1..q9], this step's
    frame), and the maps that connect this step's end to the next step's start."""

    def __init__(self, bm: BipedModel, q_t: np.ndarray) -> None:
        self.q_t = q_t
        self.mass_matrix = bm.mass_matrix(q_t)
        self.j1, self.j2 = bm.tip_jacobians(q_t)
        self.locked_rotation = locked_rotation(bm, q_t)

    @property
    def momentum_row(self) -> np.ndarray:
        """z_d^T D_e (12,): Xd -> angular momentum about the foot-to-foot line (kg m^2/s)."""
        return self.locked_rotation @ self.mass_matrix

    def next_step_velocity(self, qd_a: np.ndarray) -> np.ndarray:
        """Xd^a: the next step's initial joint velocity ``qd_a`` (its own coordinates, rad/s)
        in this step's extended coordinates, the new stance tip at rest (docs/model.md section 5)."""
        qd = P_INVERSE @ qd_a
        return np.concatenate([-self.j2[:, 3:] @ qd, qd])

    def problem(self, qd_b: np.ndarray, qd_a: np.ndarray) -> ImpactProblem:
        """Eqs. (6)-(10): this step ends with joint velocity ``qd_b``, the next starts with
        ``qd_a`` (in its own coordinates)."""
        xd_b = np.concatenate([np.zeros(3), qd_b])
        return ImpactProblem(self.mass_matrix, self.j1, self.j2, xd_b, self.next_step_velocity(qd_a),
                             self.locked_rotation)

    def closure_gap(self, qd_a: np.ndarray, qd_b: np.ndarray) -> float:
        """z_d^T D_e (Xd^a - Xd^b) (kg m^2/s): zero when the double support can close the cycle."""
        xd_b = np.concatenate([np.zeros(3), qd_b])
        return float(self.locked_rotation @ self.mass_matrix @ (self.next_step_velocity(qd_a) - xd_b))

    def forward(self, qd_b: np.ndarray, i_minus: np.ndarray, i_plus: np.ndarray) -> np.ndarray:
        """The next step's initial joint velocity (its own coordinates, rad/s) when this step
        ends with ``qd_b`` and the double support applies the joint impulses ``i_minus`` and
        ``i_plus`` (N m s, q3..q9) around the passive impact: eqs. (6)-(10) run forward as three
        impacts, the old stance tip keeping its velocity through I^-, the new one at rest after
        the impact and after I^+; then the leg exchange."""
        xd_b = np.concatenate([np.zeros(3), qd_b])
        xd_minus = impact_with(self.mass_matrix, self.j1, xd_b, i_minus, at_rest=False)
        xd_plus = impact_with(self.mass_matrix, self.j2, xd_minus, np.zeros(7), at_rest=True)
        xd_a = impact_with(self.mass_matrix, self.j2, xd_plus, i_plus, at_rest=True)
        return exchange(xd_a[3:])

    def closure_gradients(self) -> tuple[np.ndarray, np.ndarray]:
        """d gap / d qd_a (in the next step's coordinates) and d gap / d qd_b, at this
        configuration (the gap is linear in both)."""
        row = self.momentum_row
        d_a = (row[3:] - row[:3] @ self.j2[:, 3:]) @ P_INVERSE
        return d_a, -row[3:]


def impact_with(mass_matrix: np.ndarray, contact: np.ndarray, xd: np.ndarray, joint_impulse: np.ndarray,
                at_rest: bool) -> np.ndarray:
    """The extended velocity after one impulsive sub-phase: D_e (Xd' - Xd) = B_e I + J^T I_R with
    the contact point of ``contact`` (J, 3 x 12) at rest after it (``at_rest``) or keeping its
    velocity (J Xd' = J Xd); ``joint_impulse`` I on q3..q9 (N m s)."""
    kkt = np.block([[mass_matrix, -contact.T], [contact, np.zeros((3, 3))]])
    rhs = np.concatenate([mass_matrix @ xd, np.zeros(3) if at_rest else contact @ xd])
    rhs[5:12] += joint_impulse
    return np.linalg.solve(kkt, rhs)[:12]


class HybridStep:
    """The hybrid step of one biped: its flows (one per RK8 grid), guard, reset maps."""

    def __init__(self, bm: BipedModel) -> None:
        self.bm = bm
        self._flows: dict[int, BallisticFlow] = {}

    def flow(self, steps: int) -> BallisticFlow:
        """The ballistic flow on a grid of ``steps`` RK8 steps per call (built once per grid)."""
        if steps not in self._flows:
            self._flows[steps] = BallisticFlow(self.bm.single, steps)
        return self._flows[steps]

    def guard(self, armed_after: float) -> TouchdownGuard:
        """The touchdown guard, armed ``armed_after`` s into the step."""
        return TouchdownGuard(self.bm, armed_after)

    def impact(self, q_t: np.ndarray) -> ImpactMap:
        """The reset's double support at touchdown configuration ``q_t``."""
        return ImpactMap(self.bm, q_t)
