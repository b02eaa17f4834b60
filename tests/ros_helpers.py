"""Helpers for tests over a real DDS middleware: node processes started from their entry
points, and reading a recording with rosbags (an independent reader)."""

from __future__ import annotations

import signal
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rosbags.highlevel import AnyReader

from biped_gait.ros.launch import start_entry, stop_process


STARTED: list[subprocess.Popen] = []
"""Every node process the tests started, in order (``tests/conftest.py`` stops those a test left running)."""


def start_node(entry: str, *ros_args: str, cwd: Path) -> subprocess.Popen:
    """Start an entry point (e.g. ``biped-gait-planner``) with ``--ros-args`` in its own
    process, logging to ``cwd/<entry>.log``."""
    proc = start_entry(entry, list(ros_args), log=cwd / f"{entry}.log", cwd=cwd)
    STARTED.append(proc)
    return proc


@contextmanager
def planner_process(name: str, cwd: Path) -> Iterator[subprocess.Popen]:
    """A planner node named ``name``, not recording, stopped (status 0) at the end."""
    proc = start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", "record:=false", cwd=cwd)
    yield proc
    assert stop_node(proc) == 0


def start_simulator(where: Path, planner: str, *params: str, initial_state: str | None = "walking") -> subprocess.Popen:
    """A simulator asking the planner node named ``planner``, recording under ``where/bags``,
    with the parameters ``params`` ('name:=value'), logging to ``where``; it begins in
    ``initial_state`` (the walks of most tests: ``walking``, on the gait's orbit), None: the node's
    default (standing) or as ``params`` say."""
    args = ["-p", f"plan_service:=/{planner}/plan_gait", "-p", f"optimize_action:=/{planner}/optimize_arm_swing",
            "-p", f"record_dir:={where / 'bags'}"]
    if initial_state is not None:
        args += ["-p", f"initial_state:={initial_state}"]
    for p in params:
        args += ["-p", p]
    return start_node("biped-gait-simulator", *args, cwd=where)


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



def walk_recorded(where: Path, planner: str, steps: int, *params: str) -> dict[str, list]:
    """The recording (``read_bag``) of a simulator's walk of ``steps`` steps asking the planner node
    named ``planner``, with the parameters ``params``, as fast as it computes: its exit status 0,
    ``steps`` touchdowns and no fall."""
    from biped_gait_interfaces.msg import GaitEvent

    proc = start_simulator(where, planner, *params, f"steps:={steps}", "real_time_factor:=0.0", "exit_when_done:=true")
    assert proc.wait(timeout=600) == 0, (where / "biped-gait-simulator.log").read_text()[-2000:]
    [bag] = list((where / "bags").iterdir())
    recorded = read_bag(bag)
    events = [m for _, m in recorded["/gait_events"]]
    assert not [e for e in events if e.kind == GaitEvent.FALL]
    assert len([e for e in events if e.kind == GaitEvent.TOUCHDOWN]) == steps
    return recorded


def stamp(msg) -> float:
    """A message's header stamp (s)."""
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


def double_supports(recorded: dict[str, list]) -> list[tuple[float, float]]:
    """The spans (s, s) of a walk's double supports on /gait_phase: from each DOUBLE_STANCE to the
    phase after it."""
    from biped_gait_interfaces.msg import GaitPhase

    phases = [m for _, m in recorded["/gait_phase"]]
    return [(stamp(ds), stamp(after)) for ds, after in zip(phases, phases[1:]) if ds.phase == GaitPhase.DOUBLE_STANCE]
