"""The navigator's pose source: the localisation's topic, its history and the map match's
correction."""

import numpy as np
import pytest

from amr_twin.analysis.se2 import compose
from amr_twin.navigation.localisation import PoseSource
from amr_twin.ros.bus import Bus
from amr_twin.ros.geometry_messages import Odometry, Point, Pose, PoseWithCovariance, Quaternion
from amr_twin.ros.messages import Header, Time
from amr_twin.base.clock import VirtualClock


def _odom(t_s, x, y, yaw):
    return Odometry(
        Header(0, Time.from_sec(t_s), "map"),
        "base_link",
        PoseWithCovariance(Pose(Point(x, y, 0.0), Quaternion.from_yaw(yaw))),
    )


def test_a_jump_the_ekf_takes_in_leaves_every_corrected_pose_where_it_was():
    """The EKF fuses the match and its pose jumps: the correction gives the jump back, so the
    navigator's pose now and the poses a scan's beams are placed at (its history) stay put; without
    the rebase they would move by the jump (5 cm and 0.02 rad here)."""
    bus = Bus(VirtualClock())
    src = PoseSource(bus, "odometry/filtered")
    for k in range(10):
        bus.publish("odometry/filtered", _odom(0.1 * k, 0.3 * k, 1.0, 0.4 + 0.01 * k))
    src.correction = (0.12, -0.05, 0.03)
    t = np.linspace(0.05, 0.9, 7)
    before_hist, before_now = src.poses_at(t), src.pose()
    raw = src.raw_pose()
    jumped = compose(raw, (0.03, -0.04, 0.02))  # the EKF's latest pose after the fusion, same stamp
    bus.publish("odometry/filtered", _odom(0.9, *jumped))
    assert np.hypot(*(src.pose()[:2] - before_now[:2])) > 0.04  # the jump shows before the rebase
    src.rebase(raw)
    assert src.pose() == pytest.approx(before_now, abs=1e-9)
    assert src.poses_at(t) == pytest.approx(before_hist, abs=1e-9)
    assert src.raw_pose() == pytest.approx(jumped)
