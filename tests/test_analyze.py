"""biped-gait-analyze on recordings made once for the module by real nodes (a recording planner
of the test's own, one refused request, a 3-step walk): the summary holds what an independent
reader (rosbags) finds in the files, the plots are PNG images, bad input exits with status 2."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

from matplotlib.figure import Figure

from biped_gait.analysis.cli import main
from biped_gait.analysis.plots import _joint_figure
from biped_gait.analysis.summaries import read_walk
from biped_gait.recording.reader import open_bag
from biped_gait.ros.client import ClientSide, plan_request
from biped_gait_interfaces.srv import PlanGait

from .ros_helpers import read_bag  # rosbags: reads the files independently
from .walk_recording import own_planner, record_walk

pytestmark = pytest.mark.ros

PLANNER = "analyze_test_planner"
STEPS = 3
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
PLOTS = ("joint_angles.png", "yaw_momentum_two_steps.png", "com_feet_top_view.png")


@pytest.fixture(scope="module")
def recordings(tmp_path_factory) -> tuple[Path, Path]:
    """(walk recording, planner recording); the planner refused one request before the walk's."""
    where = tmp_path_factory.mktemp("analyze_walk")
    with own_planner(where, PLANNER, record=True):
        side = ClientSide("analyze_test_client")
        try:
            client = side.node.create_client(PlanGait, f"/{PLANNER}/plan_gait")
            side.connect(client)
            refused = side.call(client, plan_request(step_length=math.nan, period=0.45, arm_amplitude=0.41))
            assert not refused.success
        finally:
            side.close()
        walk = record_walk(where, PLANNER, STEPS)
    [planner] = list((where / "planner_bags").iterdir())
    return walk, planner


def analyzed(bag: Path, out: Path, capsys) -> tuple[dict, str]:
    assert main([str(bag), "--out", str(out)]) == 0
    return json.loads((out / "summary.json").read_text()), capsys.readouterr().out


def test_walk_summary_holds_what_the_recording_holds(recordings, tmp_path, capsys):
    walk, _ = recordings
    summary, printed = analyzed(walk, tmp_path, capsys)
    messages = read_bag(walk)
    first = min(stamp for topic in messages.values() for stamp, _ in topic)  # the recording's start
    start = min(messages[topic][0][0] for topic in ("/joint_states", "/angular_momentum"))  # the walk's: its first sample
    assert summary["walk_start"] == pytest.approx((start - first) * 1e-9, abs=1e-9)  # 0 here: nothing came before it
    walk_read = read_walk(open_bag(walk))  # the plots' time axis: from the walk's first sample, so labelled
    assert walk_read.joint_time[0] == 0.0 and min(walk_read.momentum_time) >= 0.0
    figure = Figure()
    _joint_figure(figure, walk_read)
    assert figure.axes[1].get_xlabel() == "time from the walk's start, its first sample (s)"
    events = [(stamp, e) for stamp, e in messages["/gait_events"]]
    touchdowns = [(stamp, e) for stamp, e in events if e.kind == 0]
    assert len(touchdowns) == STEPS and summary["walk"]["steps"] == STEPS
    assert summary["walk"]["effort_cost_per_step"] == [e.effort_cost for _, e in touchdowns]
    for step, (stamp, e) in zip(summary["walk"]["per_step"], touchdowns):
        assert step["step"] == e.step and step["touchdown_time"] == pytest.approx((stamp - start) * 1e-9, abs=1e-9)
        assert step["state_error"] == e.state_error and step["velocity_miss"] == e.velocity_miss
        assert step["time_in_step"] == e.time_in_step
    assert summary["walk"]["total_effort_cost"] == pytest.approx(sum(e.effort_cost for _, e in touchdowns), rel=1e-15)
    assert summary["walk"]["falls"] == [] and summary["walk"]["finished"] == f"walked {STEPS} steps"
    metadata = yaml.safe_load((walk / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    topics = {t["topic_metadata"]["name"]: {"type": t["topic_metadata"]["type"], "messages": t["message_count"]}
              for t in metadata["topics_with_message_count"]}
    assert summary["topics"] == topics
    assert {topic: len(msgs) for topic, msgs in messages.items()} == {t: v["messages"] for t, v in topics.items()}
    assert summary["duration"] == pytest.approx(metadata["duration"]["nanoseconds"] * 1e-9, abs=1e-9)
    assert summary["planner"] is None
    for name in PLOTS:
        data = (tmp_path / name).read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 10_000, name
        assert str(tmp_path / name) in printed
    assert f"walk: {STEPS} steps, finished" in printed and "W per step (N m s): " in printed
    markdown = (tmp_path / "summary.md").read_text()
    assert all(f"| {s} | " in markdown for s in range(STEPS)) and "![joint_angles](joint_angles.png)" in markdown


def test_planner_recording_summarizes_the_calls(recordings, tmp_path, capsys):
    _, planner = recordings
    summary, printed = analyzed(planner, tmp_path, capsys)
    calls = [call for _, call in read_bag(planner)[f"/{PLANNER}/plan_gait/calls"]]
    assert [c.success for c in calls] == [False, True]
    assert summary["planner"]["calls"] == 2 and summary["planner"]["successes"] == 1
    assert summary["planner"]["failures"] == [{"sequence": 1, "message": calls[0].message}]
    assert "step length must be a finite number" in calls[0].message
    [plan] = summary["planner"]["plans"]
    assert plan["effort_cost"] == calls[1].plan.effort_cost and plan["mode"] == "normal"
    assert summary["walk"] is None and summary["plots"] == []
    assert "planner: calls to plan_gait 2, succeeded 1, failed 1" in printed
    assert f"call 1 failed: {calls[0].message}" in printed


def test_command_on_a_bare_mcap_writes_beside_it(recordings, tmp_path):
    """The entry point, on a bare .mcap copied alone: default output <its directory>/analysis."""
    walk, _ = recordings
    [mcap] = walk.glob("*.mcap")
    shutil.copy(mcap, tmp_path / mcap.name)
    exe = Path(sys.executable).parent / "biped-gait-analyze"
    done = subprocess.run([str(exe), str(tmp_path / mcap.name)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert sorted(p.name for p in (tmp_path / "analysis").iterdir()) == sorted([*PLOTS, "summary.json", "summary.md"])
    assert f"summary: {tmp_path / 'analysis' / 'summary.json'}" in done.stdout


@pytest.mark.parametrize("name, message", [
    ("missing", "missing: no such file or directory"),
    ("text.mcap", "text.mcap: not an MCAP file"),
    ("empty_dir", "empty_dir: no .mcap file in this directory"),
    ("truncated.mcap", "truncated.mcap: the recording was not finalized (no MCAP summary)"),
])
def test_bad_input_is_one_line_and_status_2(recordings, tmp_path, capsys, name, message):
    walk, _ = recordings
    [mcap] = walk.glob("*.mcap")
    (tmp_path / "text.mcap").write_text("not a recording\n")
    (tmp_path / "empty_dir").mkdir()
    (tmp_path / "truncated.mcap").write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    assert main([str(tmp_path / name)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("biped-gait-analyze: error: ") and err.count("\n") == 1, err
    assert message in err
