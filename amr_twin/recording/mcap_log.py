"""Record a run as ROS 2 messages in an ``.mcap`` file.

The same streams as :mod:`amr_twin.recording.rerun_log`, CDR-encoded (:mod:`amr_twin.ros.ros2_cdr`)
with ROS 2 message definitions (schema encoding ``ros2msg``, :mod:`amr_twin.ros.ros2_schemas`),
so ``ros2 bag info/play`` (rosbag2 MCAP storage) and Foxglove read the file. Log and
publish times are the simulation time (ns) at which the bus delivered the message;
header stamps are the messages' own. Bus topics are the messages the nodes published
(as they were); the robot's state (joint states, link transforms, ground truth,
clock) is built by :mod:`amr_twin.ros.ros_state` from the capture's samples.

Reasons and measurements: docs/reference/recordings.md#amr_twinrecordingmcap_log."""

from __future__ import annotations

import collections
from pathlib import Path

import numpy as np

from amr_twin.ros import ros_state
from amr_twin.base.atomic_file import replacing
from amr_twin.recording.event_log import mcap_items as event_items
from amr_twin.ros.geometry_messages import TFMessage
from amr_twin.ros.messages import String
from amr_twin.ros.ros2_cdr import (
    encode_battery_state,
    encode_clock,
    encode_float64,
    encode_float64_multi_array,
    encode_float64_multi_array_msg,
    encode_imu,
    encode_joint_state,
    encode_laser_scan,
    encode_magnetic_field,
    encode_odometry,
    encode_pose_array,
    encode_pose_with_covariance_stamped,
    encode_range,
    encode_string,
    encode_tf_message,
    encode_twist,
)
from amr_twin.ros.nav_messages import encode_occupancy_grid, encode_path, encode_polygon_stamped
from amr_twin.ros.ros2_schemas import msgdef, ros2_type

REQUEST_FIELDS = "motionL,speedL,motionR,speedR"
"""Label of the one dimension of a recorded ``wheel_Command_Service`` request."""
JOINT_STATE_PERIOD_US = 20_000
"""Period of /joint_states and of the joints' links on /tf, us (50 Hz)."""
BATTERY_EVERY_ROWS = 10
"""/battery_state every 10th row of the 100 Hz record grid (10 Hz)."""
LATCHED = ("/tf_static", "/robot_description", "/map")
"""Topics offered transient-local (a late subscriber gets the last message)."""


def _encode_request(req) -> bytes:
    return encode_float64_multi_array(
        [float(req.motionL), float(req.speedL), float(req.motionR), float(req.speedR)],
        REQUEST_FIELDS,
    )


# bus topic -> (ROS 2 topic, type, encoder); the order breaks ties of equal log times
BUS_TOPICS = {
    "odom": ("/odom", "nav_msgs/Odometry", encode_odometry),
    "tf": ("/tf", "tf2_msgs/TFMessage", encode_tf_message),
    "cmd_vel": ("/cmd_vel", "geometry_msgs/Twist", encode_twist),
    "wheel_Command_Service/request": (
        "/wheel_Command_Service/request",
        "std_msgs/Float64MultiArray",
        _encode_request,
    ),
    "wheel_Command": (
        "/wheel_Command",
        "std_msgs/Float64MultiArray",
        encode_float64_multi_array_msg,
    ),
    "wheel0_Vel": ("/wheel0_Vel", "std_msgs/Float64", encode_float64),
    "wheel1_Vel": ("/wheel1_Vel", "std_msgs/Float64", encode_float64),
    "scan": ("/scan", "sensor_msgs/LaserScan", encode_laser_scan),
    "imu/data_raw": ("/imu/data_raw", "sensor_msgs/Imu", encode_imu),
    "imu/mag": ("/imu/mag", "sensor_msgs/MagneticField", encode_magnetic_field),
    "uwb/range": ("/uwb/range", "sensor_msgs/Range", encode_range),
    "ground_truth/odom": ("/ground_truth/odom", "nav_msgs/Odometry", encode_odometry),
    "odometry/filtered": ("/odometry/filtered", "nav_msgs/Odometry", encode_odometry),
    "map_match/pose": (
        "/map_match/pose",
        "geometry_msgs/PoseWithCovarianceStamped",
        encode_pose_with_covariance_stamped,
    ),
    "plan": ("/plan", "nav_msgs/Path", encode_path),
    "map": ("/map", "nav_msgs/OccupancyGrid", encode_occupancy_grid),
    "local_costmap/costmap": (
        "/local_costmap/costmap",
        "nav_msgs/OccupancyGrid",
        encode_occupancy_grid,
    ),
    "local_costmap/published_footprint": (
        "/local_costmap/published_footprint",
        "geometry_msgs/PolygonStamped",
        encode_polygon_stamped,
    ),
    "actors/poses": ("/actors/poses", "geometry_msgs/PoseArray", encode_pose_array),
}


