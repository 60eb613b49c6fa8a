"""Record a world of several robots as ROS 2 messages in one ``.mcap`` file.

Each robot's streams of :mod:`amr_twin.recording.mcap_log` under its namespace
(:class:`~amr_twin.ros.robot_namespace.RobotNamespace`: ``/amr-1/odom``, ``/amr-1/scan``,
``/amr-1/battery_state``, ``/amr-1/twin/ground_truth``, ``/amr-1/robot_description``, ...), its
frames prefixed (``amr-1/base_link``) on the world's one ``/tf`` and ``/tf_static``, one
``/clock``; each robot's collisions on ``/amr-1/twin/collisions``; the fleet manager's events
(with ``--manager``) on ``/fleet_manager/events`` (``std_msgs/String``, one JSON object each).
Reasons:
docs/reference/recordings.md#amr_twinrecordingfleet_mcap.
"""

from __future__ import annotations

import json
from pathlib import Path

from amr_twin.recording.event_log import mcap_items as event_items
from amr_twin.recording.mcap_log import run_items, write_items
from amr_twin.ros import ros_state
from amr_twin.ros.geometry_messages import TFMessage
from amr_twin.ros.messages import String
from amr_twin.ros.ros2_cdr import encode_clock, encode_string, encode_tf_message

EVENTS_TOPIC = "/fleet_manager/events"
"""The fleet manager's events: placed, assigned, wait, deadlock, done, failed, ..."""
ROBOT_ORDER = 1 << 40
"""Order of a robot's items after the robot before it's, at one instant (ties of log time)."""


def static_transforms(robots) -> TFMessage:
    """The ``/tf_static`` of a fleet: every robot's static transforms in its frames, a shared
    frame (the UWB anchors) once, and ``map -> <name>/odom`` at each robot's start pose (where
    its odometry began; the twin's ``map`` is its world frame), which puts every robot in the
    one tree as a multi-robot launch's static publisher does."""
    import math

    out, seen = [], set()
    for r in robots:
        x, y, yaw = r.view.start_xy_yaw
        q = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        out.append(ros_state.frame_transform("map", r.namespace.frame("odom"), (x, y, 0.0), q))
        for tf in r.view.bus.static_transforms():
            tf = r.namespace.message(tf)
            if tf.child_frame_id not in seen:
                seen.add(tf.child_frame_id)
                out.append(tf)
    return TFMessage(out)


def fleet_items(robots, urdf: str, events=()) -> list[tuple[int, int, str, str, bytes]]:
    """``(t_ns, order, topic, type, CDR payload)`` of every robot of ``robots``
    (:class:`~amr_twin.recording.fleet_capture.RobotCapture` items, in order) and of the
    manager's ``events`` (``(t_us, dict)`` items; module notes)."""
    items = [
        (t_us * 1000, -3, "/clock", "rosgraph_msgs/Clock", encode_clock(ros_state.clock(t_us)))
        for t_us in robots[0].capture.state.t_us
    ]
    description = encode_string(String(urdf))
    for i, r in enumerate(robots, 1):
        ns, base = r.namespace, i * ROBOT_ORDER
        robot_items = run_items(r.capture, r.recorder.series(), ns)
        robot_items.append((0, -2, ns.topic("robot_description"), "std_msgs/String", description))
        robot_items += [
            (t, order, ns.topic(topic), typ, data)
            for t, order, topic, typ, data in event_items(r.view, len(robot_items))
        ]
        items += [(t, base + k, topic, typ, data) for t, k, topic, typ, data in robot_items]
    items += [
        (t_us * 1000, -4, EVENTS_TOPIC, "std_msgs/String", encode_string(String(json.dumps(e))))
        for t_us, e in events
    ]
    items.append(
        (0, -1, "/tf_static", "tf2_msgs/TFMessage", encode_tf_message(static_transforms(robots)))
    )
    return items


def write_fleet_mcap(robots, path: Path, urdf: str, events=()) -> Path:
    """Write the fleet's recording to ``path`` (.mcap) through a temporary file; ``robots``: the
    :func:`~amr_twin.recording.fleet_capture.attach_fleet` captures, ``urdf`` the robot's
    description (each robot's ``/<name>/robot_description``), ``events`` the manager's."""
    return write_items(fleet_items(robots, urdf, events), path)
