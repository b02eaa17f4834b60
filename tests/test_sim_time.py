"""Time, frames, controls and the live view as ROS users expect them, over Fast DDS: /clock
advances with the simulation and nodes with use_sim_time (a subscriber's, the planner) follow
it; /tf is received live and is what was recorded, byte for byte; the recording's metadata
opens in rosbags with every topic's QoS and the type hashes rclpy reports; pause, resume and
reset; the Foxglove live view answers a plain websocket client, and what a client publishes on
/cmd_vel (as Foxglove's Teleop panel does) reaches the graph."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import asyncio
import json
import re
import struct
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Callable

import numpy as np
import rclpy
import websockets
import yaml
from geometry_msgs.msg import Twist
from mcap.reader import make_reader
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.serialization import deserialize_message
from rosbags.highlevel import AnyReader
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import String, UInt64
from std_srvs.srv import Trigger
from tf2_msgs.msg import TFMessage

from biped_gait.ros.client import ClientSide, plan_request
from biped_gait.ros.teleop import client_twist
from biped_gait_interfaces.msg import AngularMomentum
from biped_gait_interfaces.srv import PlanGait

from .ros_helpers import read_bag, start_node, start_simulator, stop_node
from .test_replay import same_messages

pytestmark = pytest.mark.ros

PLANNER = "sim_time_test_planner"
BEST_EFFORT = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)


def ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def simulator(where: Path, *params: str):
    return start_simulator(where, PLANNER, *params)


@pytest.fixture(scope="module")
def planner_node(tmp_path_factory):
    """A planner on simulated time (its plans' stamps follow /clock)."""
    where = tmp_path_factory.mktemp("sim_time_planner")
    proc = start_node("biped-gait-planner", "-r", f"__node:={PLANNER}", "-p", "record:=false", "-p", "use_sim_time:=true",
                      cwd=where)
    yield proc
    assert stop_node(proc) == 0


@pytest.fixture
def side():
    client_side = ClientSide("sim_time_listener")
    yield client_side
    client_side.close()


def test_clock_tf_and_the_recording_as_users_expect(planner_node, side, tmp_path):
    """Two steps in real time on simulated time from 0: /clock, a use_sim_time node's clock,
    /tf live against the recording, the metadata in rosbags, the planner's stamps."""
    user = rclpy.create_node("sim_time_user", context=side.context,
                             parameter_overrides=[Parameter("use_sim_time", value=True)])
    side.executor.add_node(user)
    clocks, tf, joints, seen_by_user = [], [], [], []
    side.node.create_subscription(Clock, "/clock", lambda m: clocks.append(ns(m.clock)), BEST_EFFORT)
    side.node.create_subscription(TFMessage, "/tf", lambda data: tf.append((data, 0)), QoSProfile(depth=5000), raw=True)
    side.node.create_subscription(JointState, "/joint_states", lambda m: joints.append(ns(m.header.stamp)),
                                  QoSProfile(depth=5000))
    user.create_subscription(JointState, "/joint_states", lambda _m: seen_by_user.append(user.get_clock().now().nanoseconds),
                             QoSProfile(depth=5000))
    proc = simulator(tmp_path, "steps:=2", "real_time_factor:=1.0", "exit_when_done:=true", "use_sim_time:=true",
                     "wait_for_subscribers:=2")
    side.wait(lambda: proc.poll() is not None, 120.0)
    settle = time.monotonic() + 0.5
    side.wait(lambda: time.monotonic() > settle)
    assert proc.returncode == 0, (tmp_path / "biped-gait-simulator.log").read_text()
    # /clock: simulated time from 0, increasing, one per sample, the samples' stamps
    assert len(clocks) > 300 and np.all(np.diff(clocks) > 0)
    assert 0 <= clocks[0] < 10_000_000 and 0.85e9 < clocks[-1] < 0.95e9  # 2 steps of 0.45 s
    assert set(joints) <= set(clocks)
    # a node with use_sim_time reads simulated time, not the wall clock
    assert seen_by_user and 0 < seen_by_user[-1] < 1e9
    # the planner on simulated time stamps its plans with it
    client = side.node.create_client(PlanGait, f"/{PLANNER}/plan_gait")
    side.connect(client)
    plan = side.call(client, plan_request(step_length=0.45, period=0.45, arm_amplitude=0.41)).plan
    assert 0 < ns(plan.header.stamp) < 10e9
    # /tf received live is what was recorded, message for message
    [bag] = list((tmp_path / "bags").iterdir())
    [path] = bag.glob("*.mcap")
    with open(path, "rb") as f:
        recorded = [(m.log_time, m.data) for _, _, m in make_reader(f).iter_messages(topics=["/tf"], log_time_order=True)]
    assert same_messages(tf, recorded)
    # the metadata: rosbags opens it with every topic's QoS; the type hashes are rclpy's. Everything
    # published is recorded but /clock (its values are the samples' log times: replay --clock)
    with AnyReader([bag]) as reader:
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
    assert set(qos) == {"/joint_states", "/odom", "/angular_momentum", "/tf", "/tf_static", "/robot_description",
                        "/gait_events", "/gait_phase", "/biped_gait_simulator/velocity_envelope", "/diagnostics",
                        "/biped_gait_simulator/iterations"}
    # one clock: every log time and every header stamp recorded is simulated time (from 0 here)
    recorded = read_bag(bag)
    end = max(clocks)
    assert all(0 <= stamp <= end + 2e9 for messages in recorded.values() for stamp, _ in messages)
    [(logged, envelope)] = recorded["/biped_gait_simulator/velocity_envelope"]
    assert ns(envelope.header.stamp) == logged <= clocks[0]  # the walk's start, in simulated time
    health = [(stamp, m) for stamp, m in recorded["/diagnostics"]]
    assert health and all(ns(m.header.stamp) == stamp for stamp, m in health)
    [status] = health[-1][1].status  # published at once when the walk ended
    walk = {kv.key: kv.value for kv in status.values}
    assert status.name == "biped_gait_simulator: walk" and walk["state"] == "finished" and walk["touchdowns"] == "2"
    counts = [m.data for _, m in recorded["/biped_gait_simulator/iterations"]]
    assert counts == sorted(counts) and 0 < counts[-1] <= round(end * 500e-9) + 1  # samples at 500 Hz
    assert all(len(profiles) == 1 for profiles in qos.values())
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    hashes = {t["topic_metadata"]["name"]: t["topic_metadata"]["type_description_hash"]
              for t in info["topics_with_message_count"]}
    publisher = side.node.create_publisher(JointState, "/sim_time_test_hash", 1)
    [endpoint] = side.node.get_publishers_info_by_topic("/sim_time_test_hash")
    assert hashes["/joint_states"] == str(endpoint.topic_type_hash) and all(h.startswith("RIHS01_") for h in hashes.values())
    side.node.destroy_publisher(publisher)


def test_pause_resume_and_reset(planner_node, side, tmp_path):
    clocks, momentum, counts = [], [], []
    side.node.create_subscription(Clock, "/clock", lambda m: clocks.append(ns(m.clock)), BEST_EFFORT)
    side.node.create_subscription(AngularMomentum, "/angular_momentum", momentum.append, QoSProfile(depth=5000))
    side.node.create_subscription(UInt64, "/biped_gait_simulator/iterations", lambda m: counts.append(m.data),
                                  QoSProfile(depth=100))
    proc = simulator(tmp_path, "steps:=0", "real_time_factor:=1.0", "record:=false", "wait_for_subscribers:=1")
    services = {name: side.node.create_client(Trigger, f"/biped_gait_simulator/{name}") for name in ("pause", "resume", "reset")}
    try:
        side.connect_all(services.values())
        side.wait(lambda: any(m.step >= 1 for m in momentum), 60.0)  # into the second step
        assert side.call(services["pause"], Trigger.Request()).success
        settle = time.monotonic() + 0.3
        side.wait(lambda: time.monotonic() > settle)
        held = len(clocks)
        settle = time.monotonic() + 0.5
        side.wait(lambda: time.monotonic() > settle)
        assert len(clocks) == held, "the simulation went on while paused"
        assert not side.call(services["pause"], Trigger.Request()).success  # already paused
        assert side.call(services["resume"], Trigger.Request()).success
        side.wait(lambda: len(clocks) > held + 50, 10.0)
        before = len(momentum)
        assert side.call(services["reset"], Trigger.Request()).success
        side.wait(lambda: any(m.step == 0 for m in momentum[before:]), 10.0)
        restart = next(m for m in momentum[before:] if m.step == 0)
        assert restart.stance_foot.x == 0.0 and restart.stance_side == "right"
        assert np.all(np.diff(clocks) > 0), "simulated time went back"
        side.wait(lambda: counts and counts[-1] >= len(clocks) - 100, 5.0)  # the step counter follows
        assert counts == sorted(counts)
    finally:
        assert stop_node(proc) == 0, (tmp_path / "biped-gait-simulator.log").read_text()


def test_the_live_view_answers_a_websocket_client(planner_node, tmp_path):
    """A Foxglove client's view: the channels advertised with their ros2msg schemas, the robot
    description sent on subscription, joint states streaming as CDR, the node's health and step
    counter too. The handshake is the SDK's: a client offering foxglove.sdk.v1 (the Foxglove app,
    Lichtblick from 1.22, which offers both) connects; one offering only the older
    foxglove.websocket.v1 is refused with HTTP 400, as by foxglove_bridge 3."""
    proc = simulator(tmp_path, "steps:=0", "real_time_factor:=1.0", "record:=false", "live_view:=true",
                     "live_view_port:=0")
    log = tmp_path / "biped-gait-simulator.log"
    try:
        port = live_view_port(log, "walking L =")
        channels, received = asyncio.run(foxglove_client(port, until=counted))
        both, _ = asyncio.run(foxglove_client(port, ["foxglove.websocket.v1", "foxglove.sdk.v1"]))
        with pytest.raises(websockets.InvalidStatus) as refused:
            asyncio.run(foxglove_client(port, ["foxglove.websocket.v1"]))
    finally:
        assert stop_node(proc) == 0, log.read_text()
    assert refused.value.response.status_code == 400
    assert set(both) == set(channels)
    assert {"/diagnostics", "/biped_gait_simulator/iterations", "/biped_gait_simulator/velocity_envelope"} <= set(channels)
    assert channels["/diagnostics"]["schemaName"] == "diagnostic_msgs/msg/DiagnosticArray"
    health = deserialize_message(received["/diagnostics"][-1], DiagnosticArray)
    assert health.status[0].name == "biped_gait_simulator: walk"
    assert counted(received), [deserialize_message(m, UInt64).data for m in received.get(COUNTER, [])]
    assert {"/robot_description", "/tf", "/tf_static", "/joint_states", "/angular_momentum"} <= set(channels)
    assert channels["/joint_states"]["schemaName"] == "sensor_msgs/msg/JointState"
    assert channels["/joint_states"]["encoding"] == "cdr" and channels["/joint_states"]["schemaEncoding"] == "ros2msg"
    assert "<robot" in deserialize_message(received["/robot_description"][0], String).data
    joints = [deserialize_message(data, JointState) for data in received["/joint_states"]]
    assert len(joints) >= 10 and list(joints[0].name)[:2] == ["right_hip", "right_knee"]
    odom = received.get("/odom")
    assert odom is None or deserialize_message(odom[0], Odometry).header.frame_id == "odom"


def live_view_port(log: Path, ready: str) -> int:
    """The port of the simulator's live view once its log (``log``) gives it, waiting then until
    the log says ``ready`` (120 s in all at most)."""
    deadline = time.monotonic() + 120.0
    while not (match := re.search(r"ws://127\.0\.0\.1:(\d+)", log.read_text())) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert match, log.read_text()
    while ready not in log.read_text() and time.monotonic() < deadline:
        time.sleep(0.1)
    return int(match.group(1))


COUNTER = "/biped_gait_simulator/iterations"  # the step counter: latched, then published 10 times a second


def counted(received: dict[str, list[bytes]]) -> bool:
    """A step count above 0 has come. The latched count a client gets on subscribing may be the 0
    published before the walk's first step, and 10 joint states can come before the next count."""
    return any(deserialize_message(m, UInt64).data > 0 for m in received.get(COUNTER, []))


@asynccontextmanager
async def foxglove_session(port: int, subprotocols: tuple[str, ...] = ("foxglove.sdk.v1",),
                           ) -> AsyncIterator[tuple[websockets.ClientConnection, dict]]:
    """A connection with the Foxglove protocol offering ``subprotocols`` (the server selects
    foxglove.sdk.v1) and the server's first message, its serverInfo. What the server sends is
    queued without bound: a client that reads only at times is not throttled."""
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=list(subprotocols), max_queue=None) as ws:
        assert ws.subprotocol == "foxglove.sdk.v1"
        info = json.loads(await asyncio.wait_for(ws.recv(), 30.0))
        assert info["op"] == "serverInfo", info
        yield ws, info


