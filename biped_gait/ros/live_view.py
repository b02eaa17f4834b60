"""A live view of the walk in Foxglove: a Foxglove WebSocket server (foxglove-sdk, MIT) that
serves the topics it is given with the same CDR bytes and ``ros2msg`` schemas as the recording,
and the simulated time (the server's time capability). Foxglove, connected to
``ws://HOST:PORT``, shows the robot from ``/robot_description`` (a URDF layer of the 3D panel
on that topic) moving with ``/tf`` and ``/tf_static``, and plots ``/joint_states`` and
``/angular_momentum`` as the robot walks.

Clients may publish (the protocol's client publishing, ``clientPublish``, as foxglove_bridge
offers it) in JSON, the one encoding the server offers them (``supportedEncodings``): so does
Foxglove's Teleop panel, its geometry_msgs/Twist on ``/cmd_vel``. Each message a client publishes goes to
the view's owner (``on_message``: its topic, schema name, encoding and bytes, by the channel the
client advertised), which takes or refuses it (``teleop``); the view itself knows no ROS.

Latched topics (transient-local: the robot description, the static transforms) are sent again
to each client that subscribes to them, as a late ROS subscriber would get them. The server
binds ``127.0.0.1`` unless told otherwise; it runs on threads of its own (Rust), and logging a
message to a channel nobody subscribes to costs next to nothing. The SDK is imported when a live
view starts: the nodes that show nothing do not load it (nor its runtime's exit hook).

The handshake is the SDK's own: it selects the subprotocol ``foxglove.sdk.v1`` (or
``foxglove.sdk.v1.1``) and refuses with HTTP 400 a client that offers only the older name of the
same protocol, ``foxglove.websocket.v1`` (foxglove-sdk 0.30.3 has no option for it: its
``start_server`` takes none, its handshake hard-codes the name). docs/ros.md says which clients
connect.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from ..recording.schemas import schema_text

DEFAULT_PORT = 8765  # Foxglove's default for a WebSocket connection
CLIENT_ENCODINGS = ["json"]  # what clients may publish in: Foxglove picks the first it knows (json, ros1, cdr)

ClientMessage = Callable[[str, str, str, bytes], None]
"""A message a client published: (topic, schema name, encoding, bytes)."""


class LiveView:
    """A Foxglove WebSocket server on ``host``:``port`` (0: any free port, see ``port``); the
    messages its clients publish go to ``on_message`` (called on the server's threads: it must
    not raise)."""

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT, name: str = "biped_gait", *,
                 on_message: ClientMessage) -> None:
        import foxglove
        from foxglove.websocket import Capability

        self._foxglove = foxglove
        self._context = foxglove.Context()
        self._channels: dict[str, object] = {}  # topic -> its foxglove.Channel
        self._latched: dict[str, tuple[bytes, int]] = {}  # topic -> its latest message and stamp (ns)
        self._closed = False  # a walk's step may still log to a view stopped at run time: dropped
        self._on_message = on_message
        self._advertised: dict[tuple[int, int], tuple[str, str, str]] = {}  # (client, channel): topic, schema, encoding
        self.server = foxglove.start_server(name=name, host=host, port=port, context=self._context,
                                            capabilities=[Capability.Time, Capability.ClientPublish],
                                            supported_encodings=CLIENT_ENCODINGS, server_listener=_listener(self))

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return self.server.port

    def add_topic(self, topic: str, datatype: str, latched: bool = False) -> None:
        """Serve ``topic`` of type ``datatype`` ('pkg/msg/Type', CDR); ``latched``: send its
        latest message to each new subscriber."""
        if topic in self._channels:
            return
        foxglove = self._foxglove
        schema = foxglove.Schema(name=datatype, encoding="ros2msg", data=schema_text(datatype).encode())
        self._channels[topic] = foxglove.Channel(topic, schema=schema, message_encoding="cdr", context=self._context)
        if latched:
            self._latched[topic] = (b"", 0)

    def log(self, topic: str, data: bytes, stamp_ns: int | None = None) -> None:
        """Send the CDR bytes of one message on ``topic`` to its subscribers, stamped ``stamp_ns``
        (ns; default: now)."""
        if self._closed:
            return
        stamp = time.time_ns() if stamp_ns is None else int(stamp_ns)
        if topic in self._latched:
            self._latched[topic] = (data, stamp)
        self._channels[topic].log(data, log_time=stamp)

    def time(self, stamp_ns: int) -> None:
        """Tell the clients the current (simulated) time (ns)."""
        if not self._closed:
            self.server.broadcast_time(int(stamp_ns))

    def resend_latched(self, topic: str) -> None:
        """Send ``topic``'s latest message again if it is latched (a client just subscribed)."""
        data, stamp = self._latched.get(topic, (b"", 0))
        if data:
            self._channels[topic].log(data, log_time=stamp)

    def client_advertised(self, client: int, channel: int, topic: str, schema_name: str, encoding: str) -> None:
        """Client ``client`` advertised its channel ``channel``: ``topic``, ``schema_name``, ``encoding``."""
        self._advertised[(client, channel)] = (topic, schema_name, encoding)

    def client_unadvertised(self, client: int, channel: int) -> None:
        """Client ``client`` unadvertised its channel ``channel`` (it said so, or left)."""
        self._advertised.pop((client, channel), None)

    def client_message(self, client: int, channel: int, data: bytes) -> None:
        """A message client ``client`` published on its channel ``channel``: to ``on_message``."""
        what = self._advertised.get((client, channel))
        if what is not None and not self._closed:
            self._on_message(*what, data)

    def close(self) -> None:
        """Stop the server (its clients are disconnected); what is logged afterwards is dropped."""
        self._closed = True
        self.server.stop()


def _listener(view: LiveView):
    """The server's callbacks: a client's subscription to a latched topic gets its latest message;
    the channels clients advertise, and what they publish on them, go to ``view``."""
    from foxglove.websocket import ServerListener

    class Listener(ServerListener):
        def on_subscribe(self, _client, channel) -> None:
            view.resend_latched(channel.topic)

        def on_client_advertise(self, client, channel) -> None:
            view.client_advertised(client.id, channel.id, channel.topic, channel.schema_name, channel.encoding)

        def on_client_unadvertise(self, client, client_channel_id: int) -> None:
            view.client_unadvertised(client.id, client_channel_id)

        def on_message_data(self, client, client_channel_id: int, data: bytes) -> None:
            view.client_message(client.id, client_channel_id, data)

    return Listener()
