"""MQTT for one vehicle (paho-mqtt): its ``order`` and ``instantActions`` topics in, its messages
out, the ``connection`` topic's last will (CONNECTIONBROKEN), ONLINE at connection and OFFLINE at a
clean close, retained (the specification's sections 6.2 and 6.14)."""

from __future__ import annotations

import json
import threading
from urllib.parse import urlparse

from amr_twin.fleet.protocol import QOS, topic

KEEPALIVE_S = 15
"""The MQTT heartbeat: the broker declares the connection broken after 1.5 times this without
traffic (6.14)."""


def broker_address(url: str) -> tuple[str, int]:
    """``mqtt://HOST:PORT`` (port 1883 if left out) as (host, port); ValueError naming the option
    otherwise."""
    parsed = urlparse(url)
    try:
        port = parsed.port or 1883
    except ValueError:
        port = None
    if (
        parsed.scheme != "mqtt"
        or not parsed.hostname
        or port is None
        or parsed.path not in ("", "/")
    ):
        raise ValueError(f"--vda5050 {url!r}: expected mqtt://HOST:PORT (a plain TCP MQTT broker)")
    return parsed.hostname, port


class MqttTransport:
    """One vehicle's MQTT client. ``on_message(subtopic, payload)`` is called in paho's network
    thread."""

    def __init__(
        self, url: str, interface: str, serial: str, on_message, will: dict, manufacturer: str
    ):
        import paho.mqtt.client as mqtt

        self.host, self.port = broker_address(url)
        self._topic = lambda sub: topic(interface, serial, sub, manufacturer)
        self.messages_in = 0
        """Messages received so far (order and instantActions)."""
        self._on_message, self._connected = on_message, threading.Event()
        self.client = mqtt.Client(
            mqtt.CallbackAPIVersion.VERSION2,
            client_id=f"{interface}-{manufacturer}-{serial}",
            protocol=mqtt.MQTTv311,
        )
        self.client.will_set(
            self._topic("connection"), json.dumps(will), qos=QOS["connection"], retain=True
        )
        self.client.on_connect = self._connect_cb
        self.client.on_message = self._message_cb
        self._subs = {self._topic(s): s for s in ("order", "instantActions")}

    def _connect_cb(self, client, _userdata, _flags, reason, _properties=None) -> None:
        if reason == 0:
            for name in self._subs:
                client.subscribe(name, qos=1)
            self._connected.set()

    def _message_cb(self, _client, _userdata, message) -> None:
        sub = self._subs.get(message.topic)
        if sub is not None:
            self.messages_in += 1
            self._on_message(sub, message.payload)

    def connect(self, timeout_s: float = 10.0) -> None:
        """Connect and subscribe; OSError with one line if the broker does not answer in
        ``timeout_s``."""
        try:
            self.client.connect(self.host, self.port, keepalive=KEEPALIVE_S)
        except OSError as exc:
            raise OSError(
                f"--vda5050 mqtt://{self.host}:{self.port}: cannot connect ({exc.strerror or exc})"
            ) from None
        self.client.loop_start()
        if not self._connected.wait(timeout_s):
            self.client.loop_stop()
            raise OSError(
                f"--vda5050 mqtt://{self.host}:{self.port}: the broker did not accept the "
                f"connection "
                f"within {timeout_s:g} s"
            )

    def publish(self, subtopic: str, msg: dict) -> None:
        """Send ``msg`` on the vehicle's ``subtopic`` (QoS of the specification; connection
        retained)."""
        self.client.publish(
            self._topic(subtopic),
            json.dumps(msg),
            qos=QOS.get(subtopic, 0),
            retain=subtopic == "connection",
        )

    def close(self, offline: dict | None = None) -> None:
        """Send ``offline`` (connection OFFLINE) and disconnect cleanly (no last will)."""
        if offline is not None and self.client.is_connected():
            info = self.client.publish(
                self._topic("connection"), json.dumps(offline), qos=1, retain=True
            )
            info.wait_for_publish(5.0)
        self.client.disconnect()
        self.client.loop_stop()
