"""Standing: a posture with both feet down and a balance controller that holds it (docs/model.md
section 13).

**The posture** (``standing_pose``): the feet ``stance_length`` apart along the walking direction
and the step width apart sideways, both legs straight, the torso not yawed, the arms hanging (0),
the pelvis and trunk pitched by the theta that puts the centre of mass over the line through both
feet (the feet line): section 3's double-support configuration q(T) at that step length, arm
amplitude 0. Its static torques: the actuated joints' torques and the feet's reactions that hold it
against gravity, the torques of least norm (the feet's squeeze along the legs takes what it can).

**Why a controller, and which.** With point feet, nothing holds the body's rotation about the feet
line but the body's shape: the joint torques are internal and both reactions act on the line, so
the momentum about it changes by m g delta alone (delta: the centre of mass's signed distance
from the line). Standing is an inverted pendulum about the feet line (time constant about 0.3 s),
balanced only by moving the centre of mass across the line with the hips, the torso and the arms.
``balance`` linearizes the closed chain (core/dynamics/closed_chain.py) about the posture in
minimal coordinates (the null space N of the held contact rows: delta q = N x), checks that every
unstable mode is controllable (the PBH test: rank [A - lambda I, B] = 2 m at each eigenvalue
lambda with Re lambda >= 0), and makes an LQR state feedback, u = u* - K [N'(q - q*); N' qd],
its weights by Bryson's rule: 0.1 rad and 1 rad/s of each minimal coordinate against a tenth of
each joint's effort limit (a closed loop of tens of 1/s, which a 1 ms step integrates).

Units SI, rad; torques N m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg import solve_continuous_are
from scipy.optimize import brentq

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import locked_rotation
from ..gait.configurations import GaitMode, boundary_configurations

STANCE_LENGTH = 0.2  # m: the front foot this far ahead of the back one while standing
FD_STEP = 1e-6  # rad, rad/s, N m: the linearization's central differences
POSITION_SCALE = 0.1  # rad: the deviation of each minimal coordinate the LQR weighs as one unit
RATE_SCALE = 1.0  # rad/s: likewise for their rates
TORQUE_SCALE = 0.1  # of each joint's effort limit: the torque the LQR weighs as one unit
RANK_TOLERANCE = 1e-9  # the PBH test's relative singular-value tolerance


class BalanceError(ValueError):
    """The standing posture cannot be held: the message says why."""


@dataclass(frozen=True, eq=False)
class StandingPose:
    """A posture with both feet down (model coordinates of the back foot's frame: its tip at the
    origin, the front foot at (``stance_length``, ``width``, 0)), the actuated joints' static torques
    (N m) and the front foot's static reaction (all its components, N, N m)."""

    q: np.ndarray
    torque: np.ndarray
    force: np.ndarray
    stance_length: float
    width: float
    theta: float


