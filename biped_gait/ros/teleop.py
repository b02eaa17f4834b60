"""Steering from Foxglove: what a live view's client publishes (Foxglove's Teleop panel:
geometry_msgs/Twist on ``/cmd_vel``, sent as JSON through the WebSocket protocol's client
publishing) is put on the ROS graph by a publisher of the simulator's own, as foxglove_bridge
does: the simulator's own ``/cmd_vel`` subscription gets it, and so does any other node.

Taken: topic ``/cmd_vel``, schema ``geometry_msgs/msg/Twist`` (or the ROS 1 name
``geometry_msgs/Twist``, which Foxglove also uses), encoding ``json`` (the only one the live view
offers its clients, so Foxglove sends ``JSON.stringify`` of the message): a JSON object with the
objects ``linear`` and ``angular``, each with the numbers ``x``, ``y`` and ``z``. Anything else
(another topic, schema or encoding, malformed JSON, a field missing or not a number) is refused
with a warning, one per topic and reason; the walk goes on. Non-finite numbers (JSON's ``NaN``,
``Infinity``) pass here and are refused by the speed command (``SpeedCommand.on_twist``).

Called on the live view's server threads (``LiveView``'s ``on_message``): nothing here raises.
"""

from __future__ import annotations

import json
import threading

from geometry_msgs.msg import Twist, Vector3
from rclpy.node import Node

from ..recording import topics

TWIST_SCHEMAS = ("geometry_msgs/msg/Twist", "geometry_msgs/Twist")  # ROS 2's name, ROS 1's
ENCODING = "json"  # the encoding the live view offers its clients to publish in


class Teleop:
    """A client's ``/cmd_vel`` from the live view, published on the ROS graph by ``node``
    (a publisher of queue depth ``depth``); the rest refused with a warning (module docstring)."""

    def __init__(self, node: Node, depth: int) -> None:
        self.publisher = node.create_publisher(Twist, topics.CMD_VEL, depth)
        self._logger = node.get_logger()
        self._said: set[tuple[str, str]] = set()  # (topic, reason) of the refusals logged
        self._lock = threading.Lock()

    def on_message(self, topic: str, schema_name: str, encoding: str, data: bytes) -> None:
        """A message a client published on ``topic`` (schema ``schema_name``, ``encoding``):
        published on ``/cmd_vel`` if it is a Twist there in JSON, else refused."""
        try:
            msg = client_twist(topic, schema_name, encoding, data)
        except ValueError as exc:
            reason = str(exc)
            with self._lock:
                said = (topic, reason) in self._said
                self._said.add((topic, reason))
            if not said:
                self._logger.warn(f"live view: a client's message on {topic} refused: {reason} (said once per topic "
                                  "and reason)")
            return
        self.publisher.publish(msg)


def client_twist(topic: str, schema_name: str, encoding: str, data: bytes) -> Twist:
    """The Twist a client sent on ``topic`` as ``data`` (``encoding``, schema ``schema_name``);
    ``ValueError`` with the reason it is refused (module docstring)."""
    if topic != topics.CMD_VEL:
        raise ValueError(f"clients may publish {topics.CMD_VEL} alone")
    if schema_name not in TWIST_SCHEMAS:
        raise ValueError(f"schema {schema_name!r}, not {TWIST_SCHEMAS[0]}")
    if encoding != ENCODING:
        raise ValueError(f"encoding {encoding!r}, not {ENCODING}")
    try:
        value = json.loads(data)
    except UnicodeDecodeError:
        raise ValueError("not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"malformed JSON ({exc.msg})") from None
    except RecursionError:
        raise ValueError("malformed JSON (nested too deeply)") from None
    if not isinstance(value, dict):
        raise ValueError("not a JSON object")
    return Twist(linear=_vector(value, "linear"), angular=_vector(value, "angular"))


def _vector(value: dict, name: str) -> Vector3:
    """The Vector3 of the object ``value[name]``; ``ValueError`` if a field is missing or not a number."""
    if name not in value:
        raise ValueError(f"{name} is missing")
    vector = value[name]
    if not isinstance(vector, dict):
        raise ValueError(f"{name} is not an object")
    numbers = []
    for axis in "xyz":
        if axis not in vector:
            raise ValueError(f"{name}.{axis} is missing")
        number = vector[axis]
        if isinstance(number, bool) or not isinstance(number, (int, float)):
            raise ValueError(f"{name}.{axis} is not a number")
        try:
            numbers.append(float(number))
        except OverflowError:  # an integer beyond a double
            raise ValueError(f"{name}.{axis} is beyond a double's range") from None
    return Vector3(x=numbers[0], y=numbers[1], z=numbers[2])
