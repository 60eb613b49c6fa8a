"""A Foxglove WebSocket client written to the published protocol, for the live tests.

Independent of the server under test: the ``websockets`` package, the message layout of
the Foxglove WebSocket protocol specification (``foxglove/ws-protocol``, docs/spec.md), and
rosbags' own CDR (de)serializer for the payloads. The foxglove-sdk server names the
subprotocol ``foxglove.sdk.v1`` (the same messages as ``foxglove.websocket.v1``; the SDK
refuses the old name, as foxglove_bridge 3.x does).

Server -> client: JSON ``serverInfo``, ``advertise``, ``advertiseServices``, ``status``,
``serviceCallFailure``; binary ``0x01`` message data ``u32 subscription id | u64 log time ns |
payload``, ``0x02`` time ``u64 ns``, ``0x03`` service call response ``u32 service id | u32 call
id | u32 encoding length | encoding | payload``. Client -> server: JSON ``subscribe``,
``advertise``; binary ``0x01`` ``u32 client channel id | payload`` and ``0x02`` service call
request (the response's layout). All integers little endian.
"""

from __future__ import annotations

import json
import re
import struct
import subprocess
import time

SUBPROTOCOL = "foxglove.sdk.v1"


class FoxgloveClient:
    """One connection; :attr:`channels` (topic -> advertised channel) and :attr:`services` (name ->
    service)."""

    def __init__(self, url: str, timeout_s: float = 20.0):
        from websockets.sync.client import connect

        deadline = time.monotonic() + timeout_s
        while True:
            try:
                self._connection = connect(
                    url, subprotocols=[SUBPROTOCOL], open_timeout=5, max_size=None
                )
                self.ws = self._connection.__enter__()
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.05)
        self.info: dict = {}
        self.channels: dict[str, dict] = {}
        self.services: dict[str, dict] = {}
        self.statuses: list[dict] = []
        self.failures: list[dict] = []
        self.times_ns: list[int] = []
        self._subs: dict[int, str] = {}
        self._next_id = 1
        self._responses: dict[int, tuple[str, bytes]] = {}
        self.closed = False
        """The server closed the connection (the twin's run ended)."""

    def close(self) -> None:
        self._connection.__exit__(None, None, None)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- receiving ------------------------------------------------------------------
    def _handle(self, frame, out: list | None) -> None:
        if isinstance(frame, str):
            msg = json.loads(frame)
            op = msg["op"]
            if op == "serverInfo":
                self.info = msg
            elif op == "advertise":
                for ch in msg["channels"]:
                    self.channels[ch["topic"]] = ch
            elif op == "advertiseServices":
                for sv in msg["services"]:
                    self.services[sv["name"]] = sv
            elif op == "status":
                self.statuses.append(msg)
            elif op == "serviceCallFailure":
                self.failures.append(msg)
            return
        opcode = frame[0]
        if opcode == 0x01:
            sub_id, t_ns = struct.unpack_from("<IQ", frame, 1)
            if out is not None and sub_id in self._subs:
                out.append((time.monotonic(), self._subs[sub_id], t_ns, bytes(frame[13:])))
        elif opcode == 0x02:
            self.times_ns.append(struct.unpack_from("<Q", frame, 1)[0])
        elif opcode == 0x03:
            _service, call_id, n = struct.unpack_from("<III", frame, 1)
            self._responses[call_id] = (frame[13 : 13 + n].decode(), bytes(frame[13 + n :]))

    def pump(self, duration_s: float, out: list | None = None, until=None) -> list:
        """Read frames for ``duration_s`` (or until ``until()`` is true); data messages go to
        ``out``."""
        from websockets.exceptions import ConnectionClosed

        out = [] if out is None else out
        end = time.monotonic() + duration_s
        while time.monotonic() < end and not (until is not None and until()):
            try:
                frame = self.ws.recv(timeout=max(0.001, min(0.05, end - time.monotonic())))
            except TimeoutError:
                continue
            except ConnectionClosed:
                self.closed = True
                break
            self._handle(frame, out)
        return out

    def wait_for_channels(self, topics, timeout_s: float = 10.0) -> None:
        self.pump(timeout_s, until=lambda: all(t in self.channels for t in topics))
        missing = [t for t in topics if t not in self.channels]
        assert not missing, f"not advertised: {missing}"

    # -- sending --------------------------------------------------------------------
    def subscribe(self, topics) -> None:
        subs = []
        for topic in topics:
            sub_id = self._next_id
            self._next_id += 1
            self._subs[sub_id] = topic
            subs.append({"id": sub_id, "channelId": self.channels[topic]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    def advertise(
        self, topic: str, schema_name: str, encoding: str = "cdr", channel_id: int | None = None
    ) -> int:
        channel_id = channel_id if channel_id is not None else 100 + self._next_id
        self._next_id += 1
        self.ws.send(
            json.dumps(
                {
                    "op": "advertise",
                    "channels": [
                        {
                            "id": channel_id,
                            "topic": topic,
                            "encoding": encoding,
                            "schemaName": schema_name,
                        }
                    ],
                }
            )
        )
        return channel_id

    def publish(self, channel_id: int, payload: bytes) -> None:
        self.ws.send(b"\x01" + struct.pack("<I", channel_id) + payload)

    def call_service(
        self, name: str, payload: bytes, encoding: str = "cdr", timeout_s: float = 10.0
    ):
        """(encoding, payload) of the response, or None on a failure (see :attr:`failures`)."""
        call_id = self._next_id
        self._next_id += 1
        enc = encoding.encode()
        self.ws.send(
            b"\x02"
            + struct.pack("<III", self.services[name]["id"], call_id, len(enc))
            + enc
            + payload
        )
        n_fail = len(self.failures)
        self.pump(
            timeout_s, until=lambda: call_id in self._responses or len(self.failures) > n_fail
        )
        return self._responses.get(call_id)


def start_cli(args: list[str], amr_twin: str) -> tuple[subprocess.Popen, str]:
    """Start ``amr-twin ARGS`` (with ``--live --port 0``) and return it with the server's URL from
    stderr."""
    proc = subprocess.Popen(
        [amr_twin, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    lines = []
    for line in proc.stderr:
        lines.append(line)
        found = re.search(r"(ws://[\d.]+:\d+)", line)
        if found:
            return proc, found.group(1)
    proc.wait(timeout=30)
    raise AssertionError(
        f"no server address printed; exit {proc.returncode}: {''.join(lines)[-2000:]}"
    )
