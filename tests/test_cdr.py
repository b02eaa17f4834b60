"""The project's CDR bytes are exactly a message's encoding: every message of the interfaces,
with its sequences empty and filled to every length modulo the alignment, decodes with rclpy
and with rosbags (an independent reader, which checks the length), to the same values; and
rclpy's own bytes are longer than that encoding where an empty float64[] needs no padding."""

from __future__ import annotations

import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

import numpy as np
from biped_gait_interfaces.msg import AngularMomentum, GaitEvent, GaitPhase, GaitPlan, PlanGaitCall
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from tf2_msgs.msg import TFMessage

from biped_gait.recording.schemas import SEPARATOR, schema_text, type_name
from biped_gait.ros.cdr import HEADER, cdr_size, serialized

pytestmark = pytest.mark.recording

MESSAGES = [AngularMomentum, GaitEvent, GaitPhase, GaitPlan, PlanGaitCall, TFMessage]  # PlanGaitCall holds the service's fields


def _store():
    store = get_typestore(Stores.ROS2_JAZZY)
    for cls in MESSAGES:
        name = type_name(cls)
        for part in schema_text(name).split(SEPARATOR):
            lines = part.strip().splitlines()
            if lines and lines[0].startswith("MSG: "):
                store.register(get_types_from_msg("\n".join(lines[1:]), lines[0][5:].strip()))
            elif part.strip():
                store.register(get_types_from_msg(part, name))
    return store


def _filled(cls: type, length: int, rng: np.random.Generator):
    """A ``cls`` message whose sequences all hold ``length`` items and whose numbers are random."""
    msg = cls()
    for name, typ in cls.get_fields_and_field_types().items():
        value = getattr(msg, name)
        inner = typ[len("sequence<"):-1].split(",")[0] if typ.startswith("sequence<") else None
        if inner in ("double", "float"):
            setattr(msg, name, rng.normal(size=length).tolist())
        elif inner == "string":
            setattr(msg, name, ["x" * (k + 1) for k in range(length)])
        elif inner is not None and "/" in inner:
            item_cls = type(_nested(cls, name))
            setattr(msg, name, [_filled(item_cls, length, rng) for _ in range(length)])
        elif typ == "double":
            setattr(msg, name, float(rng.normal()))
        elif typ == "string":
            setattr(msg, name, "s" * (length + 1))
        elif hasattr(value, "get_fields_and_field_types"):
            setattr(msg, name, _filled(type(value), length, rng))
    return msg


def _nested(cls: type, name: str):
    """An item of the message sequence ``name`` of ``cls``."""
    package, item_name = cls.get_fields_and_field_types()[name][len("sequence<"):-1].split(",")[0].split("/")
    return getattr(__import__(f"{package}.msg", fromlist=[item_name]), item_name)()


@pytest.mark.parametrize("cls", MESSAGES, ids=lambda cls: type_name(cls))
def test_every_message_decodes_with_rclpy_and_rosbags_at_every_sequence_length(cls):
    store = _store()
    rng = np.random.default_rng(1)
    for length in range(4):
        msg = _filled(cls, length, rng)
        data = serialized(msg)
        assert len(data) == HEADER + cdr_size(msg)
        assert deserialize_message(data, cls) == msg
        other = store.deserialize_cdr(data, type_name(cls))
        assert len(store.serialize_cdr(other, type_name(cls))) == len(data)  # rosbags' own encoding


def test_rclpy_pads_an_empty_float64_sequence_past_the_end():
    event = GaitEvent(stance_side="left", message="walked 3 steps")
    assert len(serialize_message(event)) == len(serialized(event)) + 8  # i_minus, i_plus: 4 bytes each
    assert deserialize_message(serialized(event), GaitEvent) == event
