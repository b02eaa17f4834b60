"""The held feet kept where the floor holds them while a planned phase is tracked (docs/model.md
section 15.1): the actuated swing's walk tracks its plan with an LQR, which knows the joints and
not the floor, and its corrections can tip a reaction out of the friction cone (without this the
walk's double support slipped in its 15th step, at a friction ratio of 0.521).

At a given state the reactions of the held tips are affine in the joint torques (the forward
dynamics are), so the torques that keep them within reach are a convex set: the LQR's torques
``u`` are kept where they lie in it, else replaced by the nearest torques in it, each joint's
deviation weighed by its effort limit (a small quadratic program, OSQP):

    least sum ((v - u) / limit)^2  with  G (f0 + F v) <= 0,  f_z >= GUARD_LEAST_NORMAL_FORCE,  |v| <= limit,

G the octagonal pyramid circumscribing the cone of mu - ``GUARD_MARGIN`` (within the floor's mu:
the walk's fall test), per held tip. With both feet held (the closed chain) and legs of pitch
joints only, the lateral force's share between the feet is free (``ClosedChain.shared_wrenches``):
one more unknown, unweighted. Where no torques within their limits keep the reactions in reach,
the LQR's (within their limits) act, and the walk's fall test says what slipped.

Units SI, rad; forces N (world axes of the step's model), torques N m.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.impulses import pyramid

GUARD_MARGIN = 0.05  # below the floor's friction coefficient: the pyramid's inscribed cone
GUARD_LEAST_NORMAL_FORCE = 20.0  # N: each held tip's vertical reaction at least this
SOLVED = ("solved", "solved inaccurate")  # OSQP's statuses with an answer
TOLERANCE = 1e-8  # OSQP's absolute and relative tolerances (of the torques over their limits)
LATERAL_UNIT = 100.0  # N: the lateral share's unit in the program
SHARE_WEIGHT = 1e-8  # the lateral share's weight against each torque's (any share the cone allows will do)


def reaction_map(chain, q: np.ndarray, qd: np.ndarray, actuated: int) -> tuple[np.ndarray, np.ndarray]:
    """The held tips' forces (3 per tip, N) at (``q``, ``qd``) as f0 + F v over the ``actuated``
    joint torques v (and, for the closed chain with a free lateral share, one more unknown: the new
    tip's lateral force, the old tip taking the rest): f0 (3 k) and F (3 k x unknowns), from the
    chain's forward dynamics, exact (affine) at unit torques."""

    def forces(torque: np.ndarray) -> np.ndarray:
        qdd, held = chain.forward(q, qd, torque)
        if isinstance(chain, ClosedChain):
            return chain.wrenches(q, qd, qdd, chain.full_force(held))[:, :3].ravel()
        return np.asarray(held, dtype=float)

    f0 = forces(np.zeros(actuated))
    columns = [forces(e) - f0 for e in np.eye(actuated)]
    if isinstance(chain, ClosedChain) and chain.lateral_free:
        columns.append(chain.lateral_share(q)[:, :3].ravel())
    return f0, np.column_stack(columns)


def within_reach(chain, q: np.ndarray, qd: np.ndarray, actuated: int) -> tuple[np.ndarray, np.ndarray]:
    """The reactions within reach at (``q``, ``qd``) as linear constraints A v <= b on the unknowns
    of ``reaction_map`` (the ``actuated`` torques, N m, and the free lateral share, N): each held tip
    within the pyramid of the module docstring and pressing with ``GUARD_LEAST_NORMAL_FORCE``."""
    f0, f = reaction_map(chain, q, qd, actuated)
    mu = chain.bm.params.friction
    face = np.vstack([pyramid((mu - GUARD_MARGIN) / math.cos(math.pi / 8)), [[0.0, 0.0, -1.0]]])
    tips = len(f0) // 3
    rows = np.kron(np.eye(tips), face)
    least = np.concatenate([np.zeros(len(face) - 1), [-GUARD_LEAST_NORMAL_FORCE]])
    return rows @ f, np.tile(least, tips) - rows @ f0


def guarded_torque(chain, q: np.ndarray, qd: np.ndarray, torque: np.ndarray, limits: np.ndarray) -> np.ndarray:
    """``torque`` (N m, the tracking's; within ``limits``) where it keeps the held tips' reactions
    within reach, else the torques within ``limits`` nearest it that do (module docstring)."""
    u = np.clip(torque, -limits, limits)  # the tracking's, within the limits
    a, bound = within_reach(chain, q, qd, len(u))
    free = a.shape[1] - len(u)
    if not free and np.all(a @ u <= bound):
        return u
    # In units of each limit (and of LATERAL_UNIT for the lateral share), so that ADMM's tolerance is
    # one for all: least |x - u / limit|^2 (the share weighed by SHARE_WEIGHT, to make it unique).
    scale = np.concatenate([limits, np.full(free, LATERAL_UNIT)])
    weight = np.concatenate([np.ones(len(u)), np.full(free, SHARE_WEIGHT)])
    box = np.concatenate([np.ones(len(u)), np.full(free, np.inf)])
    import osqp  # here: only a guarded walk needs it (a tenth of a second to import)

    solver = osqp.OSQP()
    solver.setup(sparse.csc_matrix(np.diag(weight)), -np.concatenate([torque / limits, np.zeros(free)]),
                 sparse.csc_matrix(np.vstack([a * scale, np.eye(len(scale))])),
                 np.concatenate([np.full(len(bound), -np.inf), -box]), np.concatenate([bound, box]),
                 verbose=False, eps_abs=TOLERANCE, eps_rel=TOLERANCE)
    result = solver.solve(raise_error=False)
    if str(result.info.status) not in SOLVED:
        return u
    return np.clip(result.x[:len(u)] * limits, -limits, limits)

