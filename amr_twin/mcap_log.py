"""Record a run as ROS 2 messages in an ``.mcap`` file (issue 7).

The same streams as :mod:`amr_twin.rerun_log`, CDR-encoded (:mod:`amr_twin.ros2_cdr`)
with ROS 2 message definitions (schema encoding ``ros2msg``, :mod:`amr_twin.ros2_schemas`),
so ``ros2 bag info/play`` (rosbag2 MCAP storage) and Foxglove read the file. Log and
publish times are the simulation time (ns) at which the bus delivered the message;
header stamps are the messages' own.

Topics (frames as in REP-105; ``world`` is the simulation's world frame)::

    /odom              nav_msgs/msg/Odometry          odom -> base_link, 50 Hz
    /tf                tf2_msgs/msg/TFMessage         odom -> base_link, 50 Hz
    /tf_static         tf2_msgs/msg/TFMessage         world -> odom, base_link -> laser, imu_link
    /scan              sensor_msgs/msg/LaserScan      (with TwinOptions(sensors=True))
    /imu/data_raw      sensor_msgs/msg/Imu            (idem)
    /imu/mag           sensor_msgs/msg/MagneticField  (idem)
    /uwb/range         sensor_msgs/msg/Range          one per anchor exchange, frame uwb_anchor_<i>
                                                      (only when a UwbSensor publishes, e.g. the fusion drive)
    /wheel0_Vel, /wheel1_Vel   std_msgs/msg/Float64   RPM as published by the firmware
    /wheel_Command     std_msgs/msg/Float64MultiArray [motionL, speedL, motionR, speedR]
    /twin/true_rpm     std_msgs/msg/Float64MultiArray [left, right], signed, record rate (100 Hz)
    /twin/pwm_counts   std_msgs/msg/Float64MultiArray [left, right] analogWrite counts, 100 Hz
    /twin/ground_truth nav_msgs/msg/Odometry          world -> base_link (true pose), 100 Hz
"""

from __future__ import annotations

import collections
import math
from pathlib import Path

import mujoco
import numpy as np

from .atomic_file import replacing
from .ros2_cdr import (Cdr, encode_float64, encode_float64_multi_array, encode_imu, encode_laser_scan,
                       encode_magnetic_field, encode_odometry, encode_range, encode_tf_message)
from .ros2_schemas import msgdef, ros2_type

_ZERO36 = np.zeros(36)

# bus topic -> (ROS 2 topic, type, encoder)
BUS_TOPICS = {
    "odom": ("/odom", "nav_msgs/Odometry", encode_odometry),
    "tf": ("/tf", "tf2_msgs/TFMessage", encode_tf_message),
    "scan": ("/scan", "sensor_msgs/LaserScan", encode_laser_scan),
    "imu/data_raw": ("/imu/data_raw", "sensor_msgs/Imu", encode_imu),
    "imu/mag": ("/imu/mag", "sensor_msgs/MagneticField", encode_magnetic_field),
    "uwb/range": ("/uwb/range", "sensor_msgs/Range", encode_range),
    "wheel0_Vel": ("/wheel0_Vel", "std_msgs/Float64", encode_float64),
    "wheel1_Vel": ("/wheel1_Vel", "std_msgs/Float64", encode_float64),
    "wheel_Command": ("/wheel_Command", "std_msgs/Float64MultiArray",
                      lambda m: encode_float64_multi_array(m.data)),
}


def _static_tf(capture, series) -> bytes:
    """world -> odom (the start pose), base_link -> laser and imu_link (from the model)."""
    m = capture.twin.physics.model
    x0, y0, yaw0 = (float(v) for v in series.pose[0])
    entries = [("world", "odom", (x0, y0, 0.0), (math.cos(yaw0 / 2), 0.0, 0.0, math.sin(yaw0 / 2)))]
    base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/base_link")
    for body, frame in (("amr/laser", "laser"), ("amr/imu_link", "imu_link")):
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
        if b >= 0 and m.body_parentid[b] == base:
            entries.append(("base_link", frame, m.body_pos[b], m.body_quat[b]))
    c = Cdr()
    c.u32(len(entries))
    for parent, child, xyz, (w, x, y, z) in entries:
        c.header(0, 0, parent)
        c.string(child)
        c.f64(*(float(v) for v in xyz), float(x), float(y), float(z), float(w))
    return bytes(c.b)


