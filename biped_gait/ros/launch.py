"""``biped-gait-launch``: the planner and the simulator as separate processes, like a ROS 2
launch file (the launch package is not installable here).

Both nodes get ``--ros-args --params-file CONFIG`` (a ROS 2 parameters file with a section per
node), checked first (size, UTF-8, nesting, the shape rcl expects: a bad one is one line and
exit status 2, no node started). The simulator gets ``exit_when_done: true`` unless the file
says otherwise, so a walk of ``steps`` steps ends the launch. Ctrl-C and SIGTERM are forwarded
to both; when the simulator ends, the planner is stopped, and when the planner ends, the
simulator is. Exit status: 0 if both ended cleanly, 130 after Ctrl-C or SIGTERM, else the first
non-zero status. ``--analyze`` then runs ``biped-gait-analyze`` on the new walk recording.
``--record-dir DIR`` has both nodes record under DIR (their ``record_dir``, over the file's);
without it they record where the file says (else ``bags``), and ``--analyze`` looks there.
``--live-view [PORT]`` has the simulator serve a Foxglove live view (``live_view``) on that port.
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from ..arguments import OneLineParser
from ..recording import topics
from .environment import keep_discovery_local
from .live_view import DEFAULT_PORT
from .parameters import PARAMS_KEY, check_parameters_file

PLANNER, SIMULATOR = "biped-gait-planner", "biped-gait-simulator"


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="biped-gait-launch", description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=Path, help="ROS 2 parameters file with biped_gait_planner and "
                        "biped_gait_simulator sections (default: the nodes' own defaults)")
    parser.add_argument("--analyze", action="store_true", help="analyse the simulator's recording afterwards")
    parser.add_argument("--record-dir", type=Path, metavar="DIR",
                        help="both nodes record under DIR (their record_dir parameter, over the config's); default: "
                        "the config's simulator record_dir, else bags")
    parser.add_argument("--live-view", type=int, nargs="?", const=DEFAULT_PORT, metavar="PORT",
                        help="the simulator serves a Foxglove live view on ws://127.0.0.1:PORT "
                        f"(default {DEFAULT_PORT})")
    return parser


def start_entry(entry: str, ros_args: list[str] = (), log: Path | None = None, cwd: Path | None = None,
                own_session: bool = False) -> subprocess.Popen:
    """Start the entry point ``entry`` (e.g. ``biped-gait-planner``) of this environment with
    ``--ros-args ros_args``; its output goes to the file ``log`` if given (never to a pipe
    nobody reads), else to ours. ``own_session``: in a process group of its own, so that a
    terminal's Ctrl-C reaches only the caller, which forwards it."""
    exe = shutil.which(entry, path=str(Path(sys.executable).parent)) or shutil.which(entry)
    if exe is None:
        raise FileNotFoundError(f"entry point {entry} is not installed")
    args = [exe] + (["--ros-args", *ros_args] if ros_args else [])
    out = open(log, "wb") if log is not None else None
    try:
        return subprocess.Popen(args, cwd=cwd, env=dict(os.environ), stdout=out, stderr=subprocess.STDOUT if out else None,
                                start_new_session=own_session)
    finally:
        if out is not None:
            out.close()


def stop_process(proc: subprocess.Popen, sig: int = signal.SIGINT, timeout: float = 20.0) -> int:
    """Send ``sig`` to a node process and wait for it; kill it if it hangs. Returns its status."""
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode


def main(argv: list[str] | None = None) -> int:
    """Run the two nodes; returns the exit status (non-zero if one of them failed)."""
    args = build_parser().parse_args(argv)
    if args.config is not None and not args.config.is_file():
        print(f"biped-gait-launch: error: no config file {args.config}", file=sys.stderr)
        return 2
    try:
        document = check_parameters_file(args.config) if args.config is not None else {}
    except ValueError as exc:
        print(f"biped-gait-launch: error: {exc}", file=sys.stderr)
        return 2
    keep_discovery_local()
    sections = {node.strip("/"): section.get(PARAMS_KEY, {}) for node, section in document.items()}
    record_dir = args.record_dir or Path(str(sections.get("biped_gait_simulator", {}).get("record_dir",
                                                                                        topics.RECORD_DIR)))
    before = set(record_dir.glob("walk_*")) if record_dir.is_dir() else set()
    stopping = []

    def forward(signum, _frame) -> None:
        stopping.append(signum)

    previous = {sig: signal.signal(sig, forward) for sig in (signal.SIGINT, signal.SIGTERM)}
    # -p after the file wins over it (rcl: a -p before it would lose even when after it): the options
    # over the file's values; the launcher's exit_when_done only where the file does not set it
    ros_args = ["--params-file", str(args.config)] if args.config else []
    recording = ["-p", f"record_dir:={args.record_dir}"] if args.record_dir is not None else []
    planner = start_entry(PLANNER, [*ros_args, *recording], own_session=True)
    ending = [] if "exit_when_done" in sections.get("biped_gait_simulator", {}) else ["-p", "exit_when_done:=true"]
    live = [] if args.live_view is None else ["-p", "live_view:=true", "-p", f"live_view_port:={args.live_view}"]
    simulator = start_entry(SIMULATOR, [*ros_args, *ending, *live, *recording], own_session=True)
    try:
        while simulator.poll() is None and planner.poll() is None and not stopping:
            time.sleep(0.05)
    finally:
        sim_status = stop_process(simulator)
        planner_status = stop_process(planner)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    statuses = {SIMULATOR: sim_status, PLANNER: planner_status}
    failed = {name: code for name, code in statuses.items() if code != 0}
    if failed:
        print("biped-gait-launch: " + ", ".join(f"{n} exited with status {c}" for n, c in failed.items()), file=sys.stderr)
        return next(iter(failed.values())) if not stopping else 130
    if stopping:
        return 130
    if args.analyze:
        new = sorted(set(record_dir.glob("walk_*")) - before)
        if not new:
            print("biped-gait-launch: error: the simulator left no new recording to analyse", file=sys.stderr)
            return 1
        from ..analysis.cli import main as analyze

        return analyze([str(new[-1])])
    return 0
