"""The simulator's gait phase topic (biped_gait_interfaces/GaitPhase, after the convention of
biped_interfaces/Phase): published when a phase begins, i.e. at the first sample of a step's
phase (the stance foot of a single support, both feet of a double support that lasts, ``STOPPING``
while a stop brings the walk to rest, ``STANDING`` while the robot stands, ``STARTING`` while a start
sets it off: once, at its first sample) and at each touchdown (the instantaneous double
support). The topic is transient local, depth 1 (``qos.LATCHED``): a subscriber that joins
later, with that durability, receives the current phase at once. No physics here."""

from __future__ import annotations

from std_msgs.msg import Header

from biped_gait_interfaces.msg import GaitPhase

from ..core.walking.events import SINGLE_SUPPORT, STANDING, STARTING, STOPPING
from ..core.walking.world import WORLD_FRAME
from .walk_messages import stamp_msg

STANCE = {"left": GaitPhase.LEFT_STANCE, "right": GaitPhase.RIGHT_STANCE}
PHASES = {STANDING: GaitPhase.STANDING, STOPPING: GaitPhase.STOPPING, STARTING: GaitPhase.STARTING}  # the others: both feet


class GaitPhases:
    """Publishes the phases of a walk on ``publisher`` (a ``RecordedPublisher`` of GaitPhase)
    with stamps ``start_ns`` + the walk time."""

    def __init__(self, publisher) -> None:
        self.publisher = publisher
        self._phase: tuple[int, int] | None = None  # the step and phase published last

    def restart(self) -> None:
        """A new walk begins (a reset): its first sample begins a phase whatever its step."""
        self._phase = None

    def sample(self, step: int, stance_side: str, kind: str, t: float, start_ns: int) -> None:
        """A sample of ``step`` at ``t`` (s in the walk), of a phase of ``kind``
        (``events.PHASE_KINDS``): that phase begins if it is its first."""
        phase = STANCE[stance_side] if kind == SINGLE_SUPPORT else PHASES.get(kind, GaitPhase.DOUBLE_STANCE)
        if (step, phase) != self._phase:
            self._phase = (step, phase)
            self._publish(phase, step, t, start_ns)

    def touchdown(self, step: int, t: float, start_ns: int) -> None:
        """``step`` ends at ``t`` (s in the walk) with the double support: it begins then (the
        paper's, instantaneous), unless its samples began it already (one that lasts, whose
        touchdown event comes at its lift-off, a stop, at its end, or a start, at its lift-off)."""
        if self._phase not in ((step, GaitPhase.DOUBLE_STANCE), (step, GaitPhase.STOPPING), (step, GaitPhase.STARTING)):
            self._phase = (step, GaitPhase.DOUBLE_STANCE)
            self._publish(GaitPhase.DOUBLE_STANCE, step, t, start_ns)

    def _publish(self, phase: int, step: int, t: float, start_ns: int) -> None:
        stamp_ns = start_ns + round(t * 1e9)
        msg = GaitPhase(header=Header(stamp=stamp_msg(stamp_ns), frame_id=WORLD_FRAME), phase=phase, step=step)
        self.publisher.publish(msg, stamp_ns)