def _ground_truth(t_ns: int, pose) -> bytes:
    x, y, yaw = (float(v) for v in pose)
    c = Cdr()
    c.header(t_ns // 1_000_000_000, t_ns % 1_000_000_000, "world")
    c.string("base_link")
    c.f64(x, y, 0.0, 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    c.f64_array(_ZERO36)
    c.f64(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    c.f64_array(_ZERO36)
    return bytes(c.b)


_QOS = ("- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n"
        "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n  liveliness: 1\n"
        "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n  avoid_ros_namespace_conventions: false")


def qos_profile(topic: str) -> str:
    """``offered_qos_profiles`` channel metadata, required by the MCAP ``ros2`` profile.

    rosbag2's pre-Jazzy YAML form (integers: history 1 keep-last, reliability 1
    reliable, durability 1 transient-local / 2 volatile). ``/tf_static`` is
    transient-local with depth 1, as tf2's static broadcaster offers it, so that
    ``ros2 bag play`` re-publishes it in a way tf2's static listener accepts.
    """
    if topic == "/tf_static":
        return _QOS.format(depth=1, durability=1)
    return _QOS.format(depth=10, durability=2)


def write_mcap(capture, series, path: Path) -> Path:
    """Write the capture's bus messages and ``series`` to ``path`` (.mcap), through a temporary file."""
    from mcap.writer import Writer

    path = Path(path)
    items: list[tuple[int, int, str, str, bytes]] = []  # t_ns, order, topic, type, CDR payload
    k = 0
    for bus_topic, (topic, typ, encode) in BUS_TOPICS.items():
        for t_us, msg in capture.messages.get(bus_topic, []):
            items.append((int(t_us) * 1000, k, topic, typ, encode(msg)))
            k += 1
    t_ns = np.round(series.t_s * 1e9).astype(np.int64).tolist()
    true_rpm, pwm, pose = series.true_rpm.tolist(), series.pwm_counts.tolist(), series.pose
    for i, t in enumerate(t_ns):
        items.append((t, k, "/twin/true_rpm", "std_msgs/Float64MultiArray",
                      encode_float64_multi_array(true_rpm[i])))
        items.append((t, k + 1, "/twin/pwm_counts", "std_msgs/Float64MultiArray",
                      encode_float64_multi_array(pwm[i])))
        items.append((t, k + 2, "/twin/ground_truth", "nav_msgs/Odometry", _ground_truth(t, pose[i])))
        k += 3
    items.append((0, -1, "/tf_static", "tf2_msgs/TFMessage", _static_tf(capture, series)))
    items.sort(key=lambda it: (it[0], it[1]))
    with replacing(path) as tmp:
        with open(tmp, "wb") as f:
            writer = Writer(f)
            writer.start(profile="ros2", library="amr_twin")
            writer.add_metadata("rosbag2", {"ROS_DISTRO": "humble"})
            schemas, channels, seq = {}, {}, collections.Counter()
            for _t, _k, topic, typ, _data in items:
                if typ not in schemas:
                    schemas[typ] = writer.register_schema(name=ros2_type(typ), encoding="ros2msg",
                                                          data=msgdef(typ).encode())
                if topic not in channels:
                    channels[topic] = writer.register_channel(topic=topic, message_encoding="cdr",
                                                              schema_id=schemas[typ],
                                                              metadata={"offered_qos_profiles": qos_profile(topic)})
            for t, _k, topic, _typ, data in items:
                seq[topic] += 1
                writer.add_message(channels[topic], log_time=t, data=data, publish_time=t,
                                   sequence=seq[topic])
            writer.finish()
    return path
