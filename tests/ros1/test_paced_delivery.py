"""Paced at real time, the twin writes each message when it is stamped, as a ROS node does: a
queue_size=1 rospy subscriber (Debian's rospy, a process of its own) gets nearly every IMU message
and every /clock and /clock arrives at 100 Hz; and no IMU message is written before the /clock of
its instant, as a reader of both connections in one thread sees them (rospy's subscriber reads each
topic in a thread of its own, which a busy machine wakes late: what it sees of the order is its own
scheduling)."""

import json
import select
import socket
import struct
import subprocess
import sys
import threading
import time
import xmlrpc.client
import xmlrpc.server
from pathlib import Path


from conftest import needs_ros1, stop, subscribers, wait_for

AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))
WINDOW = (0.5, 5.5)
"""The stamps counted, simulated s: 500 IMU messages and 500 clocks of a 6 s run at --rate 1."""

SUBSCRIBER = """
import json, sys, threading, time
import rospy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
lock, clocks, imus = threading.Lock(), [], []
rospy.init_node("test_paced_delivery")
def on_clock(m):
    with lock:
        clocks.append((m.clock.to_sec(), time.perf_counter()))
def on_imu(m):
    with lock:
        imus.append(m.header.stamp.to_sec())
rospy.Subscriber("/clock", Clock, on_clock, queue_size=1)
rospy.Subscriber("/imu/data_raw", Imu, on_imu, queue_size=1)
print("ready", flush=True)
sys.stdin.read()  # the test closes it once the twin has exited
with lock:
    print(json.dumps({"clocks": clocks, "imus": imus}), flush=True)
"""


_U32 = struct.Struct("<I")
ORDERED = {"/clock": ("rosgraph_msgs/Clock", 0), "/imu/data_raw": ("sensor_msgs/Imu", 4)}
"""The topics the in-order reader takes: type, and where the stamp is in a message (bytes)."""


class InOrderReader:
    """A subscriber of /clock and /imu/data_raw of its own (TCPROS, registered with the master so
    the twin waits for it) that reads both connections in one thread: at each wake it takes the IMU
    connection's bytes, then every byte the clock connection has. A clock written before an IMU
    message is then known when that message is, whatever the scheduling; ``leads`` are the IMU
    stamps less the latest clock known then, s."""

    def __init__(self, env, name: str = "/test_paced_in_order"):
        self.master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
        self.name, self.leads, self.error = name, [], None
        self._api = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
        self._api.register_function(lambda *_a: [1, "", 0], "publisherUpdate")
        threading.Thread(target=self._api.serve_forever, daemon=True).start()
        uri = f"http://127.0.0.1:{self._api.server_address[1]}/"
        for topic, (typ, _at) in ORDERED.items():
            self.master.registerSubscriber(name, topic, typ, uri)
        self._uri = uri
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _connect(self, topic: str) -> socket.socket:
        deadline = time.monotonic() + 60
        while True:  # the twin's node, then its publisher of topic
            code, _m, api = self.master.lookupNode(self.name, "/amr_twin")
            if code == 1:
                code, _m, proto = xmlrpc.client.ServerProxy(api).requestTopic(
                    self.name, topic, [["TCPROS"]]
                )
                if code == 1:
                    break
            assert time.monotonic() < deadline, f"no publisher of {topic}"
            time.sleep(0.02)
        sock = socket.create_connection((proto[1], proto[2]), timeout=30)
        fields = [
            f"{k}={v}".encode()
            for k, v in dict(
                callerid=self.name, topic=topic, md5sum="*", type=ORDERED[topic][0], tcp_nodelay=1
            ).items()
        ]
        body = b"".join(_U32.pack(len(f)) + f for f in fields)
        sock.sendall(_U32.pack(len(body)) + body)
        (n,) = _U32.unpack(self._exactly(sock, 4))
        reply = self._exactly(sock, n)
        assert b"error=" not in reply, reply
        sock.setblocking(False)
        return sock

    @staticmethod
    def _exactly(sock, n: int) -> bytes:
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            assert chunk, "connection closed during the handshake"
            data += chunk
        return data

    def _run(self) -> None:
        try:
            socks = {topic: self._connect(topic) for topic in ORDERED}
            bufs, latest, live = {t: bytearray() for t in socks}, -1.0, set(socks)
            while live:
                if not select.select([socks[t] for t in live], [], [], 30)[0]:
                    break  # the twin went quiet without closing
                for topic in ("/imu/data_raw", "/clock"):  # the IMU's bytes first
                    while topic in live:
                        try:
                            chunk = socks[topic].recv(65536)
                        except BlockingIOError:
                            break
                        if not chunk:
                            live.discard(topic)
                        bufs[topic] += chunk
                for topic in ("/clock", "/imu/data_raw"):  # then the clocks known first
                    buf, at = bufs[topic], ORDERED[topic][1]
                    while len(buf) >= 4 and len(buf) >= 4 + _U32.unpack_from(buf)[0]:
                        sec, nsec = struct.unpack_from("<II", buf, 4 + at)
                        stamp = sec + nsec * 1e-9
                        if topic == "/clock":
                            latest = max(latest, stamp)
                        else:
                            self.leads.append((stamp, stamp - latest))
                        del buf[: 4 + _U32.unpack_from(buf)[0]]
        except Exception as exc:  # noqa: BLE001 - reported by the test
            self.error = exc

    def close(self, timeout_s: float = 30) -> None:
        """Wait for the twin's connections to end; leave the graph."""
        self._thread.join(timeout_s)
        for topic in ORDERED:
            self.master.unregisterSubscriber(self.name, topic, self._uri)
        self._api.shutdown()
        self._api.server_close()


