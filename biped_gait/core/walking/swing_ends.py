"""What a walk needs of a cycle whose swing is actuated at its two ends (docs/model.md section
15.1; the plan: ``core/gait/actuated_swing.py``): its two actuated ends as references to track
(``tracking``: the single support with the stance tip pinned, ``PinnedTip``, driven by the plan's
torques and the LQR about the plan), its double support (``held_support``), and the orbit that
carries them.

**Resolution.** The plan holds the single support's equations at its collocation points only
(Hermite-Simpson, 10 intervals of tau / 10 at each end), and Hermite-Simpson can ring between
them (docs/model.md 14: the stop and the start were refused for it). Along the reference the
stance tip's reaction, from the single support's forward dynamics every millisecond, must press
within the floor's friction (``SwingEnds.reactions``); ``actuated_orbit`` refuses a plan whose
reference does not, with the figures.

Times in each end (s from its start); q, qd in the step's model coordinates. Units SI, rad.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import HybridStep
from .held_support import held_support
from .orbit import PlannedOrbit
from .phases.pulse_dynamics import PinnedTip, friction_ratio
from .tracking import Tracking, tracking


@dataclass(frozen=True, eq=False)
class SwingEnds:
    """The actuated ``start`` and ``end`` of the swing, each a ``tracking.Tracking`` of the single
    support driven (its chain a ``PinnedTip``), times from its own start."""

    start: Tracking
    end: Tracking

    @property
    def duration(self) -> float:
        """tau (s): how long each end is actuated."""
        return self.start.duration

    def reactions(self, which: str) -> tuple[np.ndarray, np.ndarray]:
        """Along the reference of the end ``which`` (``start`` or ``end``; ``Tracking.along``, every
        millisecond): the instants (s in the end) and the stance tip's reaction there (n x 3, N,
        world axes of the step's model), the single support's forward dynamics under the plan's
        torques in the plan's interpolated state."""
        rows = [(t, force) for t, _, _, _, _, force in getattr(self, which).along()]
        return np.array([t for t, _ in rows]), np.array([force for _, force in rows])


def swing_tracking(pinned: PinnedTip, end) -> Tracking:
    """The ``Tracking`` of an actuated end of the swing (``actuated_swing.SwingEnd``: its samples in
    the double-support coordinates, the stance tip at the origin)."""
    at = np.asarray(pinned.bm.ds_of_single)
    return tracking(pinned, end.t - end.t[0], end.x[:, at], end.xd[:, at], end.xdd[:, at], end.torques)


def actuated_orbit(orbit: PlannedOrbit, cycle, hybrid: HybridStep) -> PlannedOrbit:
    """The gait of ``orbit`` walked with the swing actuated at its two ends as ``cycle`` plans it (a
    solved ``actuated_swing.ActuatedSwingCycle`` with a double support that lasts, d > 0): the step
    from the actuated start's first state (the lift-off, legs exchanged) to the actuated end's last
    (the touchdown, on q_T), its ends and its double support to track. ``ValueError`` if the cycle
    is not solved, has no double support, or its reference pulls or slips between the collocation
    points (module docstring)."""
    if not cycle.success:
        raise ValueError(f"cannot walk a cycle that was not solved: {cycle.message}")
    pinned = PinnedTip(hybrid.bm)
    ends = SwingEnds(swing_tracking(pinned, cycle.start), swing_tracking(pinned, cycle.end))
    mu = hybrid.bm.params.friction
    for which in ("start", "end"):
        t, forces = ends.reactions(which)
        least, ratio = float(forces[:, 2].min()), friction_ratio(forces)
        if not (least > 0.0 and ratio <= mu):
            raise ValueError(f"the actuated {which} of the swing cannot be tracked: between its collocation points the "
                             f"stance tip's vertical reaction falls to {least:.0f} N and its friction ratio reaches "
                             f"{ratio:.3f} (mu = {mu:g}): its mesh does not resolve the phase (docs/model.md section 15.1)")
    support = held_support(ClosedChain(hybrid.bm, hybrid.exchange), cycle.support)
    return replace(orbit, q0=ends.start.q[0], qd_a=ends.start.qd[0], q_t=ends.end.q[-1], qd_b=ends.end.qd[-1],
                   double_support=support, swing_ends=ends)
