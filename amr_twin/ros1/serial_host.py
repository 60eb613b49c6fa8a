"""The project's rosserial host: a rospy node bridging a serial port to the ROS 1 graph.

Reasons and measurements: docs/how-to/ros1.md#amr_twinros1serial_host."""

from __future__ import annotations

import io
import os
import select
import struct
import termios
import threading
import time
import tty

from amr_twin.ros.rosserial_frame import (
    ID_PUBLISHER,
    ID_SUBSCRIBER,
    ID_TIME,
    ID_TX_STOP,
    FrameParser,
    TopicInfo,
    frame,
)

ID_LOG, ID_PARAMETER_REQUEST = 7, 6
RETRY_S = 0.5
"""Wait between two attempts to open a port that is not there, s (upstream's serial_node keeps
trying too)."""


def open_port(path: str, baud: int) -> int:
    """``path`` opened read/write in raw mode at ``baud`` (a pseudo-terminal ignores the speed)."""
    speed = getattr(termios, f"B{baud}", None)
    if speed is None:
        raise ValueError(f"~baud {baud}: not a speed termios knows")
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)
    attrs = termios.tcgetattr(fd)
    attrs[4] = attrs[5] = speed
    termios.tcsetattr(fd, termios.TCSANOW, attrs)
    termios.tcflush(fd, termios.TCIFLUSH)
    return fd


class SerialHost:
    """The host side of one rosserial link on the file descriptor ``fd`` (see the module notes)."""

    def __init__(self, rospy, fd: int, timeout_s: float = 5.0):
        import roslib.message

        self.rospy, self.fd, self.timeout_s = rospy, fd, timeout_s
        self._get_class = roslib.message.get_message_class
        self._parser = FrameParser()
        self._write_lock = threading.Lock()
        self.publishers: dict[int, tuple] = {}  # topic id -> (rospy Publisher, message class)
        self.subscribers: dict[int, object] = {}
        self.topic_requests = 0
        """Requests for the topics sent: 1 at start, then one per renegotiation."""
        self.renegotiations = 0
        self.time_requests = 0
        self.synced = False
        self.last_sync = rospy.Time.now()

    def write(self, topic_id: int, message: bytes) -> None:
        with self._write_lock:
            os.write(self.fd, frame(topic_id, message))

    def request_topics(self) -> None:
        self.topic_requests += 1
        self.write(ID_PUBLISHER, b"")

    def _message_class(self, info: TopicInfo):
        cls = self._get_class(info.message_type)
        if cls is None:
            self.rospy.logerr(
                "rosserial: topic %s: no message class %s", info.topic_name, info.message_type
            )
        elif cls._md5sum != info.md5sum:
            self.rospy.logerr(
                "rosserial: topic %s: md5sum %s of %s differs from the client's %s",
                info.topic_name,
                cls._md5sum,
                info.message_type,
                info.md5sum,
            )
            cls = None
        return cls

    def _setup_publisher(self, info: TopicInfo) -> None:
        cls = self._message_class(info)
        if cls is not None and info.topic_id not in self.publishers:
            self.publishers[info.topic_id] = (
                self.rospy.Publisher(info.topic_name, cls, queue_size=100),
                cls,
            )
            self.rospy.loginfo("rosserial: publishing %s [%s]", info.topic_name, info.message_type)

    def _setup_subscriber(self, info: TopicInfo) -> None:
        cls = self._message_class(info)
        if cls is None or info.topic_id in self.subscribers:
            return

        def forward(msg, topic_id=info.topic_id):
            buff = io.BytesIO()
            msg.serialize(buff)
            self.write(topic_id, buff.getvalue())

        self.subscribers[info.topic_id] = self.rospy.Subscriber(
            info.topic_name, cls, forward, queue_size=100
        )
        self.rospy.loginfo("rosserial: subscribing %s [%s]", info.topic_name, info.message_type)

    def handle(self, topic_id: int, message: bytes) -> None:
        """One frame from the client."""
        rospy = self.rospy
        if topic_id == ID_PUBLISHER:
            self._setup_publisher(TopicInfo.deserialize(message))
        elif topic_id == ID_SUBSCRIBER:
            self._setup_subscriber(TopicInfo.deserialize(message))
        elif topic_id == ID_TIME:
            now = rospy.Time.now()
            self.write(ID_TIME, struct.pack("<II", now.secs, now.nsecs))
            self.time_requests += 1
            self.last_sync, self.synced = now, True
        elif topic_id in self.publishers:
            pub, cls = self.publishers[topic_id]
            pub.publish(cls().deserialize(message))
        elif topic_id >= 100:
            rospy.logwarn(
                "rosserial: the client published on topic id %d before it was configured", topic_id
            )
            self.request_topics()
        elif topic_id in (ID_LOG, ID_PARAMETER_REQUEST):
            rospy.logwarn_once(
                "rosserial: the client's logging and parameters are not served by this host"
            )

    def check_sync(self) -> None:
        """Drop sync and ask for the topics again after ``3 * timeout`` without a time request."""
        now = self.rospy.Time.now()
        if (
            self.last_sync.is_zero()
        ):  # started before the first /clock (use_sim_time): count from the first
            self.last_sync = now
        elif (now - self.last_sync).to_sec() > 3 * self.timeout_s:
            if self.synced:
                self.rospy.logerr("rosserial: lost sync with the client, restarting")
            else:
                self.rospy.logerr("rosserial: no time request from the client: cannot sync")
            self.renegotiations += 1
            self.request_topics()
            self.last_sync = now

    def spin(self) -> None:
        """Read and handle frames until rospy shuts down; then TX_STOP."""
        self.request_topics()
        try:
            while not self.rospy.is_shutdown():
                ready, _, _ = select.select([self.fd], [], [], 0.05)
                if ready:
                    try:
                        data = os.read(self.fd, 4096)
                    except OSError as exc:
                        self.rospy.logerr("rosserial: reading the port failed: %s", exc)
                        break
                    for f in self._parser.feed(data):
                        self.handle(f.topic_id, f.message)
                self.check_sync()
        finally:
            try:
                self.write(ID_TX_STOP, b"")
            except OSError:
                pass


def main() -> None:
    """The node: ``~port``, ``~baud``, ``~timeout`` (see the module notes)."""
    import rospy

    rospy.init_node("serial_node")
    port = rospy.get_param("~port", "/dev/ttyACM0")
    baud = int(rospy.get_param("~baud", 57600))
    timeout_s = float(rospy.get_param("~timeout", 5.0))
    fd, said = None, False
    while fd is None:
        try:
            fd = open_port(port, baud)
        except ValueError as exc:
            rospy.logfatal("rosserial: cannot open %s: %s", port, exc)
            raise SystemExit(1)
        except OSError as exc:  # not there (yet): a board plugged in later, a twin started later
            if not said:
                rospy.logerr(
                    "rosserial: cannot open %s (%s); trying again every %g s",
                    port,
                    exc.strerror,
                    RETRY_S,
                )
                said = True
            if rospy.is_shutdown():
                return
            time.sleep(RETRY_S)
    rospy.loginfo("rosserial: connected to %s at %d baud", port, baud)
    host = SerialHost(rospy, fd, timeout_s)
    host.spin()
    rospy.loginfo(
        "rosserial: %d topic request(s), %d renegotiation(s), %d time request(s)",
        host.topic_requests,
        host.renegotiations,
        host.time_requests,
    )


if __name__ == "__main__":
    main()