@needs_ros1
def test_paced_messages_go_one_by_one_at_their_stamps_behind_the_clock(ros_env):
    sub = subprocess.Popen(
        ["/usr/bin/python3", "-c", SUBSCRIBER],
        env=ros_env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    reader = None
    try:
        assert sub.stdout.readline().strip() == "ready"
        reader = InOrderReader(ros_env)
        wait_for(
            lambda: "/test_paced_delivery" in subscribers(ros_env, "/imu/data_raw"),
            "the subscriber on the graph",
        )
        run = subprocess.run(
            [
                AMR_TWIN,
                "run",
                "stop",
                "--duration-s",
                "6",
                "--world",
                "empty",
                "--sensors",
                "--ros1",
                "--rate",
                "1",
            ],
            env=ros_env,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert run.returncode == 0, run.stderr
        got = json.loads(sub.communicate("", timeout=30)[0].splitlines()[-1])
    finally:
        stop(sub)
        if reader is not None:
            reader.close()
    lo, hi = WINDOW
    imus = [s for s in got["imus"] if lo <= s < hi]
    clocks = [(s, w) for s, w in got["clocks"] if lo <= s < hi]
    # per tick bursts (two IMU messages and two clocks in one write every 20 ms) kept half of each
    assert len(imus) >= 450, len(imus)
    assert len(clocks) >= 450, len(clocks)
    hz = (len(clocks) - 1) / (
        clocks[-1][1] - clocks[0][1]
    )  # as rostopic hz: arrivals over wall time
    assert 95.0 <= hz <= 105.0, hz
    # The twin writes each /clock before the messages of its instant (tests/ros1/test_outbox.py);
    # read in one thread, in the order written, no IMU message is ahead of the clocks before it
    assert reader.error is None, reader.error
    ordered = [(s, lead) for s, lead in reader.leads if lo <= s < hi]
    assert len(ordered) == 500, len(ordered)  # a subscriber with a queue gets them all
    assert max(lead for _s, lead in ordered) <= 1e-6, max(ordered, key=lambda x: x[1])
