"""Both feet on the ground: the closed chain of a double support that lasts (docs/model.md section 12).

Both foot tips are held as point contacts. The old stance tip is held as the single support holds
it (the root of the single-support tree, its ankle a passive roll and pitch, its spin held); the new
one, the swing tip, by the contact rows C(q) over the single-support coordinates q:

    M(q) qdd + h(q, qd) = S' tau + C(q)' f,      C(q) qdd + Cdot(q, qd) qd = 0

with tau the actuated joints' torques (N m), f the new tip's reaction (N: world axes of the step's
model; with lateral hip joints also its spin moment about its shin, N m, which the ground holds as
it holds the stance foot's), M, h those of the single-support model. The old tip's reaction
(force, and spin moment with lateral hip joints) follows from the double-support model's inverse
dynamics, whose root rows carry it (``reactions``).

**Which rows the new tip holds.** With legs of pitch joints only (the paper's nine coordinates)
the legs move in the sagittal planes of a frame rolled by q1, and a double support has q1 = 0:
the swing tip's lateral position then does not depend on q to first order (its row of C is zero),
only to second (a rotation phi about the feet line moves it by about 0.2 phi^2 m). Its x and z
are held; the lateral force at the new tip is an internal force between the feet, which the
motion does not determine (``lateral_free``). With lateral hip joints all three and the spin are
held.

**The passive impact with both tips held** (``impact``): the touchdown with the old tip staying
on the ground, D_e (Xd^+ - Xd^-) = J1' I1 + J2' I2, J1 Xd^+ = J2 Xd^+ = 0, no joint impulse; the old
tip's impulse I1 must press on the ground (I1z >= 0) for the double support to begin.

Units SI, rad; forces in N, impulses in N s.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from ..model.biped import SWING_TIP, BipedModel
from .hybrid import contact_jacobians

SPIN_STEP = 1e-7  # rad: the central difference in time of the spin row (its Cdot qd)


@dataclass(frozen=True, eq=False)
class HeldImpact:
    """The passive impact with both tips held, at a touchdown configuration: the velocity after it
    (rad/s, q), the old and the new tip's reaction impulses (N s, world axes of the step's model; with
    lateral hip joints the spin impulse moment last, N m s)."""

    qd: np.ndarray
    old: np.ndarray
    new: np.ndarray


class ClosedChain:
    """The double-support dynamics of ``bm`` with both tips held (module docstring); ``exchange``
    is the model's leg exchange (the new foot's spin row). Not thread-safe (Pinocchio data reused)."""

    def __init__(self, bm: BipedModel, exchange) -> None:
        self.bm, self.exchange = bm, exchange
        self.ds = bm.double_support
        self.ds_data = self.ds.createData()
        self.n = bm.nq
        self.at = np.asarray(bm.ds_of_single)
        self.roots = np.setdiff1d(np.arange(self.ds.nv), self.at)
        self.actuated = np.asarray(bm.actuated)
        self.lateral_free = not bm.params.joints.lateral_hips
        self.rows = np.array([0, 2]) if self.lateral_free else np.arange(4)
        self.tip_frame = self.ds.getFrameId(SWING_TIP)

    @property
    def force_size(self) -> int:
        """Components of the new tip's reaction: force (3), and spin moment with lateral hips."""
        return 3 if self.lateral_free else 4

    @cached_property
    def selection(self) -> np.ndarray:
        """S' (nq x nA): the actuated joints' torques as generalized forces."""
        s = np.zeros((self.n, len(self.actuated)))
        s[self.actuated, np.arange(len(self.actuated))] = 1.0
        return s

    # The contacts ---------------------------------------------------------------------------------
    def new_tip(self, q: np.ndarray) -> np.ndarray:
        """J2 over the double-support coordinates X (3 rows, and the spin row with lateral hips)."""
        return contact_jacobians(self.bm, self.exchange, q)[1]

    def rows_of(self, q: np.ndarray) -> np.ndarray:
        """C(q): the held rows of the new tip over q."""
        return self.new_tip(q)[self.rows][:, self.at]

    def drift(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Cdot(q, qd) qd: the held rows' acceleration at qdd = 0 (m/s^2, rad/s^2)."""
        model, data = self.ds, self.ds_data
        x, xd = self.bm.ds_state(q), self.bm.embed(qd)
        pin.forwardKinematics(model, data, x, xd, np.zeros(model.nv))
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        out = list(pin.getFrameClassicalAcceleration(model, data, self.tip_frame, frame).linear)
        if not self.lateral_free:
            h = SPIN_STEP
            row = (self.exchange.spin_row(q + h * qd) - self.exchange.spin_row(q - h * qd)) / (2 * h)
            out.append(float(row @ xd))
        return np.asarray(out)[self.rows]

    # Dynamics ---------------------------------------------------------------------------------
    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """D_e(q) of the double-support model, symmetric."""
        return self.bm.mass_matrix(q)

    def forward(self, q: np.ndarray, qd: np.ndarray, torque: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """qdd (rad/s^2) and the new tip's held reaction (its ``rows``) under the actuated joints'
        ``torque`` (N m) with both tips held."""
        x, xd = self.bm.ds_state(q), self.bm.embed(qd)
        m = self.mass_matrix(q)[np.ix_(self.at, self.at)]
        bias = pin.rnea(self.ds, self.ds_data, x, xd, np.zeros(self.ds.nv))[self.at]
        c = self.rows_of(q)
        n, r = self.n, len(self.rows)
        kkt = np.zeros((n + r, n + r))
        kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = m, -c.T, c
        solved = np.linalg.solve(kkt, np.concatenate([self.selection @ torque - bias, -self.drift(q, qd)]))
        return solved[:n], solved[n:]

    def reactions(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, new: np.ndarray) -> np.ndarray:
        """The old tip's reaction (N; and spin moment, N m, with lateral hips) for the motion (q, qd,
        qdd) and the new tip's reaction ``new`` (all its components, ``force_size``): the root rows of
        the double-support model's inverse dynamics less what the new tip carries there."""
        x, xd, xdd = self.bm.ds_state(q), self.bm.embed(qd), self.bm.embed(qdd)
        tau = pin.rnea(self.ds, self.ds_data, x, xd, xdd)
        return (tau - self.new_tip(q).T @ new)[self.roots]

    def wrenches(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, new: np.ndarray) -> np.ndarray:
        """[Fx, Fy, Fz, Mz] at the old and at the new tip (2 x 4: N; N m about the vertical through
        the tip) for the motion (q, qd, qdd) and the new tip's reaction ``new`` (all its components):
        the extended model's inverse dynamics gives the whole ground wrench at the old tip, the root
        (``samples.ground_reaction_inverse_dynamics``); the new tip's force and spin moment, moved
        there, are taken from it."""
        bm = self.bm
        x, xd, xdd = bm.extended_state(q), np.concatenate([np.zeros(3), qd]), np.concatenate([np.zeros(3), qdd])
        total = pin.rnea(bm.extended, bm.extended_data, x, xd, xdd)[:3]
        moment = bm.extended_data.f[1].angular[2]
        force, tip = new[:3], bm.swing_tip(q)
        spin = 0.0
        if not self.lateral_free:  # the spin moment about the new tip's shin, its vertical part
            pin.framesForwardKinematics(bm.single, bm.single_data, q)
            spin = float(new[3] * bm.single_data.oMf[bm.single.getFrameId(SWING_TIP)].rotation[2, 2])
        old_moment = moment - (tip[0] * force[1] - tip[1] * force[0]) - spin
        return np.array([[*(total - force), old_moment], [*force, spin]])

    def shared_wrenches(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, held: np.ndarray) -> np.ndarray:
        """``wrenches`` for the new tip's held reaction ``held`` (its ``rows``), with legs of pitch
        joints only the free lateral force shared between the feet so that the larger of their
        friction ratios |F_xy| / F_z is least (the motion does not determine it; rigid point feet
        take any share, and the one that needs the least friction is the one a floor holds first;
        each ratio is convex in the share while both feet press)."""
        first = self.wrenches(q, qd, qdd, self.full_force(held))
        if not self.lateral_free:
            return first
        from scipy.optimize import minimize_scalar  # SciPy's optimizers only where a walk holds both feet

        share = self.lateral_share(q)

        def at(lateral: float) -> np.ndarray:
            """``wrenches`` with the new tip's lateral force ``lateral``: affine in it."""
            return first + lateral * share

        def ratio(lateral: float) -> float:
            w = at(lateral)
            return max(np.hypot(f[0], f[1]) / f[2] if f[2] > 0 else np.inf for f in w[:, :3])

        if np.any(first[:, 2] <= 0):
            return first
        reach = abs(first[0, 1]) + np.abs(first[:, :2]).sum()
        return at(minimize_scalar(ratio, bounds=(-reach, reach), method="bounded", options={"xatol": 1e-9}).x)

    def lateral_share(self, q: np.ndarray) -> np.ndarray:
        """The change of ``wrenches`` (2 x 4) per newton of the new tip's lateral force at ``q``, with
        legs of pitch joints only (the motion does not determine it): the new tip takes it, the old
        tip the rest, with its moment about the vertical."""
        return np.array([[0.0, -1.0, 0.0, -self.bm.swing_tip(q)[0]], [0.0, 1.0, 0.0, 0.0]])

    def full_force(self, held: np.ndarray, lateral: float = 0.0) -> np.ndarray:
        """The new tip's reaction with all its components from its held rows (``lateral``: the free
        lateral force, N, with legs of pitch joints only)."""
        if not self.lateral_free:
            return np.asarray(held, dtype=float)
        return np.array([held[0], lateral, held[1]])

    def lateral_drift(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray | None:
        """With legs of pitch joints only, minus the new tip's sideways velocity (m/s, model axes;
        None with lateral hips, which hold it): the chain holds the new tip's x and z (its lateral
        row vanishes at q1 = 0), and rolling over the feet line moves it sideways to second order,
        a few mm/s by a lift-off. The whole robot translated by this velocity has the new tip at
        rest and the old one drifting instead."""
        if not self.lateral_free:
            return None
        _, j2 = contact_jacobians(self.bm, self.exchange, q)
        return np.array([0.0, -float(j2[1] @ self.bm.embed(qd)), 0.0])

    def impact(self, q: np.ndarray, qd: np.ndarray) -> HeldImpact:
        """The passive impact at ``q`` from the single-support velocity ``qd`` (rad/s), both tips held
        after it (module docstring; with legs of pitch joints only the lateral impulse is carried by
        the old tip)."""
        bm = self.bm
        d = bm.mass_matrix(q)
        j1, j2 = contact_jacobians(bm, self.exchange, q)
        j = np.vstack([j1, j2[self.rows]])
        n, c = d.shape[0], j.shape[0]
        kkt = np.zeros((n + c, n + c))
        kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = d, -j.T, j
        xd = bm.embed(qd)
        solved = np.linalg.solve(kkt, np.concatenate([d @ xd, np.zeros(c)]))
        impulses = solved[n:]
        old = impulses[:j1.shape[0]]
        return HeldImpact(solved[:n][self.at], old, self.full_force(impulses[j1.shape[0]:]))
