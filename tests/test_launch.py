"""``biped-gait-launch``: both nodes as processes from one parameters file; a walk that ends by
itself, and Ctrl-C forwarded to both with their recordings finalized."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import yaml

from biped_gait.recording.recover import is_complete

pytestmark = pytest.mark.ros

LAUNCH = shutil.which("biped-gait-launch", path=str(Path(sys.executable).parent))


def config(tmp_path: Path, **simulator) -> Path:
    params = {
        "biped_gait_planner": {"ros__parameters": {"record": True, "record_dir": str(tmp_path / "bags")}},
        "biped_gait_simulator": {"ros__parameters": {
            "record": True, "record_dir": str(tmp_path / "bags"), "exit_when_done": True, "initial_state": "walking",
            **simulator}},
    }
    path = tmp_path / "launch.yaml"
    path.write_text(yaml.safe_dump(params))
    return path


def test_a_walk_that_ends_stops_both_nodes(tmp_path):
    """Both nodes record under --record-dir (over the file's record_dir), where --analyze finds the walk."""
    cfg = config(tmp_path, steps=2, real_time_factor=0.0, arm_amplitude=0.41)
    chosen = tmp_path / "chosen"
    proc = subprocess.run([LAUNCH, "--config", str(cfg), "--record-dir", str(chosen), "--analyze"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert not (tmp_path / "bags").exists()
    bags = sorted(p.name.split("_")[0] for p in chosen.iterdir())
    assert bags == ["planner", "walk"]
    for bag in chosen.iterdir():
        assert is_complete(next(bag.glob("*.mcap"))), bag
    assert "walk: 2 steps" in proc.stdout and next(chosen.glob("walk_*/analysis/summary.md")).is_file()


def test_ctrl_c_is_forwarded_and_recordings_are_finalized(tmp_path):
    cfg = config(tmp_path, steps=0, real_time_factor=1.0, arm_amplitude=0.41)
    proc = subprocess.Popen([LAUNCH, "--config", str(cfg)], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(list((tmp_path / "bags").glob("*/*.mcap"))) < 2:
        time.sleep(0.2)
    time.sleep(2.0)  # walking
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err[-2000:]
    mcaps = list((tmp_path / "bags").glob("*/*.mcap"))
    assert len(mcaps) == 2 and all(is_complete(m) for m in mcaps)


def test_a_missing_config_is_one_line_and_status_2(tmp_path):
    proc = subprocess.run([LAUNCH, "--config", str(tmp_path / "nope.yaml")], capture_output=True, text=True, timeout=30)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "no config file" in proc.stderr
