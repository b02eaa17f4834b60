"""The simulation's controls, as Gazebo offers them: ``~/pause``, ``~/resume`` and ``~/reset``
(std_srvs/Trigger), and ``~/iterations`` (std_msgs/UInt64), the step counter: the simulation
steps made (one per sample, 1 / ``publish_rate`` s of simulated time each) since the node
started, published (and recorded, stamped with the simulated time) at ``PERIOD`` s of wall
time when it changed and at once on a pause or reset.

A pause holds the walk before its next sample (simulated time stands still and the pacing
resumes where it stopped); a reset puts the robot back at the plan's start, its first stance
foot at the world's origin, with simulated time going on (as Gazebo's reset of the world), and
walks the plan again, also after a walk that ended (finished or fell) when the node stays up.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

from rclpy.callback_groups import CallbackGroup
from rclpy.node import Node
from std_msgs.msg import UInt64
from std_srvs.srv import Trigger

if TYPE_CHECKING:
    from .recorded import RecordedPublisher

PERIOD = 0.1  # s of wall time between publications of a changed counter
HOLD_POLL = 0.05  # s: how often a held walk checks for a stop


class SimControls:
    """Pause, resume and reset requests for the walk's thread, and the step counter, published
    with ``counter`` (a latched ``RecordedPublisher`` of ``~/iterations``) stamped ``now_ns()``."""

    def __init__(self, node: Node, group: CallbackGroup, counter: "RecordedPublisher",
                 now_ns: Callable[[], int]) -> None:
        self._running = threading.Event()
        self._running.set()
        self._reset = threading.Event()
        self._lock = threading.Lock()
        self.iterations = 0  # simulation steps made (the walk's thread counts them)
        self._published = -1
        self.can_reset = False  # a walk has begun: there is something to reset
        self._counter, self._now_ns = counter, now_ns
        node.create_service(Trigger, "~/pause", self._on_pause, callback_group=group)
        node.create_service(Trigger, "~/resume", self._on_resume, callback_group=group)
        node.create_service(Trigger, "~/reset", self._on_reset, callback_group=group)
        node.create_timer(PERIOD, self.publish_iterations, callback_group=group)

    @property
    def paused(self) -> bool:
        """True while a pause holds the walk."""
        return not self._running.is_set()

    def _on_pause(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success = not self.paused
        response.message = "paused" if response.success else "already paused"
        self._running.clear()
        self.publish_iterations()
        return response

    def _on_resume(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success = self.paused
        response.message = "resumed" if response.success else "not paused"
        self._running.set()
        return response

    def _on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success = self.can_reset
        response.message = "reset: the walk starts again from the plan's start" if self.can_reset else \
            "nothing to reset: no walk has begun"
        if self.can_reset:
            self._reset.set()
            self.publish_iterations()
        return response

    def hold(self, stop: threading.Event) -> None:
        """Return once not paused, or a reset or ``stop`` is asked for."""
        while not self._running.wait(HOLD_POLL):
            if stop.is_set() or self._reset.is_set():
                return

    def wait_for_reset(self, stop: threading.Event) -> bool:
        """Wait for a reset (True) or ``stop`` (False)."""
        while not self._reset.wait(HOLD_POLL):
            if stop.is_set():
                return False
        return True

    def reset_requested(self) -> bool:
        """True if a reset was asked for and not yet taken."""
        return self._reset.is_set()

    def take_reset(self) -> bool:
        """True (once) if a reset was asked for."""
        if self._reset.is_set():
            self._reset.clear()
            return True
        return False

    def publish_iterations(self) -> None:
        """Publish the step counter if it changed since it was last published."""
        with self._lock:
            count = self.iterations
            if count == self._published:
                return
            self._published = count
        self._counter.publish(UInt64(data=count), self._now_ns())
