"""Bad input to every entry point: parameters of the wrong type or out of range, malformed
parameter and launch files (nested, huge, binary), unknown arguments, unwritable outputs, and a
crafted recording whose schema names a module that must not be imported. Each is one line on
stderr, nothing on stdout, exit status 2, and nothing started or computed."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from mcap.writer import Writer

from biped_gait.ros.replay import message_class

pytestmark = [pytest.mark.faults, pytest.mark.ros]

BIN = Path(sys.executable).parent
HUGE = 150 * 1024 * 1024  # bytes (a sparse file: nothing is written to the disk)


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> Path:
    where = tmp_path_factory.mktemp("bad_files")
    (where / "nested.yaml").write_text("biped_gait_planner:\n  ros__parameters:\n    x: " + "[" * 5000 + "]" * 5000 + "\n")
    (where / "binary.yaml").write_bytes(bytes(range(256)) * 40)
    with open(where / "huge.yaml", "wb") as f:
        f.truncate(HUGE)
    (where / "flat.yaml").write_text("steps: 3\n")
    (where / "a_file").write_text("")
    (where / "full").mkdir()
    (where / "full" / "old.png").write_bytes(b"")
    return where


CASES = [
    # (entry point, arguments, what the line says)
    ("biped-gait-planner", ["--ros-args", "-p", "cache_size:=-1"], "parameter cache_size: must be in [0, 100000]"),
    ("biped-gait-planner", ["--ros-args", "-p", "bvp_tolerance:=nan"], "parameter bvp_tolerance: must be in"),
    ("biped-gait-planner", ["--ros-args", "-p", "record:=maybe"], "parameter record: expected true or false"),
    ("biped-gait-planner", ["--ros-args", "-p", "default_params:=nested.yaml"], "nested more than 32 levels"),
    ("biped-gait-planner", ["--ros-args", "--params-file", "binary.yaml"], "binary.yaml: not UTF-8 text"),
    ("biped-gait-planner", ["--ros-args", "--params-file", "huge.yaml"], f"{HUGE} bytes, more than"),
    ("biped-gait-planner", ["--ros-args", "--params-file", "nested.yaml"], "nested more than 32 levels"),
    ("biped-gait-planner", ["--ros-args", "--params-file", "flat.yaml"], "expected a mapping with ros__parameters"),
    ("biped-gait-planner", ["--ros-args", "-p"], "bad ROS arguments"),
    ("biped-gait-planner", ["--verbose"], "unrecognized arguments: --verbose"),
    ("biped-gait-simulator", ["--ros-args", "-p", "steps:=abc"], "parameter steps: expected an integer"),
    ("biped-gait-simulator", ["--ros-args", "-p", "period:=inf"], "period must be a finite number, got inf"),
    ("biped-gait-simulator", ["--ros-args", "-p", "arm_amplitude:=23.5"], "angles in rad here; the biped-gait command"),
    ("biped-gait-simulator", ["--ros-args", "-p", "foo:=1"], "unknown parameter foo for biped_gait_simulator"),
    ("biped-gait-planner", ["--ros-args", "-p", "foo:=1"], "unknown parameter foo for biped_gait_planner"),
    ("biped-gait-simulator", ["--ros-args", "-p", "friction:=-0.5"], "friction coefficient must be positive (or inf)"),
    ("biped-gait-simulator", ["--ros-args", "-p", "friction_margin:=0.7"], "friction margin must be in [0, 0.5)"),
    ("biped-gait-simulator", ["--ros-args", "-p", "closure:=loose"], "parameter closure: must be one of theta, slack"),
    ("biped-gait-simulator", ["--ros-args", "-p", "real_time_factor:=-1.0"], "parameter real_time_factor"),
    ("biped-gait-simulator", ["--ros-args", "-p", "mode:=hop"], "parameter mode: must be one of normal, anti-normal"),
    ("biped-gait-simulator", ["--ros-args", "-p", "plan_source:=radio"], "parameter plan_source"),
    ("biped-gait-simulator", ["--ros-args", "-p", "params:=/no/such.yaml"], "unknown parameter set '/no/such.yaml'"),
    ("biped-gait-simulator", ["--ros-args", "-p", "pushes:=4 0.5 1"], "parameter pushes: expected STEP PHASE PX PY PZ"),
    ("biped-gait-simulator", ["--ros-args", "-p", "pushes:=2 1.5 1 0 0"], "parameter pushes: the phase must be in [0, 1)"),
    ("biped-gait-simulator", ["--ros-args", "-p", "recovery:=prayer"], "parameter recovery: must be one of momentum"),
    ("biped-gait-simulator", ["--ros-args", "-p", "momentum_rate:=1.5"], "parameter momentum_rate: must be in [0, 0.99]"),
    ("biped-gait-simulator", ["--ros-args", "-p", "engine:=ode"], "parameter engine: must be one of hybrid, mujoco"),
    ("biped-gait-simulator", ["--ros-args", "-p", "pulse_duration:=0.0"], "parameter pulse_duration: must be in [0.0001, 0.1]"),
    ("biped-gait-simulator", ["--ros-args", "-p", "initial_state:=sitting"],
     "parameter initial_state: must be one of walking, standing"),
    ("biped-gait-simulator", ["--ros-args", "-p", "cmd_vel_timeout:=-1.0"], "parameter cmd_vel_timeout: must be in"),
    ("biped-gait-launch", ["--config", "binary.yaml"], "binary.yaml: not UTF-8 text"),
    ("biped-gait-launch", ["--config", "nested.yaml"], "nested more than 32 levels"),
    ("biped-gait-launch", ["--config", "huge.yaml"], "more than the 1048576 allowed"),
    ("biped-gait-launch", ["--config", "flat.yaml"], "expected a mapping with ros__parameters"),
    ("biped-gait-launch", ["--nodes", "3"], "unrecognized arguments: --nodes 3"),
    ("biped-gait", ["plan", "--params", "nested.yaml"], "nested more than 32 levels"),
    ("biped-gait", ["plan", "--params", "binary.yaml"], "not UTF-8 text"),
    ("biped-gait", ["plan", "--params", "huge.yaml"], "more than the 1048576 allowed"),
    ("biped-gait", ["plan", "--params", "x" * 5000], "more characters)"),
    ("biped-gait", ["plan", "--json", "a_file/gait.json"], "a_file is not a folder"),
    ("biped-gait", ["plan", "--json", "/proc/gait.json"], "cannot write in /proc"),
    ("biped-gait", ["sweep", "--out", "full", "--alpha-deg", "20"], "is not empty (an earlier run?)"),
    ("biped-gait", ["sweep", "--out", "a_file"], "is a file, not a folder"),
    ("biped-gait", ["sweep", "--workers", "0"], "the number of workers must be at least 1"),
    ("biped-gait", ["figure", "fig4", "--out", "a_file/fig4.png"], "a_file is not a folder"),
    ("biped-gait", ["urdf", "--out", "a_file/biped.urdf"], "a_file is not a folder"),
    ("biped-gait", ["recover", "binary.yaml"], "binary.yaml: not an MCAP file"),
]


@pytest.mark.parametrize("entry, args, message", CASES, ids=[f"{e} {' '.join(a)[:40]}" for e, a, _ in CASES])
def test_bad_input_is_one_line_and_status_2(files, entry, args, message):
    started = time.monotonic()
    done = subprocess.run([str(BIN / entry), *args], cwd=files, capture_output=True, text=True, timeout=60)
    took = time.monotonic() - started
    print(f"\n{entry} {' '.join(args)[:60]}: exit {done.returncode} in {took:.1f} s: {done.stderr.strip()[:150]}")
    assert done.returncode == 2, done.stderr[-1500:]
    assert done.stdout == "" and done.stderr.count("\n") == 1 and message in done.stderr, done.stderr[-1500:]
    assert done.stderr.startswith(f"{entry}: error: ")
    assert not (files / "bags").exists()  # no node started, nothing recorded


def test_node_help_describes_the_parameters_and_starts_nothing(tmp_path):
    done = subprocess.run([str(BIN / "biped-gait-simulator"), "--help"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0 and done.stderr == ""
    assert "arm_amplitude (default 0.41" in done.stdout and "(rad here; the biped-gait command takes degrees)" in done.stdout
    assert "wait_timeout" in done.stdout and "(s)" in done.stdout and not (tmp_path / "bags").exists()


def test_json_to_standard_output(tmp_path):
    done = subprocess.run([str(BIN / "biped-gait"), "plan", "--json", "-"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.lstrip().startswith("{") and "W = " in done.stderr
    assert not (tmp_path / "-").exists()


def test_sweep_force_replaces_an_earlier_sweeps_files(tmp_path):
    out = tmp_path / "sweep"
    out.mkdir()
    stale = out / "W_vs_alpha_L0.400_T0.450.png"
    stale.write_bytes(b"old")
    (out / "notes.txt").write_text("mine")
    done = subprocess.run([str(BIN / "biped-gait"), "sweep", "--out", str(out), "--alpha-deg", "20", "22", "--mode",
                           "normal", "--workers", "100000", "--force"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "capped to the" in done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["W_vs_alpha_L0.450_T0.450.png", "notes.txt", "sweep.csv",
                                                     "sweep.json"]


def test_a_crafted_recording_never_imports_the_module_it_names(tmp_path):
    """The schema names ``trace_probe_pkg/msg/Thing``; a package of that name is on the replay's
    path and would write a file if imported. The replay refuses the type without importing it."""
    package = tmp_path / "lib" / "trace_probe_pkg"
    package.mkdir(parents=True)
    trace = tmp_path / "imported.txt"
    (package / "__init__.py").write_text(f"open({str(trace)!r}, 'w').write('imported')\n")
    (package / "msg.py").write_text(f"open({str(trace)!r}, 'w').write('imported')\nThing = object\n")
    with open(tmp_path / "crafted.mcap", "wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2")
        schema = writer.register_schema("trace_probe_pkg/msg/Thing", "ros2msg", b"int32 value\n")
        writer.add_message(writer.register_channel("/thing", "cdr", schema), 1, bytes([0, 1, 0, 0, 7, 0, 0, 0]), 1)
        writer.finish()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path / "lib"), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run([str(BIN / "biped-gait-replay"), "crafted.mcap"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 2 and "nothing to replay" in done.stderr and "trace_probe_pkg/msg/Thing" in done.stderr
    assert not trace.exists(), "the replay imported a module named by the file"
    sys.path.insert(0, str(tmp_path / "lib"))
    try:
        for name in ("trace_probe_pkg/msg/Thing", "os/path/join", "builtins/msg/eval", "std_msgs/msg/__class__"):
            assert message_class(name) is None
        assert "trace_probe_pkg" not in sys.modules and not trace.exists()
        assert message_class("sensor_msgs/msg/JointState").__name__ == "JointState"
    finally:
        sys.path.remove(str(tmp_path / "lib"))
    shutil.rmtree(tmp_path / "lib")
