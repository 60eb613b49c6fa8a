"""The wheel odometry's output at an instant: ``nav_msgs/Odometry`` on ``odom`` and the
``odom -> base_link`` transform (:func:`odometry_message`), with the covariances of the
ros_controllers diff_drive example (:data:`DEFAULT_COVARIANCE_DIAGONAL`, :func:`covariance`)."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from amr_twin.ros.geometry_messages import (
    Odometry,
    Point,
    Pose,
    PoseWithCovariance,
    Quaternion,
    Transform,
    TransformStamped,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from amr_twin.ros.messages import Header, Time

DEFAULT_COVARIANCE_DIAGONAL = (1e-3, 1e-3, 1e6, 1e6, 1e6, 1e3)
"""(x, y, z, roll, pitch, yaw) variances, the ros_controllers diff_drive example values."""


def covariance(diagonal: Sequence[float]) -> np.ndarray:
    """The 6 x 6 covariance (flat, 36) of the variances ``diagonal`` of (x, y, z, roll, pitch,
    yaw)."""
    if len(diagonal) != 6:
        raise ValueError(f"a covariance diagonal has 6 values, got {len(diagonal)}")
    return np.diag(np.asarray(diagonal, dtype=np.float64)).ravel()


def odometry_message(
    seq: int,
    now_us: int,
    pose: tuple[float, float, float],
    twist: tuple[float, float, float],
    frames: tuple[str, str],
    covariances: tuple[np.ndarray, np.ndarray],
    with_transform: bool,
) -> tuple[Odometry, TransformStamped | None]:
    """``pose`` (x_m, y_m, yaw_rad; the yaw wrapped here) and body ``twist`` (vx_m_s, vy_m_s,
    w_rad_s) at ``now_us`` as ``nav_msgs/Odometry`` in ``frames`` (frame, child) and, with
    ``with_transform``, the transform between them. Messages built with positional fields (ROS
    order): this runs at 50 Hz on the loop's cold caches."""
    stamp = Time.from_us(now_us)
    vx_m_s, vy_m_s, w_rad_s = twist
    x_m, y_m, yaw = pose
    orientation = Quaternion.from_yaw(math.atan2(math.sin(yaw), math.cos(yaw)))
    frame, child = frames
    pose_covariance, twist_covariance = covariances
    msg = Odometry(
        Header(seq, stamp, frame),
        child,
        PoseWithCovariance(Pose(Point(x_m, y_m, 0.0), orientation), pose_covariance),
        TwistWithCovariance(
            Twist(Vector3(vx_m_s, vy_m_s, 0.0), Vector3(0.0, 0.0, w_rad_s)), twist_covariance
        ),
    )
    if not with_transform:
        return msg, None
    transform = TransformStamped(
        Header(0, stamp, frame), child, Transform(Vector3(x_m, y_m, 0.0), orientation)
    )
    return msg, transform
