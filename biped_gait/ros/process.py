"""Running a node as a process: spin on a multi-threaded executor until SIGINT or SIGTERM,
then let the node finalize (close its recording) before rclpy shuts down."""

from __future__ import annotations

import signal
import sys
from typing import Callable

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node


class Terminated(Exception):
    """Raised in the main thread when SIGTERM arrives."""


def _on_sigterm(_signum, _frame) -> None:
    raise Terminated()


def run_node(make_node: Callable[[], Node], program: str, threads: int = 4, args: list[str] | None = None) -> int:
    """Create the node with ``make_node`` and spin it; returns the process exit status.

    The SIGTERM handler is installed before ``rclpy.init``, which chains its own handler to it,
    so SIGTERM ends the spin like SIGINT does and ``node.close()`` always runs. A ``ValueError``
    while creating the node (a bad parameter) is reported on one line with status 2.
    """
    signal.signal(signal.SIGTERM, _on_sigterm)
    rclpy.init(args=args)
    node = None
    try:
        node = make_node()
        executor = MultiThreadedExecutor(num_threads=threads)
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException, Terminated):
        pass
    except ValueError as exc:
        print(f"{program}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        if node is not None:
            node.close()
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