async def foxglove_client(port: int, subprotocols: tuple[str, ...] = ("foxglove.sdk.v1",),
                          wanted: tuple[str, ...] = ("/robot_description", "/diagnostics"),
                          until: Callable[[dict[str, list[bytes]]], bool] = lambda received: True,
                          ) -> tuple[dict[str, dict], dict[str, list[bytes]]]:
    """Connect with the Foxglove protocol offering ``subprotocols``, subscribe to every channel,
    and collect messages until 10 joint states and one of each ``wanted`` topic have come and
    ``until`` holds of them, or for 60 s at most: (topic -> channel, topic -> payloads)."""
    async with foxglove_session(port, subprotocols) as (ws, _info):
        channels: dict[str, dict] = {}
        while "/joint_states" not in channels:
            message = await asyncio.wait_for(ws.recv(), 30.0)  # the server's time (binary op 2) may come first
            if isinstance(message, str) and (text := json.loads(message))["op"] == "advertise":
                channels.update({c["topic"]: c for c in text["channels"]})
        topics = {k: c["topic"] for k, c in enumerate(channels.values())}
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": k, "channelId": channels[topic]["id"]} for k, topic in topics.items()]}))
        received: dict[str, list[bytes]] = {}
        deadline = time.monotonic() + 60.0
        while (len(received.get("/joint_states", [])) < 10 or not set(wanted) <= set(received)
               or not until(received)) and time.monotonic() < deadline:
            message = await asyncio.wait_for(ws.recv(), 30.0)
            if isinstance(message, bytes) and message[0] == 1:  # message data: op, subscription, log time, payload
                _, subscription, _ = struct.unpack_from("<BIQ", message)
                received.setdefault(topics[subscription], []).append(message[13:])
        return channels, received