def _state_items(capture, k0: int, ns=None) -> list[tuple[int, int, str, str, bytes]]:
    """/clock, /twin/ground_truth, /joint_states and the joints' links on /tf from the capture's
    state samples; with ``ns`` (a :class:`~amr_twin.ros.robot_namespace.RobotNamespace`) no
    /clock, the robot's topics and frames."""
    st = capture.state
    a = {key: v.tolist() for key, v in st.arrays().items()}  # Python floats: cheaper per message
    truth, joints = (
        ("/twin/ground_truth", "/joint_states")
        if ns is None
        else (
            ns.topic("/twin/ground_truth"),
            ns.topic("/joint_states"),
        )
    )
    frames = ns.message if ns is not None else (lambda msg: msg)
    items, k = [], k0
    for i, t_us in enumerate(a["t_us"]):
        t = t_us * 1000
        if ns is None:
            items.append(
                (t, k, "/clock", "rosgraph_msgs/Clock", encode_clock(ros_state.clock(t_us)))
            )
        items.append(
            (
                t,
                k + 1,
                truth,
                "nav_msgs/Odometry",
                encode_odometry(
                    frames(
                        ros_state.ground_truth(
                            t_us, a["pos"][i], a["quat"][i], a["v_body"][i], a["w_body"][i]
                        )
                    )
                ),
            )
        )
        if t_us % JOINT_STATE_PERIOD_US == 0:
            items.append(
                (
                    t,
                    k + 2,
                    joints,
                    "sensor_msgs/JointState",
                    encode_joint_state(
                        ros_state.joint_state(t_us, st.joint_names, a["q"][i], a["qd"][i])
                    ),
                )
            )
            items.append(
                (
                    t,
                    k + 3,
                    "/tf",
                    "tf2_msgs/TFMessage",
                    encode_tf_message(
                        frames(
                            ros_state.link_transforms(
                                t_us, st.child_frames, a["link_pos"][i], a["link_quat"][i]
                            )
                        )
                    ),
                )
            )
        k += 4
    return items


_QOS = (
    "- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n"
    "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n  liveliness: 1\n"
    "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n  avoid_ros_namespace_conventions: "
    "false"
)


def qos_profile(topic: str) -> str:
    """``offered_qos_profiles`` channel metadata, required by the MCAP ``ros2`` profile.

    rosbag2's pre-Jazzy YAML form (integers: history 1 keep-last, reliability 1
    reliable, durability 1 transient-local / 2 volatile). ``/tf_static`` and
    ``/robot_description`` are transient-local with depth 1, as tf2's static
    broadcaster and robot_state_publisher offer them, so that ``ros2 bag play``
    re-publishes them in a way tf2's static listener and RViz accept (a robot's of a fleet,
    ``/amr-1/robot_description``, as well).
    """
    if topic.endswith(LATCHED):  # a robot's own too: /amr-1/robot_description
        return _QOS.format(depth=1, durability=1)
    return _QOS.format(depth=10, durability=2)


