"""A client side for scripts, tests and benchmarks: an rclpy context, node and executor of its
own in the calling process, with helpers to wait, connect to a service and call it, and the
planner's requests and goals built from the gait vocabulary's defaults.

Waits spin the executor with ``spin_once`` in a loop (faster than
``spin_until_future_complete`` for a client, and never stuck on a signal). A message's fields
start at 0, which means unset where 0 is not a meaningful value (``gait_options.resolve_unset``):
a default-constructed request is the default gait. ``plan_request`` and ``optimize_goal`` start
from the vocabulary's defaults as they are (friction NaN: the parameter set's; rate_bound inf:
none), so that a client sets only what it means and reads what it sent.
"""

from __future__ import annotations

import time

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor

from biped_gait_interfaces.action import OptimizeArmSwing
from biped_gait_interfaces.srv import PlanGait

from ..gait_options import OPTIONS, POINT

# The vocabulary's defaults a message can hold as they are (the mode is a code, params '' the node's).
_DEFAULTS = {option.name: option.default for option in (*POINT, *OPTIONS) if option.name not in ("mode", "params")}


def plan_request(**fields) -> PlanGait.Request:
    """A ``PlanGait`` request: the gait vocabulary's defaults, ``fields`` (SI, radians) over them."""
    return PlanGait.Request(**{**_DEFAULTS, **fields})


def optimize_goal(**fields) -> OptimizeArmSwing.Goal:
    """An ``OptimizeArmSwing`` goal: the vocabulary's defaults (no amplitude: the goal searches a
    range, default the paper's), ``fields`` over them."""
    defaults = {name: value for name, value in _DEFAULTS.items() if name != "arm_amplitude"}
    return OptimizeArmSwing.Goal(**{**defaults, **fields})


class ClientSide:
    """An rclpy context, a node named ``name`` and a single-threaded executor of their own."""

    def __init__(self, name: str) -> None:
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def wait(self, done, timeout: float = 30.0) -> None:
        """Spin until ``done()`` is true; ``TimeoutError`` after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while not done():
            if time.monotonic() > deadline:
                raise TimeoutError(f"timed out after {timeout:g} s")
            self.executor.spin_once(timeout_sec=0.005)

    def connect(self, client, timeout: float = 30.0) -> None:
        """Wait for a service, then let discovery finish the server's side: a response sent
        before the server has matched this client's reader is lost (a DDS race)."""
        self.connect_all([client], timeout)

    def connect_all(self, clients, timeout: float = 30.0) -> None:
        """``connect`` for several clients at once: each service waited for (``timeout`` s each),
        then one settle of a second after the last, which every client has had since its own
        service appeared (a second each, one after the other, took as many seconds as clients)."""
        for client in clients:
            if not client.wait_for_service(timeout_sec=timeout):
                raise TimeoutError(f"service {client.srv_name} did not appear in {timeout:g} s")
        settle = time.monotonic() + 1.0
        self.wait(lambda: time.monotonic() > settle, 5.0)

    def call(self, client, request, timeout: float = 30.0):
        """Call a service and return its response (spinning this side's executor)."""
        future = client.call_async(request)
        self.wait(future.done, timeout)
        return future.result()

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