def test_foxglove_teleop_publishes_cmd_vel_through_the_live_view(planner_node, side, tmp_path):
    """Foxglove's Teleop panel's way of steering: a client advertises /cmd_vel (geometry_msgs/msg/Twist
    in JSON, the server offering client publishing in JSON alone) and sends a Twist of 0.6 m/s; a
    plain subscriber of the test gets it from the graph, and so does the simulator, which refuses it
    while standing (a gait with no kept start: the refusal's reason, planned in a second or two).
    A message on another topic and malformed JSON are refused with one log line each, sent twice,
    and the node serves on."""
    commands: list[Twist] = []
    side.node.create_subscription(Twist, "/cmd_vel", commands.append, 10)
    proc = start_simulator(tmp_path, PLANNER, "arm_amplitude:=0.4", "live_view:=true", "live_view_port:=0",
                           "record:=false", "real_time_factor:=1.0", initial_state=None)  # standing, the default
    log = tmp_path / "biped-gait-simulator.log"
    refusal = "speed command 0.6 m/s, 0 rad/s refused while standing"

    def relayed_and_refused() -> bool:
        pause = time.monotonic() + 0.1
        side.wait(lambda: time.monotonic() > pause)  # the test's subscriber takes what came meanwhile
        return bool(commands) and refusal in log.read_text()

    try:
        port = live_view_port(log, "speed command: the robot stands")
        bad = [client_message(2, b'{"linear": {"x": 0.6}}'), client_message(1, b'{"linear": ')]
        info = asyncio.run(teleop_client(port, bad + bad, client_message(1, json.dumps(TWIST_06).encode()),
                                         relayed_and_refused))
        served_on = proc.poll() is None
    finally:
        assert stop_node(proc) == 0, log.read_text()
    text = log.read_text()
    assert "clientPublish" in info["capabilities"] and info["supportedEncodings"] == ["json"]
    assert commands and commands[0].linear.x == 0.6 and commands[0].angular.z == 0.0, commands
    assert served_on and text.count(refusal) == 1, text
    refused = [line for line in text.splitlines() if "a client's message on" in line]
    print("\n" + "\n".join(refused))
    assert len(refused) == 2, text
    assert any("a client's message on /foo refused: clients may publish /cmd_vel alone" in line for line in refused)
    assert any("a client's message on /cmd_vel refused: malformed JSON" in line for line in refused)