@dataclass(frozen=True, eq=False)
class Balance:
    """The LQR that holds ``pose`` of ``chain``: the minimal coordinates' basis ``basis`` (nq x m,
    orthonormal), the gain ``gain`` (nA x 2m), the open-loop and closed-loop eigenvalues of the
    linearization (1/s), and the torque limits (N m)."""

    chain: ClosedChain
    pose: StandingPose
    basis: np.ndarray
    gain: np.ndarray
    open_loop: np.ndarray
    closed_loop: np.ndarray
    limits: np.ndarray

    @property
    def time_constant(self) -> float:
        """1 / the largest unstable open-loop eigenvalue (s): how fast standing falls unheld."""
        return 1.0 / float(np.max(self.open_loop.real))

    def torque(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """The actuated joints' torques (N m) at (``q``, ``qd``), within their limits."""
        x = np.concatenate([self.basis.T @ (q - self.pose.q), self.basis.T @ qd])
        return np.clip(self.pose.torque - self.gain @ x, -self.limits, self.limits)


def centre_offset(chain: ClosedChain, q: np.ndarray) -> float:
    """delta (m): the centre of mass's horizontal distance from the feet line at ``q``, positive
    on the left of the line from the back foot to the front one."""
    bm = chain.bm
    com = bm.momentum(q, bm.embed(np.zeros(bm.nq)))[2]
    tip = bm.swing_tip(q)
    u = tip[:2] / np.linalg.norm(tip[:2])
    return float(u[0] * com[1] - u[1] * com[0])


def standing_pose(chain: ClosedChain, stance_length: float = STANCE_LENGTH, width: float | None = None) -> StandingPose:
    """The standing posture (module docstring); ``width`` None: the hips' spacing."""
    bm = chain.bm
    configurations = boundary_configurations(bm)

    def posture(theta: float) -> np.ndarray:
        return configurations(stance_length, 0.0, GaitMode.NORMAL, theta, width)[1]

    try:
        theta = brentq(lambda th: centre_offset(chain, posture(th)), -0.5, 0.5, xtol=1e-14)
    except ValueError:
        raise BalanceError(f"no trunk pitch within 0.5 rad puts the centre of mass over the feet line at a stance "
                           f"length of {stance_length:g} m") from None
    q = posture(theta)
    zero = np.zeros(bm.nq)
    x = bm.ds_state(q)
    gravity = pin.rnea(chain.ds, chain.ds_data, x, bm.embed(zero), bm.embed(zero))[chain.at]
    c = chain.rows_of(q)
    # The torques of least norm: the feet's reactions (their squeeze along the legs included) take
    # what they can, the joints the rest.
    free = np.eye(bm.nq) - c.T @ np.linalg.pinv(c.T)  # the generalized forces the held tip cannot give
    torque = np.linalg.pinv(free @ chain.selection) @ (free @ gravity)
    held = np.linalg.lstsq(c.T, gravity - chain.selection @ torque, rcond=None)[0]
    return StandingPose(q, torque, chain.full_force(held), stance_length, configurations.width(width), theta)


def linearization(chain: ClosedChain, q: np.ndarray, qd: np.ndarray, torque: np.ndarray,
                  basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A (2m x 2m) and B (2m x nA) of the closed chain about the state (``q``, ``qd``) under the
    actuated joints' ``torque`` (N m), in the minimal coordinates x = N' delta q, their rates
    N' delta qd, the torques' deviation (central differences of the forward dynamics)."""
    m, na = basis.shape[1], len(chain.actuated)

    def rates(x: np.ndarray, xd: np.ndarray, du: np.ndarray) -> np.ndarray:
        qdd = chain.forward(q + basis @ x, qd + basis @ xd, torque + du)[0]
        return basis.T @ qdd

    h = FD_STEP
    a, b = np.zeros((2 * m, 2 * m)), np.zeros((2 * m, na))
    a[:m, m:] = np.eye(m)
    zero_m, zero_a = np.zeros(m), np.zeros(na)
    for k in range(m):
        e = np.zeros(m)
        e[k] = h
        a[m:, k] = (rates(e, zero_m, zero_a) - rates(-e, zero_m, zero_a)) / (2 * h)
        a[m:, m + k] = (rates(zero_m, e, zero_a) - rates(zero_m, -e, zero_a)) / (2 * h)
    for k in range(na):
        e = np.zeros(na)
        e[k] = h
        b[m:, k] = (rates(zero_m, zero_m, e) - rates(zero_m, zero_m, -e)) / (2 * h)
    return a, b


def minimal_basis(chain: ClosedChain, q: np.ndarray) -> np.ndarray:
    """N (nq x m): an orthonormal basis of the null space of the held rows at ``q``."""
    c = chain.rows_of(q)
    return np.linalg.svd(c)[2][c.shape[0]:].T


def effort_limits(chain: ClosedChain) -> np.ndarray:
    """The actuated joints' effort limits (N m), from the joint table."""
    return np.array([chain.bm.coordinates[k].spec.limits.effort for k in chain.actuated])


def lqr_gain(a: np.ndarray, b: np.ndarray, limits: np.ndarray, position_scale: float = POSITION_SCALE,
             rate_scale: float = RATE_SCALE) -> np.ndarray:
    """The LQR gain K (nA x 2m) of (``a``, ``b``) with Bryson's weights (module docstring): each
    minimal coordinate's ``position_scale`` (rad) and rate's ``rate_scale`` (rad/s) against
    ``TORQUE_SCALE`` of each joint's effort limit ``limits`` (N m)."""
    m = a.shape[0] // 2
    q_weight = np.diag(np.concatenate([np.full(m, 1 / position_scale ** 2), np.full(m, 1 / rate_scale ** 2)]))
    r_weight = np.diag(1.0 / (TORQUE_SCALE * limits) ** 2)
    p = solve_continuous_are(a, b, q_weight, r_weight)
    return np.linalg.solve(r_weight, b.T @ p)


def uncontrollable(a: np.ndarray, b: np.ndarray) -> list[complex]:
    """The eigenvalues of ``a`` with Re >= 0 that ``b`` cannot move (the PBH test)."""
    out = []
    n = a.shape[0]
    for lam in np.linalg.eigvals(a):
        if lam.real < 0:
            continue
        s = np.linalg.svd(np.hstack([a - lam * np.eye(n), b]), compute_uv=False)
        if s[-1] <= RANK_TOLERANCE * s[0]:
            out.append(complex(lam))
    return out


def balance(chain: ClosedChain, pose: StandingPose) -> Balance:
    """The LQR that holds ``pose`` (module docstring); ``BalanceError`` if an unstable mode of the
    linearization is not controllable."""
    basis = minimal_basis(chain, pose.q)
    a, b = linearization(chain, pose.q, np.zeros_like(pose.q), pose.torque, basis)
    stuck = uncontrollable(a, b)
    if stuck:
        raise BalanceError(f"standing cannot be held: its unstable mode(s) {', '.join(f'{v.real:.3g} 1/s' for v in stuck)} "
                           "cannot be moved by the joint torques")
    limits = effort_limits(chain)
    gain = lqr_gain(a, b, limits)
    return Balance(chain, pose, basis, gain, np.linalg.eigvals(a), np.linalg.eigvals(a - b @ gain), limits)


def feet_line_momentum(chain: ClosedChain, q: np.ndarray, qd: np.ndarray) -> float:
    """The angular momentum about the feet line (kg m^2/s) at (``q``, ``qd``)."""
    bm = chain.bm
    return float(locked_rotation(bm, q) @ bm.mass_matrix(q) @ bm.embed(qd))

