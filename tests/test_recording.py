"""The recording package on its own (no rclpy, no node): schemas from the installed message
definitions, the writer's files read back by two independent readers (rosbags, mcap_ros2) with
every topic's QoS, and the recovery of a file whose writer was killed. Messages are serialized
by rosbags, a third party, so that nothing here checks itself."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from biped_gait.recording.qos import qos_description
from biped_gait.recording.reader import open_bag
from biped_gait.recording.recover import is_complete, recover
from biped_gait.recording.schemas import SEPARATOR, schema_text
from biped_gait.recording.writer import McapRecorder, SampleRows

pytestmark = pytest.mark.recording

STORE = get_typestore(Stores.ROS2_JAZZY)
STRING, JOINTS = "std_msgs/msg/String", "sensor_msgs/msg/JointState"
LATCHED = qos_description("keep_last", 1, "reliable", "transient_local")
STREAM = qos_description("keep_last", 50, "reliable", "volatile")


def joint_state(i: int) -> bytes:
    t = STORE.types
    msg = t[JOINTS](header=t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=i, nanosec=7), frame_id=""),
                    name=["right_hip", "right_knee"], position=np.array([0.1 * i, -0.2]), velocity=np.array([1.0, 2.0]),
                    effort=np.zeros(2))
    return bytes(STORE.serialize_cdr(msg, JOINTS))


def string(text: str) -> bytes:
    return bytes(STORE.serialize_cdr(STORE.types[STRING](data=text), STRING))


def test_schemas_carry_every_dependency_fully_qualified():
    text = schema_text(JOINTS)
    blocks = text.split(SEPARATOR + "\n")
    assert blocks[0].splitlines()[0] == "std_msgs/Header header"
    assert [b.splitlines()[0] for b in blocks[1:]] == ["MSG: std_msgs/Header", "MSG: builtin_interfaces/Time"]
    assert "#" not in text  # comments dropped
    with pytest.raises(LookupError, match="no definition of no_such_pkg/msg/Thing.msg"):
        schema_text("no_such_pkg/msg/Thing")


def test_what_is_written_two_readers_read_back_with_its_qos(tmp_path):
    recorder = McapRecorder(tmp_path, "bag")
    recorder.add_topic("/robot_description", STRING, [LATCHED])
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    recorder.add_topic("/joint_states", JOINTS, [LATCHED])  # idempotent: the first registration holds
    recorder.write("/robot_description", string("<robot/>"), 1_000)
    for i in range(5):
        recorder.write("/joint_states", joint_state(i), 2_000 + i)
    recorder.close()
    recorder.write("/joint_states", joint_state(9), 9_000)  # after close: ignored
    bag = open_bag(tmp_path / "bag")
    assert bag.topics() == {"/robot_description": (STRING, 1), "/joint_states": (JOINTS, 5)}
    assert bag.offered_qos("/robot_description") == [LATCHED] and bag.offered_qos("/joint_states") == [STREAM]
    decoded = [msg for topic, _, msg in bag.decoded(["/joint_states"])]
    assert [list(m.position) for m in decoded] == [[0.1 * i, -0.2] for i in range(5)]
    with AnyReader([tmp_path / "bag"]) as reader:
        qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
        assert all(len(profiles) == 1 for profiles in qos.values()), qos
        assert qos["/robot_description"][0].durability.name.lower() == "transient_local"
        got = [(c.topic, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    assert [t for _, t, _ in got] == [1_000, 2_000, 2_001, 2_002, 2_003, 2_004]
    assert got[0][2].data == "<robot/>" and list(got[-1][2].position) == [0.4, -0.2]


def test_rows_of_samples_are_recorded_as_the_same_messages_one_by_one(tmp_path):
    """``SampleRows`` (what the simulator hands over, through its recorder process) gives the
    file that writing each message in sample order gives: same bytes, stamps and order."""
    joints = [joint_state(i) for i in range(4)]
    names = [string(f"s{i}") for i in range(4)]  # rows of one topic have one size
    rows = SampleRows(("/joint_states", "/names"), (np.frombuffer(b"".join(joints), np.uint8).reshape(4, -1),
                                                    np.frombuffer(b"".join(names), np.uint8).reshape(4, -1)),
                      np.arange(4, dtype=np.int64) * 1_000 + 5)
    by_rows, one_by_one = McapRecorder(tmp_path, "rows"), McapRecorder(tmp_path, "messages")
    for recorder in (by_rows, one_by_one):
        recorder.add_topic("/joint_states", JOINTS, [STREAM])
        recorder.add_topic("/names", STRING, [STREAM])
    by_rows.write_many([rows])
    for i in range(4):
        one_by_one.write("/joint_states", joints[i], 1_000 * i + 5)
        one_by_one.write("/names", names[i], 1_000 * i + 5)
    by_rows.close()
    one_by_one.close()

    def read(name: str) -> list:
        [path] = (tmp_path / name).glob("*.mcap")
        with open(path, "rb") as f:
            return [(channel.topic, m.log_time, m.data) for _, channel, m in make_reader(f).iter_messages()]
    assert read("rows") == read("messages") and len(read("rows")) == 8


def test_recover_rebuilds_a_killed_writers_file_with_full_metadata(tmp_path):
    recorder = McapRecorder(tmp_path, "bag", chunk_size=1024)
    recorder.add_topic("/robot_description", STRING, [LATCHED])
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    recorder.write("/robot_description", string("<robot/>"), 1)
    for i in range(200):
        recorder.write("/joint_states", joint_state(i), 10 + i)
    killed = tmp_path / "killed"  # the file as a SIGKILL leaves it: closed chunks only, no summary
    killed.mkdir()
    shutil.copy(recorder.path, killed / "killed_0.mcap")
    recorder.close()
    assert not is_complete(killed / "killed_0.mcap")
    out = tmp_path / "recovered" / "recovered_0.mcap"
    out.parent.mkdir()
    count = recover(killed / "killed_0.mcap", out)
    assert is_complete(out) and 150 < count <= 201  # at most the open chunk (1 kB, ~12 messages) lost
    info = yaml.safe_load((out.parent / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    entries = {e["topic_metadata"]["name"]: e for e in info["topics_with_message_count"]}
    assert entries["/robot_description"]["topic_metadata"]["offered_qos_profiles"] == [LATCHED]
    assert entries["/joint_states"]["topic_metadata"]["offered_qos_profiles"] == [STREAM]
    with AnyReader([out.parent]) as reader:
        assert {c.topic for c in reader.connections} == {"/robot_description", "/joint_states"}
        assert sum(1 for _ in reader.messages()) == count


def test_a_bag_directory_may_not_exist_twice(tmp_path):
    McapRecorder(tmp_path, "bag").close()
    with pytest.raises(FileExistsError):
        McapRecorder(tmp_path, "bag")
    assert Path(tmp_path / "bag" / "metadata.yaml").is_file()