def test_what_a_client_may_publish():
    """``client_twist``: a Twist in JSON on /cmd_vel under either schema name Foxglove uses is
    taken (JSON's NaN too: the speed command refuses it); the rest is refused with its reason."""
    twist = json.dumps(TWIST_06).encode()
    assert client_twist("/cmd_vel", "geometry_msgs/Twist", "json", twist).linear.x == 0.6
    nan = twist.replace(b"0.6", b"NaN")
    schema = "geometry_msgs/msg/Twist"
    assert np.isnan(client_twist("/cmd_vel", schema, "json", nan).linear.x)
    refused = {("/foo", schema, "json", twist): "clients may publish /cmd_vel alone",
               ("/cmd_vel", "std_msgs/msg/String", "json", twist): "schema 'std_msgs/msg/String'",
               ("/cmd_vel", schema, "cdr", twist): "encoding 'cdr'",
               ("/cmd_vel", schema, "json", b"[" * 100_000): "malformed JSON (nested too deeply)",
               ("/cmd_vel", schema, "json", b"[0.6]"): "not a JSON object",
               ("/cmd_vel", schema, "json", twist.replace(b'"x": 0.6, ', b"")): "linear.x is missing",
               ("/cmd_vel", schema, "json", twist.replace(b"0.6", b'"0.6"')): "linear.x is not a number",
               ("/cmd_vel", schema, "json", twist.replace(b"0.6", b"1" * 400)): "beyond a double's range"}
    for message, reason in refused.items():
        with pytest.raises(ValueError, match=re.escape(reason)):
            client_twist(*message)


