"""What a live client may send the twin, decoded and checked before it reaches the bus.

Two inputs, as a ROS 2 graph of the robot would take them:

``cmd_vel`` (``geometry_msgs/msg/Twist``)
    published on the twin's bus, where the diff-drive node (``controllers/diff_drive.py``)
    turns it into wheel commands and stops the wheels 0.5 s after the last one (its
    watchdog): Foxglove's Teleop panel.
``wheel_Command_Service/request`` (``std_msgs/msg/Float64MultiArray``
    ``[motionL, speedL, motionR, speedR]``, the request topic of the recordings), or a call
    of the ``wheel_Command_Service`` service (``amr_idea_control/srv/RequestPacket``)
    a call of the thesis' service: it publishes ``wheel_Command`` to the Arduino.
``goal_pose`` (``geometry_msgs/msg/PoseStamped``, frame ``map`` or ``odom``)
    a navigation goal (nav2's ``/goal_pose``, Foxglove's 3D panel "Publish pose"): published on
    the twin's bus, where ``run goto``'s navigator takes it as a new goal that preempts the
    active one.

Payloads are CDR (either byte order, decoded by ``mcap_ros2`` against the definitions of
:mod:`amr_twin.ros.ros2_schemas`) or JSON (ROS field names, missing fields 0). Anything else
(another topic or type, a payload that does not decode, a value out of range or not
finite) raises :class:`InputError` with one line saying why; the caller logs it and drops
the message. Nothing a client sends reaches the twin unchecked.
"""

from __future__ import annotations

import json
import math
from typing import Any, Callable

from amr_twin.controllers.wheel_command import MAX_RPM, SERVICE_NAME, WheelCommandRequest
from amr_twin.ros.geometry_messages import Point, Pose, Quaternion, Twist, Vector3
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.nav_messages import PoseStamped
from amr_twin.ros.ros2_schemas import msgdef
from amr_twin.analysis.se2 import yaw_of_quaternion

TWIST_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/Twist")
REQUEST_TYPES = ("std_msgs/msg/Float64MultiArray", "std_msgs/Float64MultiArray")
POSE_TYPES = ("geometry_msgs/msg/PoseStamped", "geometry_msgs/PoseStamped")
GOAL_FRAMES = ("map", "odom")
GOAL_LIMIT_M = 1e4
"""Largest goal coordinate taken, m (as ``--goal``)."""
ENCODINGS = ("cdr", "json")
SERVICE_TYPE = "amr_idea_control/srv/RequestPacket"
SERVICE_REQUEST_DEF = "int32 motionL\nfloat32 speedL\nint32 motionR\nfloat32 speedR\n"
"""The request of the thesis' service, reconstructed: listings 4.3-4.6 name the fields (motion
codes int, speeds float, fig. 3.3 prints float32 values); the .srv file is not printed. Its
response is empty."""
EMPTY_RESPONSE_CDR = b"\x00\x01\x00\x00\x00"
MAX_BYTES = {
    "geometry_msgs/Twist": 64,
    "std_msgs/Float64MultiArray": 4096,
    SERVICE_TYPE: 4096,
    "geometry_msgs/PoseStamped": 4096,
}
"""Largest payload taken per type, bytes: a Twist is 52 in CDR (a few more with padding or JSON
spacing would still fit 64 in CDR; JSON gets 4096 throughout); a request of 4 values is under
100."""
"""An empty ROS 2 message in CDR: the header and rosidl's one placeholder byte."""


class InputError(ValueError):
    """A client's message was refused (the reason is one line)."""


_DECODERS: dict[str, Callable[[bytes], Any]] = {}


def _cdr_decoder(ros_type: str) -> Callable[[bytes], Any]:
    decoder = _DECODERS.get(ros_type)
    if decoder is None:
        from mcap.records import Schema
        from mcap_ros2.decoder import DecoderFactory

        pkg, name = ros_type.split("/")
        schema = Schema(
            id=1, name=f"{pkg}/msg/{name}", encoding="ros2msg", data=msgdef(ros_type).encode()
        )
        decoder = _DECODERS[ros_type] = DecoderFactory().decoder_for("cdr", schema)
    return decoder


