"""Running a node as a process: check the command line, spin until SIGINT, SIGTERM or the node
asks to exit, then let the node finalize (close its recording) before rclpy shuts down.

The spin is ``spin_once`` with a short timeout in a loop that checks a stop flag set by this
module's own SIGINT/SIGTERM handlers (rclpy's are not installed): a plain ``spin`` can stay
in ``rcl_wait`` after a signal. Callbacks run on a pool of threads, but those of the callback
groups a node names in ``inline_callback_groups``, which run in the spinning thread: handing a
short callback (a cached service answer) to the pool costs more than the callback. Stopping takes at most ``SPIN_PERIOD`` plus the node's
``close``; callbacks still running then (a solve in flight) are not waited for beyond
``GRACE`` s. The process then ends at once (``os._exit``, output flushed), its recording
finished and rclpy shut down: the interpreter's and the middleware's teardown after that (a
second and more on a loaded machine: the middleware's exit handlers) would only delay the stop
(Fast DDS clears a dead process's shared-memory files when the next participant starts).

Bad input never starts the node: ``--help`` prints the parameters; unknown arguments, a ROS
parameters file that is not a readable, small, well-formed YAML file, an argument rcl cannot
parse, or a bad parameter value (``ValueError`` while creating the node) are one line on stderr
and exit status 2.
"""

from __future__ import annotations

import os
import re
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy
import rclpy.logging
from rclpy.callback_groups import CallbackGroup
from rclpy.executors import (ConditionReachedException, ExternalShutdownException, MultiThreadedExecutor,
                             ShutdownException, TimeoutException)
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from ..recording.writer import RecordingError
from .parameters import Param, check_parameters_file, help_text

SPIN_PERIOD = 0.1  # s: the longest a stop request waits for the spin loop
GRACE = 0.5  # s: how long callbacks still running at a stop are waited for


@dataclass(frozen=True)
class Usage:
    """What ``--help`` says of a node's entry point: a summary and its parameters."""

    summary: str
    params: Sequence[Param]


def _ros_params_files(argv: Sequence[str]) -> list[str]:
    """The files given with ``--params-file`` inside ``--ros-args``."""
    files, inside = [], False
    for arg, following in zip(argv, [*argv[1:], None]):
        if arg == "--ros-args":
            inside = True
        elif arg == "--":
            inside = False
        elif inside and arg == "--params-file" and following is not None:
            files.append(following)
    return files


@contextmanager
def _rcl_quiet() -> Iterator[None]:
    """Hold back what rcl prints on stderr while it parses the arguments (shown afterwards if
    the block succeeds), and turn its failure into a one-line ``ValueError``."""
    saved = os.dup(2)
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        try:
            yield
        except Exception as exc:  # noqa: BLE001  rcl's RCLError: the arguments did not parse
            message = re.sub(r",? at \S+:\d+", "", str(exc)).strip()
            raise ValueError(f"bad ROS arguments: {message}") from None
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        held.seek(0)
        said = held.read()
    if said:
        os.write(2, said)


def check_command_line(program: str, argv: Sequence[str], usage: Usage | None) -> int | None:
    """An exit status if the command line is handled here (``--help``: 0; a bad argument or
    parameters file: 2, with one line on stderr), None if the node may start."""
    try:
        for path in _ros_params_files(argv):
            check_parameters_file(path)  # before rcl reads it (rcl reads any size, and fails on binary)
        with _rcl_quiet():
            extra = remove_ros_args(list(argv))[1:]
    except ValueError as exc:
        print(f"{program}: error: {exc}", file=sys.stderr)
        return 2
    if usage is not None:
        if "-h" in extra or "--help" in extra:
            print(help_text(program, usage.summary, usage.params))
            return 0
        if extra:
            print(f"{program}: error: unrecognized arguments: {' '.join(extra)} (parameters go after --ros-args, "
                  "see --help)", file=sys.stderr)
            return 2
    return None


