"""A solved double support that lasts, as a value (docs/model.md section 14): what the program of
``lasting.py`` returns, what the plan's JSON and the GaitPlan message carry, and what a walk
tracks. No CasADi here: a process that only reads or walks a plan does not load it.

Units SI, rad; forces N, impulses N s, joint impulses N m s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

IMPULSE_TIME = 0.1  # s: a reaction impulse's scale is the weight over this long
NEGLIGIBLE = 1e-7  # of a reaction's scale: below it a reaction is the solver's tolerance, not a force


@dataclass(frozen=True, eq=False)
class LastingSupport:
    """A solved (or refused) double support of ``duration`` seconds. Samples at every collocation
    point (nodes and midpoints, 2 n + 1 instants from 0 to d, both included, n its ``INTERVALS``): ``t`` (s),
    ``x``, ``xd``, ``xdd`` in the double-support coordinates X, ``torques`` (N m, actuated joints),
    ``contact_forces`` (old and new stance tip, world axes, N, n x 2 x 3). The impulses: ``i_minus``,
    ``i_plus`` (N m s), ``held_impact_impulses`` (old and new tip, N s, 2 x 3). Efforts (N m s):
    ``effort_l1`` and ``effort_l2`` of the torques over the phase, ``effort_total`` the minimized
    E's l1 reading (impulses and torques)."""

    duration: float
    success: bool
    message: str
    t: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    xdd: np.ndarray
    torques: np.ndarray
    contact_forces: np.ndarray
    i_minus: np.ndarray
    i_plus: np.ndarray
    held_impact_impulses: np.ndarray
    effort_l1: float
    effort_l2: float
    effort_total: float
    iterations: int
    solve_time_s: float
    next_start_velocity: np.ndarray | None = None  # periodic: the next step's qd(0) (its own coordinates, rad/s)
    push_off: np.ndarray | None = None  # periodic: the old tip's reaction impulse at I^+ (N s, world axes of the step's model)
    solution: dict | None = None  # the program's unknowns and multipliers, to warm-start a nearby solve
    # With lateral hip joints: the ground's spin moments on the old and the new foot over the phase
    # (n x 2, N m; the old about its shin, the new about the vertical, its heading's) and at the held
    # impact (2, N m s).
    spin_moments: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def peak_torque(self) -> np.ndarray:
        """The largest |Gamma_j| over the phase, per actuated joint (N m)."""
        return np.abs(self.torques).max(axis=0) if len(self.torques) else np.zeros(self.i_minus.shape)

    @property
    def friction_used(self) -> float:
        """The largest |F_xy| / F_z of both tips over the phase and of the held impact's impulses;
        a reaction within the solver's tolerance of zero (``NEGLIGIBLE`` of the phase's largest
        normal force, or of its impulse over 0.1 s) needs none: its direction is rounding's."""
        largest = float(np.max(np.abs(self.contact_forces[..., 2]), initial=0.0)) or 1.0
        ratios = [0.0]
        for forces, floor in ((self.contact_forces.reshape(-1, 3), NEGLIGIBLE * largest),
                              (self.held_impact_impulses, NEGLIGIBLE * largest * IMPULSE_TIME)):
            for f in forces:
                if np.linalg.norm(f) > floor:
                    ratios.append(np.hypot(f[0], f[1]) / f[2] if f[2] > 0 else math.inf)
        return float(max(ratios))


def refused_support(message: str) -> LastingSupport:
    """No phase, ``message`` saying why: duration 0, every array empty, every figure 0 (the
    GaitPlan's phases read so where there is none)."""
    empty = np.zeros(0)
    rows = np.zeros((0, 0))
    return LastingSupport(0.0, False, message, empty, rows, rows, rows, rows, np.zeros((0, 2, 3)), empty, empty,
                          np.zeros((0, 3)), 0.0, 0.0, 0.0, 0, 0.0)
