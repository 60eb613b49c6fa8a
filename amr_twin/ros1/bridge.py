"""The twin's bus and state on a ROS 1 graph, both ways: :class:`Ros1Bridge`.

Reasons and measurements: docs/how-to/ros1.md#amr_twinros1bridge."""

from __future__ import annotations

import logging
import threading
import warnings

from amr_twin.recording.mcap_log import BUS_TOPICS, JOINT_STATE_PERIOD_US, REQUEST_FIELDS
from amr_twin.ros import ros_state
from amr_twin.ros.geometry_messages import TFMessage
from amr_twin.ros.messages import Float64MultiArray, MultiArrayDimension, MultiArrayLayout
from amr_twin.ros1.frame_blocks import StateBlocks, clock_block
from amr_twin.ros1.map_transform import MapTransform
from amr_twin.ros1.messages import InputError, Ros1Messages, twist_from_ros, wheel_command_from_ros
from amr_twin.ros1.outbox import Outbox
from amr_twin.ros1.serialization import WRITERS
from amr_twin.ros1.status_topics import StatusTopics

LOG = logging.getLogger(__name__)

FIRMWARE_TOPICS = ("wheel_Command", "wheel0_Vel", "wheel1_Vel")
GRAPH_INPUTS = ("wheel_Command", "cmd_vel")
"""Bus topics the bridge publishes on with the graph's messages (not written back to the graph)."""


