"""The nodes under faults, load and bad input, over Fast DDS: SIGINT and SIGTERM during requests
and during walks (each stop within 2 s, status 0, the recording finished with its QoS), a
burst of 8 x 100 requests all answered, a full disk (a small tmpfs, when this machine lets the
test mount one), an unwritable or deleted bag folder, NaN goals, a 100 kB string, a plan that
names a file on the wire, a topic with no publisher, and the launcher without a config.

Nodes are started in small batches so that discovery and start-up overlap. Every figure the
issue asks for is printed (run with -s to see them)."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import math
import shutil
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import yaml
from rclpy.action import ActionClient
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState

from biped_gait.recording.recover import is_complete
from biped_gait.ros.client import ClientSide, optimize_goal, plan_request
from biped_gait.ros.qos import LATCHED
from biped_gait_interfaces.action import OptimizeArmSwing
from biped_gait_interfaces.msg import GaitEvent, GaitPlan
from biped_gait_interfaces.srv import PlanGait

from .ros_helpers import read_bag, start_node, start_simulator as simulator, stop_node

pytestmark = [pytest.mark.faults, pytest.mark.ros]

STOP_WITHIN = 2.0  # s from the signal to the process's end
ROUNDS = 10  # per signal and per situation: 2 signals x 2 situations x 10 = 40 stops
BATCH = 4  # nodes started at once
PLANNER_LOGS: dict[str, Path] = {}  # the module's planner's log, by node name (for a failure's message)
WALKERS = 2  # simulators walking in real time at once: one a core (more, and a stop times the scheduler)


def log_of(where: Path, entry: str) -> str:
    return (where / f"{entry}.log").read_text(errors="replace")


def finished_recording(bags: Path) -> bool:
    """One recording under ``bags``, finalized, with metadata.yaml giving every topic its QoS."""
    [bag] = list(bags.iterdir())
    [mcap] = list(bag.glob("*.mcap"))
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    topics = info["topics_with_message_count"]
    return is_complete(mcap) and bool(topics) and all(t["topic_metadata"]["offered_qos_profiles"] for t in topics)


def signal_and_time(proc: subprocess.Popen, sig: int) -> tuple[int, float]:
    """Send ``sig``; the exit status and the seconds it took (killed after 20 s: status -9)."""
    start = time.monotonic()
    status = stop_node(proc, sig, timeout=20.0)
    return status, time.monotonic() - start


def batches(tmp_path: Path, start, size: int = BATCH) -> Iterator[list[tuple[Path, object]]]:
    """``ROUNDS`` rounds in batches of ``size``: each round a folder of its own and what
    ``start(folder)`` returns for it (a process, or a (name, process) pair). A batch whose test
    fails has its processes still running killed, so that they do not walk on into the next
    tests of this worker's ROS domain."""
    for first in range(0, ROUNDS, size):
        rounds = []
        try:
            for i in range(first, min(first + size, ROUNDS)):
                where = tmp_path / f"round{i}"
                where.mkdir()
                rounds.append((where, start(where)))
            yield rounds
        finally:
            for _, started in rounds:
                proc = started[1] if isinstance(started, tuple) else started
                if proc.poll() is None:
                    proc.kill()
                    proc.wait(timeout=30)


def wait_for(condition, timeout: float, what: str, logs: tuple[Path, ...] = ()) -> None:
    """Wait until ``condition()``; after ``timeout`` s a TimeoutError saying ``what``, with the
    last lines of each log in ``logs`` (what the nodes were doing: discovery, retries)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            tails = "".join(f"\n--- {log}:\n" + "\n".join(log.read_text(errors="replace").splitlines()[-40:])
                            for log in logs if log.exists())
            raise TimeoutError(what + tails)
        time.sleep(0.05)


@pytest.fixture(scope="module")
def side():
    client_side = ClientSide(f"faults_client_{uuid.uuid4().hex[:6]}")
    yield client_side
    client_side.close()


@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    """A planner of this module's own (not recording), for the simulators and the burst."""
    where = tmp_path_factory.mktemp("faults_planner")
    name = f"faults_planner_{uuid.uuid4().hex[:6]}"
    proc = start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", "record:=false", cwd=where)
    PLANNER_LOGS[name] = where / "biped-gait-planner.log"
    yield name
    assert stop_node(proc) == 0, log_of(where, "biped-gait-planner")


