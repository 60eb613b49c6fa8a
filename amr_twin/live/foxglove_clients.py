"""The clients' side of the live Foxglove server (:mod:`.foxglove`), in the server's threads:
their channels, messages and service calls decoded and checked (:mod:`.inputs`), handed to the
twin's thread through the pacer, each refusal logged and counted (:class:`FoxgloveClients`)."""

from __future__ import annotations

import logging

from amr_twin.live import inputs as live_inputs

LOG = logging.getLogger(__name__)

SERVICE = "/wheel_Command_Service"


class FoxgloveClients:
    """What the clients of a live twin send it.

    Parameters
    ----------
    twin, pacer : Twin, Pacer
        The twin, and what runs the clients' messages in its thread.
    goal_channel : foxglove.Channel
        Where a client's goal is echoed to the clients.
    latched, latched_due : tuple of str, set of str
        The latched topics, and those the server sends again at its next flush.
    """

    def __init__(self, twin, pacer, goal_channel, latched: tuple[str, ...], latched_due: set[str]):
        self.twin, self.pacer, self.bus = twin, pacer, twin.bus
        self.goal_channel = goal_channel
        self._latched, self._latched_due = latched, latched_due
        self.dropped, self.accepted = 0, 0
        """Client messages refused (each logged), and handed to the twin."""
        self._channels: dict[tuple[int, int], tuple[str, str, object]] = {}

    def listener(self, foxglove):
        """A ``foxglove.ServerListener`` (its callbacks run in the server's threads) handing the
        clients' events to this object."""
        clients = self

        class Listener(foxglove.ServerListener):
            def on_subscribe(self, client, channel) -> None:
                clients.on_subscribe(channel.topic)

            def on_client_advertise(self, client, channel) -> None:
                clients.on_advertise(client.id, channel)

            def on_client_unadvertise(self, client, client_channel_id: int) -> None:
                clients._channels.pop((client.id, client_channel_id), None)

            def on_message_data(self, client, client_channel_id: int, data: bytes) -> None:
                clients.on_message(client.id, client_channel_id, data)

        return Listener()

    def on_subscribe(self, topic: str) -> None:
        """A client subscribed to ``topic``: a latched one is sent again at the next flush."""
        if topic in self._latched:
            try:
                self.pacer.post(lambda: self._latched_due.add(topic))
            except RuntimeError:  # the twin has stopped
                pass

    def _drop(self, client_id: int, what: str, reason: str) -> None:
        self.dropped += 1
        LOG.warning("live: dropped %s from client %d: %s", what, client_id, reason)

    def on_advertise(self, client_id: int, channel) -> None:
        """A client's channel: its decoder, or why its messages will be dropped."""
        try:
            decoder = live_inputs.input_for(channel.topic, channel.schema_name, channel.encoding)
        except live_inputs.InputError as exc:
            decoder = exc
            LOG.warning(
                "live: client %d advertises %s; its messages will be dropped: %s",
                client_id,
                channel.topic,
                exc,
            )
        self._channels[(client_id, channel.id)] = (channel.topic, channel.encoding, decoder)

    def on_message(self, client_id: int, channel_id: int, data: bytes) -> None:
        """A client's message: decoded and checked, then handed to the twin's thread."""
        entry = self._channels.get((client_id, channel_id))
        if entry is None:
            return self._drop(
                client_id, f"a message on channel {channel_id}", "the channel was not advertised"
            )
        topic, encoding, decoder = entry
        if isinstance(decoder, Exception):
            return self._drop(client_id, f"a message on {topic}", str(decoder))
        try:
            msg = decoder(data, encoding)
        except live_inputs.InputError as exc:
            return self._drop(client_id, f"a message on {topic}", str(exc))
        name = topic.lstrip("/")
        if name == "wheel_Command_Service/request":
            action = lambda: live_inputs.call_service(self.bus, msg)  # noqa: E731
        elif name == "goal_pose":
            action = lambda: self._goal(msg)  # noqa: E731
        else:
            action = lambda: self.bus.publish(name, msg)  # noqa: E731
        try:
            self.pacer.post(action)
        except RuntimeError as exc:
            return self._drop(client_id, f"a message on {topic}", str(exc))
        self.accepted += 1

    def _goal(self, msg) -> None:
        """A client's goal (the twin's thread): stamped now, on the bus' ``goal_pose``, echoed to
        the clients."""
        from amr_twin.ros.messages import Time
        from amr_twin.ros.nav_messages import encode_pose_stamped

        msg.header.stamp = Time.from_sec(self.twin.clock.now_s)
        self.bus.publish("goal_pose", msg)
        self.goal_channel.log(encode_pose_stamped(msg), log_time=self.twin.clock.now_us * 1000)

    def on_service_call(self, request) -> bytes:
        """``/wheel_Command_Service`` (the server's thread): checked, then called at the next
        tick."""
        try:
            req = live_inputs.decode_service_request(request.payload, request.encoding)
        except live_inputs.InputError as exc:
            self._drop(request.client_id, f"a call of {SERVICE}", str(exc))
            raise
        self.pacer.call(lambda: live_inputs.call_service(self.bus, req))
        self.accepted += 1
        return live_inputs.service_response(request.encoding)
