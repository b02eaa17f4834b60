"""The walk's stop and start, ready to walk (docs/model.md sections 14.2, 14.3): a phase planned from a
gait's touchdown into the standing posture (the stop) or from rest in it onto the gait (the start)
(``core/gait/spline_support.py``; the package keeps the default gait's, ``kept_path``), with what
the walk needs of it: the plan to track (``held_support.HeldSupport``, its feedback the
finite-horizon LQR's, ``tracking``) and the balance controller of the standing posture it ends or
begins in (``balance``). ``Walker.stop`` walks the stop at the touchdown of a step aimed at its gait
(``phases.stopping``), ``Walker.start`` the start from standing (``phases.starting``).

Units SI, rad.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

import numpy as np

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import HybridStep
from ..gait.lasting_support import LastingSupport, refused_support
from ..gait.spline_support import kept_path, load_plan
from ..model.biped import BipedModel
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
class KeptGait:
    """What a kept ``kind`` of phase (``spline_support.KINDS``: ``stop`` from the gait's touchdown
    into standing, ``start`` from standing onto the gait) is planned with: the gait (``params``,
    ``step_length`` m, ``period`` s, ``arm_amplitude`` rad, ``mode``)."""

    kind: str
    params: BipedParams
    step_length: float
    period: float
    arm_amplitude: float
    mode: str

    def why_not(self, orbit: PlannedOrbit) -> str:
        """Why a step aimed at ``orbit`` cannot end in this stop, or the start cannot go onto it ('' if
        it can)."""
        kind = self.kind
        if orbit.double_support is not None or orbit.swing_ends is not None:
            return f"the {kind} is planned with the paper's impulsive gait, not with one with a double support that lasts"
        if not math.isinf(orbit.turn_radius):
            return f"the {kind} is planned with a straight gait"
        same = (load_params(orbit.params or None) == self.params and orbit.mode == self.mode
                and all(abs(a - b) <= SAME_GAIT for a, b in ((orbit.step_length, self.step_length),
                                                              (orbit.period, self.period),
                                                              (orbit.arm_amplitude, self.arm_amplitude))))
        if same:
            return ""
        return (f"the {kind} is planned with the gait L = {self.step_length:g} m, T = {self.period:g} s, alpha = "
                f"{math.degrees(self.arm_amplitude):.4g} deg, {self.mode} ({self.params.name}), not with L = "
                f"{orbit.step_length:g} m, T = {orbit.period:g} s, alpha = {math.degrees(orbit.arm_amplitude):.4g} deg, "
                f"{orbit.mode}")


@dataclass(frozen=True, eq=False)
class KeptPlan(KeptGait):
    """A kept phase ready to walk: its gait (``KeptGait``), the ``plan`` to track and the
    ``balance`` that holds the posture it ends or begins in."""

    plan: HeldSupport
    balance: Balance


def unsettled(q: np.ndarray, qd: np.ndarray, orbit: PlannedOrbit) -> float:
    """How far a step's start (``q``, ``qd``) is from its gait's (max |(q, qd) - (q0, qd_a)|, rad,
    rad/s); the stop is taken from a step within ``SETTLED``."""
    return max(float(np.max(np.abs(q - orbit.q0))), float(np.max(np.abs(qd - orbit.qd_a))))


def kept_gait(kind: str = "stop") -> KeptGait | None:
    """The gait the package's kept stop or start (``kind``) is planned with, from its file alone (a
    few milliseconds); None if it keeps none."""
    path = kept_path(kind)
    if not path.is_file():
        return None
    with np.load(path) as kept:
        meta = json.loads(str(kept["meta"]))
    return KeptGait(kind, load_params(None), meta["L"], meta["T"], meta["alpha"], meta["mode"])


def kept_why_not(kind: str, orbit: PlannedOrbit) -> str:
    """Why the package's kept ``kind`` (start, stop) is not of ``orbit``'s gait ('' if it is): none
    kept, or ``KeptGait.why_not``; read from the file's meta alone (milliseconds)."""
    gait = kept_gait(kind)
    return f"the package keeps no {kind}" if gait is None else gait.why_not(orbit)


def check_phases_request(double_support: float, actuated_swing: float) -> None:
    """``ValueError`` (one line) for a start and stop asked beside a double support that lasts or a
    swing actuated at its ends: the package keeps those of the paper's impulsive gait."""
    for name, value in (("double_support", double_support), ("actuated_swing", actuated_swing)):
        if value != 0.0:
            raise ValueError(f"start_stop: the start and the stop kept are of the paper's impulsive gait, not with "
                             f"{name} {value:g} s")


def kept_phases(bm: BipedModel, orbit: PlannedOrbit) -> tuple[LastingSupport, LastingSupport]:
    """The start from standing and the stop to standing that the package keeps for ``orbit``'s gait,
    as double supports of the model ``bm`` (``load_plan``; a plan's ``start_phase`` and
    ``stop_phase``), each refused with the reason (``refused_support``, ``KeptGait.why_not``) where
    none is kept for that gait. Milliseconds: read from the package's files (their ``solve_time_s``
    0, their ``iterations`` the last stage's; planning another gait's takes a continuation of an
    hour, ``studies/spline_study.py``; docs/model.md 14.3)."""
    phases = []
    for kind in ("start", "stop"):
        why = kept_why_not(kind, orbit)
        if why:
            phases.append(refused_support(why))
            continue
        support, meta = load_plan(kept_path(kind), bm)
        said = f"{support.message} (kept in the package: planned {meta['date']} at {meta['commit']})"
        phases.append(replace(support, message=said))
    return phases[0], phases[1]


def kept_plan(hybrid: HybridStep, kind: str = "stop") -> KeptPlan:
    """The package's kept stop or start (``kind``; ``kept_path``) for the model of ``hybrid``:
    ``ValueError`` if the model is not of the parameter set it was planned for, or none is kept."""
    with_params = load_params(None)
    if hybrid.bm.params != with_params:
        raise ValueError(f"a {kind} is kept for the parameter set {with_params.name} only, not for {hybrid.bm.params.name}")
    if not kept_path(kind).is_file():
        raise ValueError(f"the package keeps no {kind}")
    chain = ClosedChain(hybrid.bm, hybrid.exchange)
    support, meta = load_plan(kept_path(kind), hybrid.bm)
    pose = standing_pose(chain, meta["L"])
    return KeptPlan(kind, with_params, meta["L"], meta["T"], meta["alpha"], meta["mode"],
                    held_support(chain, support, horizon=True), balance(chain, pose))