# Signals ------------------------------------------------------------------------------------
@pytest.mark.paced
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_the_planner_stops_cleanly_during_requests(side, tmp_path, sig):
    """Each round: a recording planner busy with an optimization and a queue of uncached
    requests gets the signal; it ends within 2 s with status 0 and a finished recording."""
    def start(where: Path) -> tuple[str, subprocess.Popen]:
        name = f"faults_stop_planner_{uuid.uuid4().hex[:6]}"
        return name, start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", f"record_dir:={where / 'bags'}",
                                cwd=where)

    results = []
    for rounds in batches(tmp_path, start):
        clients = [(side.node.create_client(PlanGait, f"/{name}/plan_gait"),
                    ActionClient(side.node, OptimizeArmSwing, f"/{name}/optimize_arm_swing"))
                   for _, (name, _) in rounds]
        side.connect_all([client for client, _ in clients])
        for _, action in clients:
            assert action.wait_for_server(timeout_sec=30.0)
        for client, action in clients:
            action.send_goal_async(optimize_goal(step_length=0.45, period=0.45, alpha_min=0.0, alpha_max=0.78))
            for k in range(30):
                client.call_async(plan_request(step_length=0.45, period=0.45, arm_amplitude=0.2 + 0.01 * k))
        settle = time.monotonic() + 0.5  # the requests reach the nodes, which start solving
        side.wait(lambda: time.monotonic() > settle)
        for where, (_, proc) in rounds:
            status, took = signal_and_time(proc, sig)
            log = log_of(where, "biped-gait-planner")
            results.append((status, took, finished_recording(where / "bags"), "Traceback" not in log))
        for client, action in clients:
            side.node.destroy_client(client)
            action.destroy()
    clean = sum(status == 0 and took < STOP_WITHIN and done and quiet for status, took, done, quiet in results)
    print(f"\nplanner, {signal.Signals(sig).name} during requests: {clean} of {len(results)} clean stops; "
          f"slowest {max(t for _, t, _, _ in results):.2f} s")
    assert clean == ROUNDS, results


@pytest.mark.paced
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_the_simulator_stops_cleanly_during_walks(planner, side, tmp_path, sig):
    """Each round: a simulator walking in real time, with a live subscriber of its joint states,
    gets the signal once it walks; it ends within 2 s, status 0, file finished."""
    subscription = side.node.create_subscription(JointState, "/joint_states", lambda _msg: None, 10)
    results = []
    start = lambda where: simulator(where, planner, "steps:=0", "real_time_factor:=1.0", "chunk_size:=4096")  # noqa: E731
    for rounds in batches(tmp_path, start, WALKERS):
        for where, proc in rounds:
            wait_for(lambda: "walking L =" in log_of(where, "biped-gait-simulator") or proc.poll() is not None, 90.0,
                     "the walk did not start", (where / "biped-gait-simulator.log", PLANNER_LOGS[planner]))
        settle = time.monotonic() + 0.3
        side.wait(lambda: time.monotonic() > settle)
        for where, proc in rounds:
            status, took = signal_and_time(proc, sig)
            log = log_of(where, "biped-gait-simulator")
            results.append((status, took, finished_recording(where / "bags"), "Traceback" not in log))
    side.node.destroy_subscription(subscription)
    clean = sum(status == 0 and took < STOP_WITHIN and done and quiet for status, took, done, quiet in results)
    print(f"\nsimulator, {signal.Signals(sig).name} during walks: {clean} of {len(results)} clean stops; "
          f"slowest {max(t for _, t, _, _ in results):.2f} s")
    assert clean == ROUNDS, results


# Load ---------------------------------------------------------------------------------------
def test_a_burst_of_800_requests_is_all_answered(planner, side):
    """8 clients send 100 requests each at once (one refused in ten: a NaN step length)."""
    service = f"/{planner}/plan_gait"
    clients = [side.node.create_client(PlanGait, service, qos_profile=QoSProfile(depth=1000)) for _ in range(8)]
    for client in clients:
        side.connect(client)
    good = plan_request(step_length=0.45, period=0.45, arm_amplitude=0.41)
    assert side.call(clients[0], good).success  # solved once: the burst is answered from the cache
    bad = plan_request(step_length=math.nan, period=0.45, arm_amplitude=0.41)
    started = time.monotonic()
    futures = [c.call_async(bad if k % 10 == 9 else good) for k in range(100) for c in clients]
    try:
        side.wait(lambda: all(f.done() for f in futures), timeout=120.0)
    except TimeoutError:
        pass
    answered = [f.result() for f in futures if f.done()]
    print(f"\nburst: {len(answered)} of {len(futures)} requests answered in {time.monotonic() - started:.1f} s")
    assert len(answered) == 800
    assert sum(r.success for r in answered) == 720 and sum("finite" in r.message for r in answered) == 80
    for client in clients:
        side.node.destroy_client(client)


