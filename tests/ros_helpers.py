"""Helpers for tests over a real DDS middleware: node processes started from their entry
points, and a client side with its own rclpy context in the test process."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rosbags.highlevel import AnyReader

from biped_gait.ros.launch import stop_process

BIN = Path(sys.executable).parent


def start_node(entry: str, *ros_args: str, cwd: Path) -> subprocess.Popen:
    """Start an entry point (e.g. ``biped-gait-planner``) with ``--ros-args`` in its own process."""
    exe = shutil.which(entry, path=str(BIN))
    assert exe, f"entry point {entry} is not installed"
    args = [exe] + (["--ros-args", *ros_args] if ros_args else [])
    log = open(cwd / f"{entry}.log", "wb")
    return subprocess.Popen(args, cwd=cwd, stdout=log, stderr=subprocess.STDOUT, env=dict(os.environ))


def stop_node(proc: subprocess.Popen, sig: int = signal.SIGTERM, timeout: float = 20.0) -> int:
    """Send ``sig`` (default SIGTERM) and wait; returns the exit status (killed if it hangs)."""
    return stop_process(proc, sig, timeout)


def read_bag(bag_dir: Path) -> dict[str, list]:
    """Every message of a recording, by topic: [(log time ns, decoded message)], read by rosbags."""
    with AnyReader([bag_dir]) as reader:
        out: dict[str, list] = {}
        for conn, stamp, raw in reader.messages():
            out.setdefault(conn.topic, []).append((stamp, reader.deserialize(raw, conn.msgtype)))
    return out


class RosSide:
    """A client-side rclpy context, node and executor in the test process."""

    def __init__(self, name: str) -> None:
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def wait(self, done, timeout: float = 30.0) -> None:
        """Spin until ``done()`` is true; AssertionError after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while not done():
            assert time.monotonic() < deadline, "timed out waiting"
            self.executor.spin_once(timeout_sec=0.005)

    def connect(self, client, timeout: float = 30.0) -> None:
        """Wait for a service, then let discovery finish the server's side: a response sent
        before the server has matched this client's reader is lost (a DDS race)."""
        assert client.wait_for_service(timeout_sec=timeout), f"service {client.srv_name} did not appear"
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
