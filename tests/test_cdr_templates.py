"""The sampled topics' messages serialized a step at a time from CDR templates decode, with
rclpy's deserializer and with rosbags (an independent reader), to exactly the messages built
field by field, and have rclpy's size; a message whose shape varies is refused."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import numpy as np
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from std_msgs.msg import String

from biped_gait.core.walking.events import StepSamples
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.walk import Walk
from biped_gait.recording import topics
from biped_gait.recording.schemas import SEPARATOR, schema_text
from biped_gait.ros.cdr_templates import CdrTemplate
from biped_gait.ros.sim_clock import clock_msg
from biped_gait.ros.walk_messages import SampleMessages, _moving_tf_msg, joint_state_msg, momentum_msg, odometry_msg

pytestmark = pytest.mark.recording


@pytest.fixture(scope="module")
def step(default_gait):
    """The second step of a walk (left foot in stance) and its walk."""
    walk = Walk(PlannedOrbit.of(default_gait), 500.0, 2)
    batches = [item for item in walk.batches() if isinstance(item, StepSamples)]
    return walk, batches[1]


def test_a_step_of_messages_decodes_to_the_messages_built_field_by_field(step):
    walk, batch = step
    world = batch.world
    stamps = 1_800_000_000_123_456_789 + np.arange(len(world)) * 2_000_000
    rows = SampleMessages(walk.world.joints.names, walk.world.link_frames).encode(world, stamps, 1, "left")
    store = get_typestore(Stores.ROS2_JAZZY)
    momentum = "biped_gait_interfaces/msg/AngularMomentum"
    store.register(get_types_from_msg(schema_text(momentum).split(SEPARATOR)[0], momentum))
    for k in (0, len(world) // 2, len(world) - 1):
        ints = [stamps[k] // 1_000_000_000, stamps[k] % 1_000_000_000]
        pelvis = [*world.pelvis_position[k], *world.pelvis_quaternion[k]]
        links = np.concatenate([world.link_translations[k], world.link_quaternions[k]], axis=1).ravel()
        expected = {
            topics.JOINT_STATES: joint_state_msg(world.joint_names, np.concatenate([world.joint_positions[k],
                                                                            world.joint_velocities[k],
                                                                            world.joint_efforts[k]]), ints),
            topics.ODOM: odometry_msg(np.array([*pelvis, *world.pelvis_linear_velocity[k],
                                                *world.pelvis_angular_velocity[k]]), ints),
            topics.ANGULAR_MOMENTUM: momentum_msg(np.concatenate([world.stance_foot, world.momentum_about_foot[k], world.com[k],
                                                                  world.momentum_about_com[k]]), [*ints, 1], "left"),
            topics.TF: _moving_tf_msg(walk.world.link_frames, np.concatenate([pelvis, links]), ints),
        }
        for topic, msg in expected.items():
            data = rows[topic][k].tobytes()
            assert len(data) == len(serialize_message(msg)), topic
            assert deserialize_message(data, type(msg)) == msg, topic
            other = store.deserialize_cdr(data, f"{type(msg).__module__.split('.')[0]}/msg/{type(msg).__name__}")
            header = other.transforms[-1].header if topic == topics.TF else other.header
            assert header.stamp.sec == ints[0] and header.stamp.nanosec == ints[1], topic
    joints = deserialize_message(rows[topics.JOINT_STATES][3].tobytes(), type(expected[topics.JOINT_STATES]))
    assert list(joints.position) == world.joint_positions[3].tolist()


def test_the_clock_template_and_a_message_of_varying_shape():
    template = CdrTemplate(clock_msg, 0, 2)
    [row] = template.encode(np.zeros((1, 0)), np.array([[12, 345]]))
    assert deserialize_message(row.tobytes(), type(clock_msg(None, [0, 0]))).clock.nanosec == 345
    with pytest.raises(ValueError, match="found"):  # the number goes into a string of varying length
        CdrTemplate(lambda floats, _ints: String(data=f"{floats[0]:.3f}"), 1)