def _decode(data: bytes, encoding: str, ros_type: str):
    """A CDR payload as a namespace, or a JSON one as a dict."""
    limit = MAX_BYTES[ros_type] if encoding == "cdr" else 4096
    if len(data) > limit:
        raise InputError(
            f"{encoding} payload of {len(data)} bytes: more than a {ros_type} can take ({limit})"
        )
    try:
        if encoding == "cdr":
            return _cdr_decoder(ros_type)(bytes(data))
        if encoding == "json":
            value = json.loads(bytes(data).decode("utf-8"))
            if not isinstance(value, dict):
                raise ValueError("not a JSON object")
            return value
    except Exception as exc:  # noqa: BLE001 - any decoding failure is the client's
        raise InputError(
            f"{encoding} payload of {len(data)} bytes does not decode as {ros_type}: {exc}"
        ) from None
    raise InputError(f"encoding {encoding!r}: the twin takes {' or '.join(ENCODINGS)}")


def _field(msg, name: str, default=0.0):
    if isinstance(msg, dict):
        return msg.get(name, default)
    return getattr(msg, name, default)


def _finite(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(f"{what}={value!r}: must be a finite number")
    return float(value)


def decode_twist(data: bytes, encoding: str) -> Twist:
    """A client's ``geometry_msgs/msg/Twist`` as the twin's
    :class:`~amr_twin.ros.geometry_messages.Twist` (m/s, rad/s)."""
    msg = _decode(data, encoding, "geometry_msgs/Twist")
    out = []
    for part in ("linear", "angular"):
        vec = _field(msg, part, {})
        out.append(Vector3(*(_finite(_field(vec, axis), f"{part}.{axis}") for axis in "xyz")))
    return Twist(out[0], out[1])


def decode_goal_pose(data: bytes, encoding: str) -> PoseStamped:
    """A client's ``geometry_msgs/msg/PoseStamped`` goal: frame ``map`` (or empty) or ``odom``, a
    finite position within +-10 km and a finite quaternion that is not zero (normalised; only its
    yaw counts)."""
    msg = _decode(data, encoding, "geometry_msgs/PoseStamped")
    frame = str(_field(_field(msg, "header", {}), "frame_id", "") or "map").lstrip("/")
    if frame not in GOAL_FRAMES:
        raise InputError(f"goal_pose in frame {frame!r}: give it in {' or '.join(GOAL_FRAMES)}")
    pose = _field(msg, "pose", {})
    xyz = [_finite(_field(_field(pose, "position", {}), k), f"pose.position.{k}") for k in "xyz"]
    if max(abs(v) for v in xyz) > GOAL_LIMIT_M:
        raise InputError(
            f"goal_pose at ({xyz[0]:g}, {xyz[1]:g}): each coordinate must be within "
            f"+-{GOAL_LIMIT_M:g} m"
        )
    q = [
        _finite(
            _field(_field(pose, "orientation", {}), k, 1.0 if k == "w" else 0.0),
            f"pose.orientation.{k}",
        )
        for k in "xyzw"
    ]
    norm = math.sqrt(sum(v * v for v in q))
    if norm < 1e-6:
        raise InputError("goal_pose: pose.orientation is a zero quaternion")
    x, y, z, w = (v / norm for v in q)
    yaw = yaw_of_quaternion(w, x, y, z)
    return PoseStamped(
        Header(0, Time(), frame), Pose(Point(xyz[0], xyz[1], 0.0), Quaternion.from_yaw(yaw))
    )


def check_request(values) -> WheelCommandRequest:
    """``[motionL, speedL, motionR, speedR]`` checked: motions -1, 0 or 1; speeds in [0, MAX_RPM]
    RPM."""
    values = list(values)
    if len(values) != 4:
        raise InputError(
            f"wheel_Command request: {len(values)} values, expected 4 [motionL, speedL, motionR, "
            f"speedR]"
        )
    motion_l, speed_l, motion_r, speed_r = (
        _finite(v, n) for v, n in zip(values, ("motionL", "speedL", "motionR", "speedR"))
    )
    for name, motion in (("motionL", motion_l), ("motionR", motion_r)):
        if motion not in (-1.0, 0.0, 1.0):
            raise InputError(f"{name}={motion:g}: must be 1 (forward), -1 (backward) or 0 (brake)")
    for name, speed in (("speedL", speed_l), ("speedR", speed_r)):
        if not 0.0 <= speed <= MAX_RPM:
            raise InputError(f"{name}={speed:g}: must be in [0, {MAX_RPM:g}] RPM")
    return WheelCommandRequest(int(motion_l), speed_l, int(motion_r), speed_r)


def decode_request_topic(data: bytes, encoding: str) -> WheelCommandRequest:
    """A ``std_msgs/msg/Float64MultiArray`` request ``[motionL, speedL, motionR, speedR]``."""
    msg = _decode(data, encoding, "std_msgs/Float64MultiArray")
    values = _field(msg, "data", [])
    if not isinstance(values, (list, tuple)):
        raise InputError("wheel_Command request: data must be an array of 4 numbers")
    return check_request(values)


def decode_service_request(data: bytes, encoding: str) -> WheelCommandRequest:
    """A ``wheel_Command_Service`` call's request (``amr_idea_control/srv/RequestPacket``)."""
    if encoding == "cdr":
        import struct

        payload = bytes(data)
        if len(payload) < 20 or len(payload) > 64 or payload[1] not in (0, 1):
            raise InputError(
                f"cdr request of {len(payload)} bytes: expected 20 (int32, float32, int32, float32)"
            )
        order = "<" if payload[1] == 1 else ">"
        values = struct.unpack_from(order + "ifif", payload, 4)
    else:
        msg = _decode(data, encoding, SERVICE_TYPE)
        values = [_field(msg, name) for name in ("motionL", "speedL", "motionR", "speedR")]
    return check_request(values)


def service_response(encoding: str) -> bytes:
    """The (empty) response of the service in ``encoding``."""
    return EMPTY_RESPONSE_CDR if encoding == "cdr" else b"{}"


def call_service(bus, request: WheelCommandRequest) -> None:
    """Call the twin's ``wheel_Command_Service`` (in the twin's thread, at a tick)."""
    bus.call_service(SERVICE_NAME, request)


INPUT_TOPICS = {
    "cmd_vel": (TWIST_TYPES, decode_twist),
    "wheel_Command_Service/request": (REQUEST_TYPES, decode_request_topic),
    "goal_pose": (POSE_TYPES, decode_goal_pose),
}
"""Topics a client may publish: name without ``/`` -> (accepted schema names, decoder)."""


def input_for(topic: str, schema_name: str, encoding: str) -> Callable[[bytes, str], Any]:
    """The decoder for a client channel, or :class:`InputError` saying what the twin takes."""
    name = topic.lstrip("/")
    entry = INPUT_TOPICS.get(name)
    if entry is None:
        raise InputError(
            f"topic {topic!r}: the twin takes /cmd_vel ({TWIST_TYPES[0]}), "
            f"/wheel_Command_Service/request ({REQUEST_TYPES[0]}) and /goal_pose ({POSE_TYPES[0]})"
        )
    types, decoder = entry
    if schema_name not in types:
        raise InputError(f"topic {topic!r} with type {schema_name!r}: expected {types[0]}")
    if encoding not in ENCODINGS:
        raise InputError(
            f"topic {topic!r} with encoding {encoding!r}: expected {' or '.join(ENCODINGS)}"
        )
    return decoder