def test_nan_goals_are_aborted_with_a_reason(planner, side):
    action = ActionClient(side.node, OptimizeArmSwing, f"/{planner}/optimize_arm_swing")
    assert action.wait_for_server(timeout_sec=30.0)
    for goal, reason in [(optimize_goal(step_length=math.nan, period=0.45, alpha_max=0.7), "step_length"),
                         (optimize_goal(step_length=0.45, period=0.45, alpha_max=math.inf), "alpha_max"),
                         (optimize_goal(step_length=0.45, period=0.45, alpha_min=0.5, alpha_max=0.2), "range")]:
        sent = action.send_goal_async(goal)
        side.wait(sent.done)
        result = sent.result().get_result_async()
        side.wait(result.done)
        answer = result.result().result
        assert not answer.success and reason in answer.message, answer.message
    action.destroy()


def test_a_100_kb_string_is_clipped_in_the_log(tmp_path, side):
    name = f"faults_long_planner_{uuid.uuid4().hex[:6]}"
    proc = start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", "record:=false", cwd=tmp_path)
    try:
        client = side.node.create_client(PlanGait, f"/{name}/plan_gait")
        side.connect(client)
        response = side.call(client, plan_request(step_length=0.45, period=0.45, arm_amplitude=0.4,
                                                      params="x" * 100_000))
        assert not response.success and len(response.message) < 1000
    finally:
        assert stop_node(proc) == 0
    log = log_of(tmp_path, "biped-gait-planner")
    assert "plan_gait refused: unknown parameter set" in log and max(len(line) for line in log.splitlines()) < 1000


# Recording failures ---------------------------------------------------------------------------
@contextmanager
def small_tmpfs(where: Path, size: str):
    """A tmpfs of ``size`` at ``where``; skips the test where mounting is not allowed."""
    where.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)],
                             capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({mounted.stderr.strip()}); tests/test_faults_recording.py "
                    "fills a disk with a file object instead")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


def test_a_full_disk_ends_the_walk_as_recording_failed(planner, tmp_path):
    with small_tmpfs(tmp_path / "disk", "1m") as disk:
        proc = simulator(tmp_path, planner, "steps:=0", "real_time_factor:=0.0", "exit_when_done:=true",
                         f"record_dir:={disk}", "chunk_size:=16384")
        assert proc.wait(timeout=120) == 1
        log = log_of(tmp_path, "biped-gait-simulator")
        assert "the walk ended: recording failed:" in log and "No space left on device" in log
        assert "fell" not in log and "Traceback" not in log
        [bag] = list(disk.iterdir())
        assert is_complete(next(bag.glob("*.mcap"))) and (bag / "metadata.yaml").is_file()
        events = [m for _, m in read_bag(bag)["/gait_events"]]
        assert all(e.kind == GaitEvent.TOUCHDOWN for e in events)


def test_a_full_disk_leaves_the_planner_serving(side, tmp_path):
    with small_tmpfs(tmp_path / "disk", "600k") as disk:
        name = f"faults_full_planner_{uuid.uuid4().hex[:6]}"
        proc = start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", f"record_dir:={disk}", cwd=tmp_path)
        try:
            client = side.node.create_client(PlanGait, f"/{name}/plan_gait")
            side.connect(client)
            answers = [side.call(client, plan_request(step_length=0.45, period=0.45, arm_amplitude=0.2 + 0.002 * k))
                       for k in range(40)]  # ~30 kB recorded per call
            assert all(a.success for a in answers)
        finally:
            assert stop_node(proc) == 0
        log = log_of(tmp_path, "biped-gait-planner")
        assert log.count("recording failed:") == 1 and "serving without recording" in log and "Traceback" not in log
        [bag] = list(disk.iterdir())
        assert is_complete(next(bag.glob("*.mcap")))


