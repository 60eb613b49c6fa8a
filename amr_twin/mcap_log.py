"""Record a run as ROS 2 messages in an ``.mcap`` file (issue 7).

The same streams as :mod:`amr_twin.rerun_log`, CDR-encoded with ROS 2 message
definitions (schema encoding ``ros2msg``), so ``ros2 bag info/play`` (rosbag2 MCAP
storage) and Foxglove read the file. Log and publish times are the simulation
time (ns) at which the bus delivered the message; header stamps are the
messages' own.

Topics (frames as in REP-105; ``world`` is the simulation's world frame)::

    /odom              nav_msgs/msg/Odometry          odom -> base_link, 50 Hz
    /tf                tf2_msgs/msg/TFMessage         odom -> base_link, 50 Hz
    /tf_static         tf2_msgs/msg/TFMessage         world -> odom, base_link -> laser, imu_link
    /scan              sensor_msgs/msg/LaserScan      (with TwinOptions(sensors=True))
    /imu/data_raw      sensor_msgs/msg/Imu            (idem)
    /imu/mag           sensor_msgs/msg/MagneticField  (idem)
    /wheel0_Vel, /wheel1_Vel   std_msgs/msg/Float64   RPM as published by the firmware
    /wheel_Command     std_msgs/msg/Float64MultiArray [motionL, speedL, motionR, speedR]
    /twin/true_rpm     std_msgs/msg/Float64MultiArray [left, right], signed, record rate (100 Hz)
    /twin/pwm_counts   std_msgs/msg/Float64MultiArray [left, right] analogWrite counts, 100 Hz
    /twin/ground_truth nav_msgs/msg/Odometry          world -> base_link (true pose), 100 Hz
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import mujoco
import numpy as np

from .messages import Time

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


# -- conversion of the twin's (ROS 1 shaped) messages to ROS 2 dicts ----------------
def _stamp(t: Time) -> dict:
    return {"sec": int(t.sec), "nanosec": int(t.nanosec)}


def _header(h) -> dict:
    return {"stamp": _stamp(h.stamp), "frame_id": h.frame_id}


def _v3(v) -> dict:
    return {"x": float(v.x), "y": float(v.y), "z": float(v.z)}


def _q(q) -> dict:
    return {"x": float(q.x), "y": float(q.y), "z": float(q.z), "w": float(q.w)}


def _cov(a) -> list[float]:
    return np.asarray(a, float).tolist()


def _odometry(msg) -> dict:
    p, tw = msg.pose, msg.twist
    return {"header": _header(msg.header), "child_frame_id": msg.child_frame_id,
            "pose": {"pose": {"position": _v3(p.pose.position), "orientation": _q(p.pose.orientation)},
                     "covariance": _cov(p.covariance)},
            "twist": {"twist": {"linear": _v3(tw.twist.linear), "angular": _v3(tw.twist.angular)},
                      "covariance": _cov(tw.covariance)}}


def _transform_stamped(ts) -> dict:
    return {"header": _header(ts.header), "child_frame_id": ts.child_frame_id,
            "transform": {"translation": _v3(ts.transform.translation), "rotation": _q(ts.transform.rotation)}}


def _tf(msg) -> dict:
    return {"transforms": [_transform_stamped(ts) for ts in msg.transforms]}


def _imu(msg) -> dict:
    return {"header": _header(msg.header), "orientation": _q(msg.orientation),
            "orientation_covariance": _cov(msg.orientation_covariance),
            "angular_velocity": _v3(msg.angular_velocity),
            "angular_velocity_covariance": _cov(msg.angular_velocity_covariance),
            "linear_acceleration": _v3(msg.linear_acceleration),
            "linear_acceleration_covariance": _cov(msg.linear_acceleration_covariance)}


def _mag(msg) -> dict:
    return {"header": _header(msg.header), "magnetic_field": _v3(msg.magnetic_field),
            "magnetic_field_covariance": _cov(msg.magnetic_field_covariance)}


def _scan(msg) -> dict:
    return {"header": _header(msg.header), "angle_min": msg.angle_min, "angle_max": msg.angle_max,
            "angle_increment": msg.angle_increment, "time_increment": msg.time_increment,
            "scan_time": msg.scan_time, "range_min": msg.range_min, "range_max": msg.range_max,
            "ranges": np.asarray(msg.ranges, np.float32).tolist(),
            "intensities": np.asarray(msg.intensities, np.float32).tolist()}


def _float64(msg) -> dict:
    return {"data": float(msg.data)}


def _multi(values) -> dict:
    return {"layout": {"dim": [], "data_offset": 0}, "data": [float(v) for v in values]}


# bus topic -> (ROS 2 topic, type, converter)
BUS_TOPICS = {
    "odom": ("/odom", "nav_msgs/Odometry", _odometry),
    "tf": ("/tf", "tf2_msgs/TFMessage", _tf),
    "scan": ("/scan", "sensor_msgs/LaserScan", _scan),
    "imu/data_raw": ("/imu/data_raw", "sensor_msgs/Imu", _imu),
    "imu/mag": ("/imu/mag", "sensor_msgs/MagneticField", _mag),
    "wheel0_Vel": ("/wheel0_Vel", "std_msgs/Float64", _float64),
    "wheel1_Vel": ("/wheel1_Vel", "std_msgs/Float64", _float64),
    "wheel_Command": ("/wheel_Command", "std_msgs/Float64MultiArray", lambda m: _multi(m.data)),
}


def _tf_entry(stamp: dict, parent: str, child: str, xyz, quat_wxyz) -> dict:
    w, x, y, z = (float(v) for v in quat_wxyz)
    return {"header": {"stamp": stamp, "frame_id": parent}, "child_frame_id": child,
            "transform": {"translation": dict(zip("xyz", (float(v) for v in xyz))),
                          "rotation": {"x": x, "y": y, "z": z, "w": w}}}


def _static_tf(capture, series) -> dict:
    """world -> odom (the start pose), base_link -> laser and imu_link (from the model)."""
    m = capture.twin.physics.model
    stamp = {"sec": 0, "nanosec": 0}
    x0, y0, yaw0 = (float(v) for v in series.pose[0])
    out = [_tf_entry(stamp, "world", "odom", (x0, y0, 0.0), (math.cos(yaw0 / 2), 0, 0, math.sin(yaw0 / 2)))]
    for body, frame in (("amr/laser", "laser"), ("amr/imu_link", "imu_link")):
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
        if b >= 0 and m.body_parentid[b] == mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "amr/base_link"):
            out.append(_tf_entry(stamp, "base_link", frame, m.body_pos[b], m.body_quat[b]))
    return {"transforms": out}


def _ground_truth(t_s: float, pose, stamp: dict) -> dict:
    x, y, yaw = (float(v) for v in pose)
    zero = [0.0] * 36
    return {"header": {"stamp": stamp, "frame_id": "world"}, "child_frame_id": "base_link",
            "pose": {"pose": {"position": {"x": x, "y": y, "z": 0.0},
                              "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}},
                     "covariance": zero},
            "twist": {"twist": {"linear": {"x": 0.0, "y": 0.0, "z": 0.0},
                                "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}, "covariance": zero}}


def write_mcap(capture, series, path: Path) -> Path:
    """Write the capture's bus messages and ``series`` to ``path`` (.mcap), through a temporary file."""
    from mcap_ros2.writer import Writer

    from .rerun_log import atomic_target

    path = Path(path)
    tmp = atomic_target(path)
    items: list[tuple[int, int, str, str, dict]] = []  # t_ns, order, topic, type, message
    k = 0
    for bus_topic, (topic, typ, conv) in BUS_TOPICS.items():
        for t_us, msg in capture.messages.get(bus_topic, []):
            items.append((int(t_us) * 1000, k, topic, typ, conv(msg)))
            k += 1
    t_ns = np.round(series.t_s * 1e9).astype(np.int64).tolist()
    for i, t in enumerate(t_ns):
        stamp = {"sec": t // 1_000_000_000, "nanosec": t % 1_000_000_000}
        items.append((t, k, "/twin/true_rpm", "std_msgs/Float64MultiArray", _multi(series.true_rpm[i])))
        items.append((t, k + 1, "/twin/pwm_counts", "std_msgs/Float64MultiArray", _multi(series.pwm_counts[i])))
        items.append((t, k + 2, "/twin/ground_truth", "nav_msgs/Odometry",
                      _ground_truth(series.t_s[i], series.pose[i], stamp)))
        k += 3
    items.append((0, -1, "/tf_static", "tf2_msgs/TFMessage", _static_tf(capture, series)))
    items.sort(key=lambda it: (it[0], it[1]))
    try:
        with open(tmp, "wb") as f:
            writer = Writer(f)
            schemas = {}
            for typ in {it[3] for it in items}:
                schemas[typ] = writer.register_msgdef(ros2_type(typ), msgdef(typ))
            for t, _k, topic, typ, message in items:
                writer.write_message(topic, schemas[typ], message, log_time=t, publish_time=t)
            writer.finish()
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path
