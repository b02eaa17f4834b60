"""The walk's stop, ready to walk (docs/model.md section 14.2): a stop planned from a gait's
touchdown into the standing posture (``core/gait/spline_support.py``; the package keeps the default
gait's, ``kept_stop_path``), with what the walk needs of it: the plan to track
(``held_support.HeldSupport``, its feedback the finite-horizon LQR's, ``tracking``) and the
balance controller that holds the posture it ends in (``balance``). ``Walker.stop`` walks it at the touchdown of a step aimed at its gait
(``phases.stopping``).

Units SI, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import HybridStep
from ..gait.spline_support import kept_stop_path, load_plan
from ..model.params import BipedParams, load_params
from .balance import Balance, balance, standing_pose
from .held_support import HeldSupport, held_support
from .orbit import PlannedOrbit

SAME_GAIT = 1e-9  # m, s, rad: a gait this close to the stop's in L, T and alpha is the stop's (they are stored to 1e-16)
# rad, rad/s: a step that starts this close to its gait's start (q0, qd_a) takes the stop. Its
# touchdown is then as close to the plan's (measured: after a push the momentum-steered walk's
# touchdown errors follow its steps' start errors within 10 %, contracting fourfold a step), and
# the stop takes touchdowns 1e-3 rad/s off its plan (docs/model.md 14.2); 3e-4 keeps a margin.
SETTLED = 3e-4


class Unsettled(ValueError):
    """A step that starts farther than ``SETTLED`` from its gait's start: the stop waits (the walk
    settles in a few steps)."""


@dataclass(frozen=True, eq=False)
class WalkStop:
    """A stop from the gait (``params``, ``step_length`` m, ``period`` s, ``arm_amplitude`` rad,
    ``mode``) into standing: the ``plan`` to track from the gait's touchdown and the ``balance`` that
    holds the posture it ends in."""

    params: BipedParams
    step_length: float
    period: float
    arm_amplitude: float
    mode: str
    plan: HeldSupport
    balance: Balance

    def why_not(self, orbit: PlannedOrbit) -> str:
        """Why a step aimed at ``orbit`` cannot end in this stop ('' if it can)."""
        if orbit.double_support is not None or orbit.swing_ends is not None:
            return "the stop is planned from the paper's impulsive gait, not from one with a double support that lasts"
        if not math.isinf(orbit.turn_radius):
            return "the stop is planned from a straight gait"
        same = (load_params(orbit.params or None) == self.params and orbit.mode == self.mode
                and all(abs(a - b) <= SAME_GAIT for a, b in ((orbit.step_length, self.step_length),
                                                              (orbit.period, self.period),
                                                              (orbit.arm_amplitude, self.arm_amplitude))))
        if same:
            return ""
        return (f"the stop is planned from the gait L = {self.step_length:g} m, T = {self.period:g} s, alpha = "
                f"{math.degrees(self.arm_amplitude):.4g} deg, {self.mode} ({self.params.name}), not from L = "
                f"{orbit.step_length:g} m, T = {orbit.period:g} s, alpha = {math.degrees(orbit.arm_amplitude):.4g} deg, "
                f"{orbit.mode}")


def unsettled(q: np.ndarray, qd: np.ndarray, orbit: PlannedOrbit) -> float:
    """How far a step's start (``q``, ``qd``) is from its gait's (max |(q, qd) - (q0, qd_a)|, rad,
    rad/s); the stop is taken from a step within ``SETTLED``."""
    return max(float(np.max(np.abs(q - orbit.q0))), float(np.max(np.abs(qd - orbit.qd_a))))


def kept_stop(hybrid: HybridStep) -> WalkStop:
    """The package's kept stop (``kept_stop_path``) for the model of ``hybrid``: ``ValueError`` if
    the model is not of the parameter set it was planned for."""
    with_params = load_params(None)
    if hybrid.bm.params != with_params:
        raise ValueError(f"a stop is kept for the parameter set {with_params.name} only, not for {hybrid.bm.params.name}")
    chain = ClosedChain(hybrid.bm, hybrid.exchange)
    support, meta = load_plan(kept_stop_path(), hybrid.bm)
    pose = standing_pose(chain, meta["L"])
    return WalkStop(with_params, meta["L"], meta["T"], meta["alpha"], meta["mode"], held_support(chain, support, horizon=True),
                    balance(chain, pose))