class Ros1Bridge:
    """Publish ``twin`` on the ROS 1 graph rospy joined, and take its inputs; a sink of ``pacer``.

    Parameters
    ----------
    twin : Twin
        Built, not yet run; a bus tap, two grid samplers and a clock event are attached to it.
    pacer : Pacer
        Runs the graph's inputs in the twin's thread and calls :meth:`flush` at its ticks.
    firmware_topics : bool
        Carry ``wheel_Command`` in and ``wheelN_Vel`` out (False: a rosserial host does).
    clock_period_us : int
        Period of ``/clock``, simulated us (100 Hz: what the recordings hold).
    """

    def __init__(self, twin, pacer, firmware_topics: bool = True, clock_period_us: int = 10_000):
        self.conv = conv = Ros1Messages()
        rospy = self.rospy = conv.rospy
        self.twin, self.pacer, self.bus = twin, pacer, twin.bus
        self.dropped = 0
        """Messages from the graph refused (each logged)."""
        self._clock_period_us = int(clock_period_us)
        self.out = Outbox(self._clock_period_us)
        self._closed = False
        self._from_graph: str | None = (
            None  # the bus topic of a message being handed over from the graph
        )
        self._lock = threading.Lock()
        sensors = "lidar" in twin.sensors
        skip = set() if sensors else {"scan", "imu/data_raw", "imu/mag"}
        if not firmware_topics:
            skip.update(FIRMWARE_TOPICS)

        def pub(topic, typ, latch=False):
            with (
                warnings.catch_warnings()
            ):  # rospy warns of a publisher without a queue: this one is meant
                warnings.simplefilter("ignore")
                return rospy.Publisher(topic, conv.ros_class(typ), queue_size=None, latch=latch)

        self.pubs = {
            bus: pub(topic.lstrip("/"), typ)
            for bus, (topic, typ, _enc) in BUS_TOPICS.items()
            if bus not in skip and not (bus == "uwb/range" and "uwb" not in twin.sensors)
        }
        self.pubs["tf_static"] = pub("tf_static", "tf2_msgs/TFMessage", latch=True)
        self.tf = self.pubs["tf"]
        self.map_tf = MapTransform()
        """``map -> odom`` on ``/tf`` from the localisation's pose in ``map``
        (:mod:`amr_twin.ros1.map_transform`)."""
        self._fast = {
            bus: (p, WRITERS[BUS_TOPICS[bus][1]])
            for bus, p in self.pubs.items()
            if bus in BUS_TOPICS
            and BUS_TOPICS[bus][1] in WRITERS
            and bus != "wheel_Command_Service/request"
        }
        """Bus topic -> (publisher, writer): the twin's messages written as they are, straight to
        the outbox."""
        self._feeds = {
            bus: self.out.feeder(p, writer)
            for bus, (p, writer) in self._fast.items()
            if bus not in MapTransform.TOPICS and bus not in GRAPH_INPUTS
        }
        """Bus topic -> its :meth:`Outbox.feeder`, a bus tap of that topic alone: the fast topics
        neither the map transform reads nor the graph publishes on (one call a message)."""
        self.clock_pub = self.out.lead = pub("/clock", "rosgraph_msgs/Clock")
        self.state_pubs = {
            "/twin/ground_truth": pub("twin/ground_truth", "nav_msgs/Odometry"),
            "/joint_states": pub("joint_states", "sensor_msgs/JointState"),
        }
        self.status = StatusTopics(twin, conv, self.out, pub)
        """``/twin/*`` rows, ``/battery_state``, ``/diagnostics``
        (:mod:`amr_twin.ros1.status_topics`)."""
        self.description_pub = pub("robot_description", "std_msgs/String", latch=True)
        self.description_pub.publish(conv.ros_class("std_msgs/String")(data=twin.urdf))
        self.pubs["tf_static"].publish(conv.to_ros(TFMessage(self.bus.static_transforms())))
        self._subs = []
        if firmware_topics:
            self._subs.append(
                rospy.Subscriber(
                    "wheel_Command",
                    conv.ros_class("std_msgs/Float64MultiArray"),
                    self._on_wheel_command,
                    queue_size=100,
                )
            )
        self._subs.append(
            rospy.Subscriber(
                "cmd_vel", conv.ros_class("geometry_msgs/Twist"), self._on_cmd_vel, queue_size=100
            )
        )
        self._services = []
        if self.bus.has_service("start_motor"):
            from std_srvs.srv import Empty, EmptyResponse

            for name in ("start_motor", "stop_motor"):

                def handler(_req, name=name):
                    self.pacer.call(lambda: self.bus.call_service(name, None))
                    return EmptyResponse()

                self._services.append(rospy.Service(name, Empty, handler))
        self._state = ros_state.StateSampler(twin.observables.model, twin.observables.named)
        twin.on_grid(self._state.sample)
        self._state.sample(twin.t_phys_us)
        self._frames = StateBlocks(
            self._state.joint_names,
            self._state.child_frames,
            ros_state.BASE_FRAME,
            ros_state.WORLD_FRAME,
        )
        for topic, feed in self._feeds.items():
            twin.on_message(feed, topics=(topic,))
        twin.on_message(
            self._tap, topics=tuple((set(self.pubs) | MapTransform.TOPICS) - set(self._feeds))
        )
        self._next_clock_us = -(-twin.clock.now_us // self._clock_period_us) * self._clock_period_us

    def start(self) -> None:
        """The graph's subscribers have connected (before the run): keep the recorder's rows if one
        of their topics is wanted (later, from the first flush that finds a subscriber)."""
        self.status.collect(self.twin.clock.now_us)

    # -- out (the twin's thread) ------------------------------------------------------------
    def _tap(self, topic: str, msg, t_us: int) -> None:
        if topic in MapTransform.TOPICS and Outbox.wanted(self.tf):
            due = self.map_tf.take(topic, msg)
            if due is not None:
                self.out.put(self.tf, due[1], due[0])
        fast = self._fast.get(topic)
        if fast is not None:
            pub, writer = fast
            impl = pub.impl
            if impl is not None and impl.connections and topic != self._from_graph:
                self.out.put(pub, writer(msg), t_us)
            return
        pub = self.pubs.get(topic)
        if pub is None or topic == self._from_graph:
            return
        if topic == "tf_static":  # latched: rospy keeps it for later subscribers
            pub.publish(self.conv.to_ros(msg))
            return
        if not Outbox.wanted(pub):
            return
        if topic == "wheel_Command_Service/request":
            msg = Float64MultiArray(
                MultiArrayLayout([MultiArrayDimension(REQUEST_FIELDS, 4, 4)]),
                [float(msg.motionL), float(msg.speedL), float(msg.motionR), float(msg.speedR)],
            )
        writer = WRITERS.get(msg._type)
        if writer is None:
            self.status.put_ros(pub, self.conv.to_ros(msg), t_us)
        else:
            self.out.put(pub, writer(msg), t_us)

    def _publish_clock(self, t_us: int) -> None:
        """``/clock`` at each multiple of the clock's period up to ``t_us``."""
        if self._next_clock_us > t_us:
            return
        times = list(range(self._next_clock_us, t_us + 1, self._clock_period_us))
        self._next_clock_us = times[-1] + self._clock_period_us
        if Outbox.wanted(self.clock_pub):
            self.out.put_block(self.clock_pub, times, clock_block(times))

    def release(self, t_us: int, wait) -> None:
        """Paced (the pacer's tick, before it sleeps): write what is due up to ``t_us`` at each
        clock instant's wall time, ``wait(instant)`` (the pacer's sleep) before each."""
        self._collect(t_us)
        self.out.release(t_us, wait)

    def flush(self, t_us: int) -> None:
        """Write everything due up to ``t_us`` (simulated) at once, ``/clock`` first."""
        self._collect(t_us)
        self.out.release(t_us)

    def _collect(self, t_us: int) -> None:
        """The clock, the grid samples and events up to ``t_us`` into the outbox."""
        self._publish_clock(t_us)
        self._publish_state(t_us)
        self.status.collect(t_us)

    def _publish_state(self, t_us: int) -> None:
        batch = self._state.split(t_us)
        gt, js, out = (
            self.state_pubs["/twin/ground_truth"],
            self.state_pubs["/joint_states"],
            self.out,
        )
        want_gt, want_js, want_tf = Outbox.wanted(gt), Outbox.wanted(js), Outbox.wanted(self.tf)
        if not (len(batch) and (want_gt or want_js or want_tf)):
            return
        b = self._frames.blocks(batch, JOINT_STATE_PERIOD_US, want_gt, want_js, want_tf)
        if want_gt:
            out.put_block(gt, b.t_us, b.ground_truth)
        if want_js:
            out.put_block(js, b.kept_us, b.joint_states)
        if want_tf:
            out.put_block(self.tf, b.kept_us, b.link_transforms)

    # -- in (rospy's threads) ------------------------------------------------------------------
    def _own(self, msg) -> bool:
        return msg._connection_header.get("callerid") == self.rospy.get_name()

    def _post(self, what: str, topic: str, convert, msg) -> None:
        if self._own(msg):
            return
        try:
            value = convert(msg)
        except InputError as exc:
            with self._lock:
                self.dropped += 1
            LOG.warning(
                "ros1: dropped %s from %s: %s", what, msg._connection_header.get("callerid"), exc
            )
            return

        def act():
            self._from_graph = topic
            try:
                self.bus.publish(topic, value)
            finally:
                self._from_graph = None

        try:
            self.pacer.post(act)
        except RuntimeError:  # the twin has stopped
            pass

    def _on_wheel_command(self, msg) -> None:
        self._post("a wheel_Command", "wheel_Command", wheel_command_from_ros, msg)

    def _on_cmd_vel(self, msg) -> None:
        self._post("a cmd_vel", "cmd_vel", twist_from_ros, msg)

    def close(self) -> None:
        """Stop publishing and taking inputs (a second call does nothing)."""
        if self._closed:
            return
        self._closed = True
        self.out.flush()
        for hooked in (self._tap, *self._feeds.values()):
            self.twin.unhook(hooked)
        for sub in self._subs:
            sub.unregister()
        for srv in self._services:
            srv.shutdown()
        for pub in [
            *self.pubs.values(),
            self.clock_pub,
            *self.state_pubs.values(),
            *self.status.publishers,
            self.description_pub,
        ]:
            pub.unregister()