def run_items(capture, series, ns=None) -> list[tuple[int, int, str, str, bytes]]:
    """``(t_ns, order, topic, type, CDR payload)`` of a robot's bus messages, its ``series``
    rows and its state samples (:func:`_state_items`); with ``ns`` (a
    :class:`~amr_twin.ros.robot_namespace.RobotNamespace`) under the robot's topics and frames,
    without /clock."""
    items: list[tuple[int, int, str, str, bytes]] = []  # t_ns, order, topic, type, CDR payload
    k = 0
    for bus_topic, (topic, typ, encode) in BUS_TOPICS.items():
        msgs = capture.messages.get(bus_topic, [])
        if ns is not None:
            topic, msgs = ns.topic(topic), [(t_us, ns.message(m)) for t_us, m in msgs]
        for t_us, msg in msgs:
            items.append((int(t_us) * 1000, k, topic, typ, encode(msg)))
            k += 1
    t_ns = np.round(series.t_s * 1e9).astype(np.int64).tolist()
    true_rpm, pwm, current = (
        series.true_rpm.tolist(),
        series.pwm_counts.tolist(),
        series.current_a.tolist(),
    )
    volts, amps, soc = (
        series.battery_v.tolist(),
        series.battery_a.tolist(),
        series.battery_soc.tolist(),
    )
    capacity = capture.twin.cfg.battery.capacity_ah
    names = ("/twin/true_rpm", "/twin/pwm_counts", "/twin/motor_current", "/battery_state")
    rpm_t, pwm_t, current_t, battery_t = names if ns is None else map(ns.topic, names)
    frame = "base_link" if ns is None else ns.frame("base_link")
    arrays, columns = (
        "std_msgs/Float64MultiArray",
        ((rpm_t, true_rpm), (pwm_t, pwm), (current_t, current)),
    )
    for i, t in enumerate(t_ns):
        for j, (topic, column) in enumerate(columns):
            items.append((t, k + j, topic, arrays, encode_float64_multi_array(column[i])))
        if i % BATTERY_EVERY_ROWS == 0:
            charge = soc[i] * capacity
            state = encode_battery_state(t, volts[i], -amps[i], charge, capacity, soc[i], frame)
            items.append((t, k + 3, battery_t, "sensor_msgs/BatteryState", state))
        k += 4
    return items + _state_items(capture, k, ns)


def write_mcap(capture, series, path: Path) -> Path:
    """Write the capture's bus messages and ``series`` to ``path`` (.mcap), through a temporary
    file."""
    items = run_items(capture, series)
    bus = capture.twin.bus
    items.append(
        (0, -2, "/robot_description", "std_msgs/String", encode_string(String(capture.twin.urdf)))
    )
    items.append(
        (
            0,
            -1,
            "/tf_static",
            "tf2_msgs/TFMessage",
            encode_tf_message(TFMessage(bus.static_transforms())),
        )
    )
    items += event_items(
        capture.twin, len(items)
    )  # /twin/collisions, /twin/faults (amr_twin/recording/event_log.py)
    return write_items(items, path)


def write_items(items: list[tuple[int, int, str, str, bytes]], path: Path) -> Path:
    """Write ``(t_ns, order, topic, type, CDR payload)`` items to ``path`` (.mcap, profile
    ``ros2``) in time order (ties: ``order``), through a temporary file."""
    from mcap.writer import Writer

    path = Path(path)
    items.sort(key=lambda it: (it[0], it[1]))
    with replacing(path) as tmp:
        with open(tmp, "wb") as f:
            writer = Writer(f)
            writer.start(profile="ros2", library="amr_twin")
            writer.add_metadata("rosbag2", {"ROS_DISTRO": "humble"})
            schemas, channels, seq = {}, {}, collections.Counter()
            for _t, _k, topic, typ, _data in items:
                if typ not in schemas:
                    schemas[typ] = writer.register_schema(
                        name=ros2_type(typ), encoding="ros2msg", data=msgdef(typ).encode()
                    )
                if topic not in channels:
                    channels[topic] = writer.register_channel(
                        topic=topic,
                        message_encoding="cdr",
                        schema_id=schemas[typ],
                        metadata={"offered_qos_profiles": qos_profile(topic)},
                    )
            for t, _k, topic, _typ, data in items:
                seq[topic] += 1
                writer.add_message(
                    channels[topic], log_time=t, data=data, publish_time=t, sequence=seq[topic]
                )
            writer.finish()
    return path