def _stop_on_signals(stop: threading.Event) -> None:
    def handler(_signum, _frame) -> None:
        stop.set()

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, handler)


class InlineExecutor(MultiThreadedExecutor):
    """A multi-threaded executor that runs the callbacks of the ``inline`` groups in the thread
    that spins it, and the others on its pool, as ``MultiThreadedExecutor`` does."""

    def __init__(self, inline: Sequence[CallbackGroup], num_threads: int) -> None:
        super().__init__(num_threads=num_threads)
        self._inline = set(inline)

    def _spin_once_impl(self, timeout_sec=None, wait_condition=lambda: False) -> None:
        if not self._inline:
            return super()._spin_once_impl(timeout_sec, wait_condition)
        try:
            handler, entity, _node = self.wait_for_ready_callbacks(timeout_sec, None, wait_condition)
        except (ExternalShutdownException, ShutdownException, TimeoutException, ConditionReachedException):
            return None
        if getattr(entity, "callback_group", None) in self._inline:
            handler()
            handler.result()  # raise its exception, if any
            return None
        self._executor.submit(handler)  # MultiThreadedExecutor's pool and futures
        self._futures.append(handler)
        for future in [f for f in self._futures if f.done()]:
            self._futures.remove(future)
            future.result()
        return None


def _spin(node: Node, stop: threading.Event, threads: int) -> MultiThreadedExecutor:
    """Spin ``node`` until ``stop``, the node's ``exit_requested`` event, or the context's end."""
    executor = InlineExecutor(getattr(node, "inline_callback_groups", ()), num_threads=threads)
    executor.add_node(node)
    exit_requested = getattr(node, "exit_requested", threading.Event())
    try:
        while not stop.is_set() and not exit_requested.is_set() and node.context.ok():
            executor.spin_once(timeout_sec=SPIN_PERIOD)
    except ExternalShutdownException:
        pass
    return executor


def _close(node: Node, program: str) -> None:
    """The node's ``close`` (finalize its recording); a recording failure is one log line."""
    try:
        node.close()
    except RecordingError as exc:
        rclpy.logging.get_logger(program).error(str(exc))


def _end_threads(executor: MultiThreadedExecutor | None) -> None:
    """Let the executor's idle threads end and wait up to ``GRACE`` s for busy ones."""
    pool = getattr(executor, "_executor", None)  # rclpy's ThreadPoolExecutor (no public handle)
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + GRACE
    for thread in threading.enumerate():
        if thread is not threading.main_thread() and not thread.daemon:
            thread.join(max(0.0, deadline - time.monotonic()))


def run_node(make_node: Callable[[], Node], program: str, threads: int = 4, args: list[str] | None = None,
             usage: Usage | None = None) -> int:
    """Check the command line (``usage``: the entry point takes no arguments of its own, and
    answers ``--help``), create the node with ``make_node`` and spin it; returns the exit
    status: 2 for bad input, else the node's ``exit_status`` (0 if it has none). A node may
    have ``exit_requested`` (a ``threading.Event``) to end the spin and ``inline_callback_groups``
    (run in the spinning thread), and must have ``close()``. Once rclpy has started, the process ends here (``os._exit`` with that status, see the
    module): call it from an entry point, not from a process that goes on."""
    argv = list(sys.argv if args is None else args)
    status = check_command_line(program, argv, usage)
    if status is not None:
        return status
    stop = threading.Event()
    _stop_on_signals(stop)
    node = executor = None
    try:
        with _rcl_quiet():
            rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
        node = make_node()
        executor = _spin(node, stop, threads)
    except ValueError as exc:
        print(f"{program}: error: {exc}", file=sys.stderr)
        status = 2
    finally:
        if node is not None:
            _close(node, program)
            status = status if status is not None else getattr(node, "exit_status", 0)
        if executor is not None:
            executor.shutdown(timeout_sec=0)
            _end_threads(executor)  # before the node's handles go: a callback ending now still has them
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