def test_an_unwritable_record_dir(planner, side, tmp_path):
    """The planner serves without recording; the simulator does not start (status 1)."""
    (tmp_path / "a_file").write_text("")
    unwritable = tmp_path / "a_file" / "bags"
    name = f"faults_nodir_planner_{uuid.uuid4().hex[:6]}"
    proc = start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", f"record_dir:={unwritable}", cwd=tmp_path)
    try:
        client = side.node.create_client(PlanGait, f"/{name}/plan_gait")
        side.connect(client)
        assert side.call(client, plan_request(step_length=0.45, period=0.45, arm_amplitude=0.41)).success
    finally:
        assert stop_node(proc) == 0
    log = log_of(tmp_path, "biped-gait-planner")
    assert "recording failed: cannot create" in log and "Traceback" not in log
    sim = simulator(tmp_path, planner, "exit_when_done:=true", f"record_dir:={unwritable}")
    assert sim.wait(timeout=60) == 1
    log = log_of(tmp_path, "biped-gait-simulator")
    assert "the walk did not start: recording failed: cannot create" in log and "Traceback" not in log


def test_a_bag_folder_deleted_during_a_walk(planner, tmp_path):
    proc = simulator(tmp_path, planner, "steps:=0", "real_time_factor:=1.0", "exit_when_done:=true", "chunk_size:=2048")
    wait_for(lambda: "walking L =" in log_of(tmp_path, "biped-gait-simulator"), 90.0, "no walk")
    shutil.rmtree(tmp_path / "bags")
    assert proc.wait(timeout=30) == 1
    log = log_of(tmp_path, "biped-gait-simulator")
    assert "the walk ended: recording failed:" in log and "was deleted while recording" in log
    assert "fell" not in log and "Traceback" not in log


# Waits and the wire ---------------------------------------------------------------------------
def test_a_topic_without_publisher_is_waited_for_aloud_then_given_up(tmp_path):
    proc = start_node("biped-gait-simulator", "-p", "plan_source:=topic", "-p", f"plan_topic:=/nobody_{uuid.uuid4().hex[:6]}",
                      "-p", "wait_timeout:=6.0", "-p", "exit_when_done:=true", "-p", "record:=false", cwd=tmp_path)
    assert proc.wait(timeout=60) == 1
    log = log_of(tmp_path, "biped-gait-simulator")
    assert "waiting for a GaitPlan on /nobody_" in log and "nothing after 6 s" in log


@pytest.mark.parametrize("wire_params", ["/etc/hostname", "../../secret.yaml"])
def test_a_plan_naming_a_file_is_refused(side, tmp_path, wire_params):
    topic = f"/wire_plans_{uuid.uuid4().hex[:6]}"
    publisher = side.node.create_publisher(GaitPlan, topic, LATCHED)
    publisher.publish(GaitPlan(params=wire_params, converged=True, step_length=0.45, period=0.45))
    proc = start_node("biped-gait-simulator", "-p", "plan_source:=topic", "-p", f"plan_topic:={topic}",
                      "-p", "exit_when_done:=true", "-p", f"record_dir:={tmp_path / 'bags'}", cwd=tmp_path)
    try:
        wait_for(lambda: proc.poll() is not None, 60.0, "the simulator did not end",
                 (tmp_path / "biped-gait-simulator.log",))
        side.wait(lambda: True)
    finally:
        side.node.destroy_publisher(publisher)
    assert proc.returncode == 1
    log = log_of(tmp_path, "biped-gait-simulator")
    assert "is neither a shipped set" in log and "Traceback" not in log
    [bag] = list((tmp_path / "bags").iterdir())
    [(_, event)] = read_bag(bag)["/gait_events"]
    assert event.kind == GaitEvent.NOT_STARTED and "refused" in event.message


def test_the_launcher_without_a_config_stands_until_stopped(tmp_path):
    """The nodes' defaults: the simulator stands (its initial_state), waiting for /cmd_vel, until
    Ctrl-C, which ends both nodes (status 130) with their recordings finished."""
    launch = shutil.which("biped-gait-launch", path=str(Path(sys.executable).parent))
    out = tmp_path / "launch.log"
    with open(out, "wb") as sink:
        proc = subprocess.Popen([launch], cwd=tmp_path, stdout=sink, stderr=subprocess.STDOUT)
    try:
        wait_for(lambda: "standing for as long as the node runs" in out.read_text() or proc.poll() is not None,
                 90.0, "the robot did not stand", (out,))
        assert proc.poll() is None, out.read_text()[-2000:]
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=60) == 130, out.read_text()[-2000:]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    mcaps = list((tmp_path / "bags").glob("*/*.mcap"))
    assert len(mcaps) == 2 and all(is_complete(m) for m in mcaps)