TWIST_06 = {"linear": {"x": 0.6, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}  # every field, as Teleop sends it
TELEOP_CHANNELS = [{"id": 1, "topic": "/cmd_vel", "encoding": "json", "schemaName": "geometry_msgs/msg/Twist"},
                   {"id": 2, "topic": "/foo", "encoding": "json", "schemaName": "geometry_msgs/msg/Twist"}]


def client_message(channel: int, payload: bytes) -> bytes:
    """A client's message data (binary, opcode 0x01): the channel's id (uint32 LE), then the payload."""
    return struct.pack("<BI", 1, channel) + payload


async def teleop_client(port: int, once: list[bytes], command: bytes, until: Callable[[], bool]) -> dict:
    """As Foxglove's Teleop panel: advertise ``TELEOP_CHANNELS``, send each of ``once`` (client
    messages), then ``command`` at about 5 Hz until ``until()`` holds (120 s at most; DDS may
    match the simulator's publisher with a subscriber after the first): the server's serverInfo."""
    async with foxglove_session(port) as (ws, info):
        await ws.send(json.dumps({"op": "advertise", "channels": TELEOP_CHANNELS}))
        for message in once:
            await ws.send(message)
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline:
            await ws.send(command)
            await asyncio.sleep(0.1)  # the connection reads what the server sent meanwhile
            if until():
                break
        return info


def test_live_view_and_recording_switched_at_run_time_and_the_walk_in_diagnostics(planner_node, side, tmp_path):
    """The parameter services of a walking simulator: the live view started (the robot description
    sent to a client that connects now) and stopped; a recording started (the latched topics first)
    and finished, holding the joint states published meanwhile (counted by a subscriber, not timed
    by the wall clock: the test runs beside others); a read-only parameter refused with its reason;
    /diagnostics tells the walk."""
    from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    proc = simulator(tmp_path, "steps:=0", "real_time_factor:=1.0", "record:=false", "live_view_port:=0")
    log = tmp_path / "biped-gait-simulator.log"
    received = []
    side.node.create_subscription(DiagnosticArray, "/diagnostics", received.append, 10)
    joints: list[JointState] = []
    side.node.create_subscription(JointState, "/joint_states", joints.append, 50)

    def walk() -> dict[str, str]:
        statuses = [s for a in received for s in a.status if s.name == "biped_gait_simulator: walk"]
        return {kv.key: kv.value for kv in statuses[-1].values} if statuses else {}

    def set_(name: str, value: bool | int):
        kind = (ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value) if isinstance(value, bool) else
                ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value))
        request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=kind)])
        return side.call(setter, request, timeout=30.0).results[0]

    try:
        setter = side.node.create_client(SetParameters, "/biped_gait_simulator/set_parameters")
        side.connect(setter)
        side.wait(lambda: walk().get("state") == "walking" and int(walk().get("touchdowns", 0)) >= 1, 60.0)
        assert walk()["recording"] == "off" and walk()["live_view"] == "off"
        assert set_("live_view", True).successful
        side.wait(lambda: re.search(r"ws://127\.0\.0\.1:(\d+)", log.read_text()) is not None, 10.0)
        port = int(re.search(r"ws://127\.0\.0\.1:(\d+)", log.read_text()).group(1))
        channels, shown = asyncio.run(foxglove_client(port, wanted=("/robot_description",)))
        assert "<robot" in deserialize_message(shown["/robot_description"][0], String).data
        assert set_("live_view", False).successful and "live view stopped" in log.read_text()
        assert set_("record", True).successful
        side.wait(lambda: walk().get("recording", "off") != "off", 10.0)
        seen = len(joints)
        side.wait(lambda: len(joints) >= seen + 600, 60.0)  # 1.2 s of the walk published while recording
        assert set_("record", False).successful
        refused = set_("steps", 3)
        assert not refused.successful and "read-only" in refused.reason and "steps" in refused.reason
    finally:
        assert stop_node(proc) == 0, log.read_text()
    [bag] = list((tmp_path / "bags").iterdir())
    with AnyReader([bag]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert counts["/robot_description"] == 1 and counts["/tf_static"] == 1  # the latched topics first
    assert counts["/joint_states"] >= 400  # 600 received while the recording was on (some may have left before it)
