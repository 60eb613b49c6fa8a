"""Record a run as ROS 2 messages in an ``.mcap`` file (issue 7).

The same streams as :mod:`amr_twin.rerun_log`, CDR-encoded with ROS 2 message
definitions (schema encoding ``ros2msg``), so ``ros2 bag info/play`` (rosbag2 MCAP
storage) and Foxglove read the file. The CDR payloads are encoded here with
:mod:`struct` (the generic encoder of ``mcap-ros2-support`` costs ~3x more); the
tests decode them with ``mcap_ros2.decoder`` against the same definitions. Log and publish times are the simulation
time (ns) at which the bus delivered the message; header stamps are the
messages' own.

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
import os
import struct
from pathlib import Path

import mujoco
import numpy as np

SEP = "=" * 80

_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "std_msgs/Float64": "float64 data",
    "std_msgs/MultiArrayDimension": "string label\nuint32 size\nuint32 stride",
    "std_msgs/MultiArrayLayout": "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset",
    "std_msgs/Float64MultiArray": "std_msgs/MultiArrayLayout layout\nfloat64[] data",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
    "geometry_msgs/PoseWithCovariance": "geometry_msgs/Pose pose\nfloat64[36] covariance",
    "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular",
    "geometry_msgs/TwistWithCovariance": "geometry_msgs/Twist twist\nfloat64[36] covariance",
    "geometry_msgs/Transform": "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation",
    "geometry_msgs/TransformStamped": ("std_msgs/Header header\nstring child_frame_id\n"
                                       "geometry_msgs/Transform transform"),
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms",
    "sensor_msgs/Imu": ("std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
                        "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n"
                        "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
                        "float64[9] linear_acceleration_covariance"),
    "sensor_msgs/MagneticField": ("std_msgs/Header header\ngeometry_msgs/Vector3 magnetic_field\n"
                                  "float64[9] magnetic_field_covariance"),
    "sensor_msgs/LaserScan": ("std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\n"
                              "float32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\n"
                              "float32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities"),
    "nav_msgs/Odometry": ("std_msgs/Header header\nstring child_frame_id\n"
                          "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist"),
    "sensor_msgs/Range": ("uint8 ULTRASOUND=0\nuint8 INFRARED=1\nstd_msgs/Header header\nuint8 radiation_type\n"
                          "float32 field_of_view\nfloat32 min_range\nfloat32 max_range\nfloat32 range"),
}


def _deps(name: str, seen: list[str]) -> list[str]:
    for line in _DEFS[name].splitlines():
        typ = line.split()[0].split("[")[0]
        if "/" in typ and typ not in seen:
            seen.append(typ)
            _deps(typ, seen)
    return seen


def msgdef(name: str) -> str:
    """The ROS 2 ``.msg`` text of ``pkg/Name`` followed by its dependencies (ros2msg schema)."""
    parts = [_DEFS[name]] + [f"{SEP}\nMSG: {dep}\n{_DEFS[dep]}" for dep in _deps(name, [])]
    return "\n".join(parts) + "\n"


def ros2_type(name: str) -> str:
    pkg, typ = name.split("/")
    return f"{pkg}/msg/{typ}"


# -- CDR encoding (XCDR1 little endian, as rmw / rosbag2 write it) ------------------
class _Cdr:
    """Builds one CDR payload: primitives aligned to their size from after the 4-byte header."""

    __slots__ = ("b",)

    def __init__(self):
        self.b = bytearray(b"\x00\x01\x00\x00")

    def _align(self, n: int) -> None:
        pad = -(len(self.b) - 4) % n
        if pad:
            self.b += bytes(pad)

    def u32(self, v: int) -> None:
        self._align(4)
        self.b += _U32.pack(v)

    def u8(self, v: int) -> None:
        self.b.append(v & 0xFF)

    def stamp(self, sec: int, nanosec: int) -> None:
        self._align(4)
        self.b += _STAMP.pack(sec, nanosec)

    def string(self, text: str) -> None:
        data = text.encode("utf-8") + b"\x00"
        self.u32(len(data))
        self.b += data

    def f64(self, *values: float) -> None:
        self._align(8)
        self.b += struct.pack(f"<{len(values)}d", *values)

    def f64_array(self, values) -> None:  # fixed-size float64[N]
        self._align(8)
        self.b += np.asarray(values, "<f8").tobytes()

    def f64_seq(self, values) -> None:  # float64[]
        a = np.asarray(values, "<f8")
        self.u32(len(a))
        if len(a):
            self._align(8)
            self.b += a.tobytes()

    def f32(self, *values: float) -> None:
        self._align(4)
        self.b += struct.pack(f"<{len(values)}f", *values)

    def f32_seq(self, values) -> None:  # float32[]
        a = np.asarray(values, "<f4")
        self.u32(len(a))
        self.b += a.tobytes()

    def header(self, sec: int, nanosec: int, frame_id: str) -> None:
        self.stamp(sec, nanosec)
        self.string(frame_id)


_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")
_ZERO36 = np.zeros(36)


def _hdr(c: _Cdr, h) -> None:
    c.header(h.stamp.sec, h.stamp.nanosec, h.frame_id)


def _odometry(msg) -> bytes:
    c = _Cdr()
    _hdr(c, msg.header)
    c.string(msg.child_frame_id)
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    c.f64(p.x, p.y, p.z, o.x, o.y, o.z, o.w)
    c.f64_array(msg.pose.covariance)
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    c.f64(lin.x, lin.y, lin.z, ang.x, ang.y, ang.z)
    c.f64_array(msg.twist.covariance)
    return bytes(c.b)


def _tf(msg) -> bytes:
    c = _Cdr()
    c.u32(len(msg.transforms))
    for ts in msg.transforms:
        _hdr(c, ts.header)
        c.string(ts.child_frame_id)
        t, r = ts.transform.translation, ts.transform.rotation
        c.f64(t.x, t.y, t.z, r.x, r.y, r.z, r.w)
    return bytes(c.b)


def _imu(msg) -> bytes:
    c = _Cdr()
    _hdr(c, msg.header)
    o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    c.f64(o.x, o.y, o.z, o.w)
    c.f64_array(msg.orientation_covariance)
    c.f64(w.x, w.y, w.z)
    c.f64_array(msg.angular_velocity_covariance)
    c.f64(a.x, a.y, a.z)
    c.f64_array(msg.linear_acceleration_covariance)
    return bytes(c.b)


def _mag(msg) -> bytes:
    c = _Cdr()
    _hdr(c, msg.header)
    f = msg.magnetic_field
    c.f64(f.x, f.y, f.z)
    c.f64_array(msg.magnetic_field_covariance)
    return bytes(c.b)


def _scan(msg) -> bytes:
    c = _Cdr()
    _hdr(c, msg.header)
    c.f32(msg.angle_min, msg.angle_max, msg.angle_increment, msg.time_increment, msg.scan_time,
          msg.range_min, msg.range_max)
    c.f32_seq(msg.ranges)
    c.f32_seq(msg.intensities)
    return bytes(c.b)


def _range(msg) -> bytes:
    c = _Cdr()
    _hdr(c, msg.header)
    c.u8(int(msg.radiation_type))
    c.f32(msg.field_of_view, msg.min_range, msg.max_range, msg.range)
    return bytes(c.b)


def _float64(msg) -> bytes:
    c = _Cdr()
    c.f64(float(msg.data))
    return bytes(c.b)


def _multi(values) -> bytes:
    c = _Cdr()
    c.u32(0)  # layout.dim: empty
    c.u32(0)  # layout.data_offset
    c.f64_seq(values)
    return bytes(c.b)


# bus topic -> (ROS 2 topic, type, encoder)
BUS_TOPICS = {
    "odom": ("/odom", "nav_msgs/Odometry", _odometry),
    "tf": ("/tf", "tf2_msgs/TFMessage", _tf),
    "scan": ("/scan", "sensor_msgs/LaserScan", _scan),
    "imu/data_raw": ("/imu/data_raw", "sensor_msgs/Imu", _imu),
    "imu/mag": ("/imu/mag", "sensor_msgs/MagneticField", _mag),
    "uwb/range": ("/uwb/range", "sensor_msgs/Range", _range),
    "wheel0_Vel": ("/wheel0_Vel", "std_msgs/Float64", _float64),
    "wheel1_Vel": ("/wheel1_Vel", "std_msgs/Float64", _float64),
    "wheel_Command": ("/wheel_Command", "std_msgs/Float64MultiArray", lambda m: _multi(m.data)),
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
    c = _Cdr()
    c.u32(len(entries))
    for parent, child, xyz, (w, x, y, z) in entries:
        c.header(0, 0, parent)
        c.string(child)
        c.f64(*(float(v) for v in xyz), float(x), float(y), float(z), float(w))
    return bytes(c.b)


def _ground_truth(t_ns: int, pose) -> bytes:
    x, y, yaw = (float(v) for v in pose)
    c = _Cdr()
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

    from .rerun_log import atomic_target

    path = Path(path)
    tmp = atomic_target(path)
    items: list[tuple[int, int, str, str, bytes]] = []  # t_ns, order, topic, type, CDR payload
    k = 0
    for bus_topic, (topic, typ, encode) in BUS_TOPICS.items():
        for t_us, msg in capture.messages.get(bus_topic, []):
            items.append((int(t_us) * 1000, k, topic, typ, encode(msg)))
            k += 1
    t_ns = np.round(series.t_s * 1e9).astype(np.int64).tolist()
    true_rpm, pwm, pose = series.true_rpm.tolist(), series.pwm_counts.tolist(), series.pose
    for i, t in enumerate(t_ns):
        items.append((t, k, "/twin/true_rpm", "std_msgs/Float64MultiArray", _multi(true_rpm[i])))
        items.append((t, k + 1, "/twin/pwm_counts", "std_msgs/Float64MultiArray", _multi(pwm[i])))
        items.append((t, k + 2, "/twin/ground_truth", "nav_msgs/Odometry", _ground_truth(t, pose[i])))
        k += 3
    items.append((0, -1, "/tf_static", "tf2_msgs/TFMessage", _static_tf(capture, series)))
    items.sort(key=lambda it: (it[0], it[1]))
    try:
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
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path
