"""The bridge's ROS 1 writers give the bytes genpy (Debian's ROS 1) gives the same message, type by
type."""

import io

import numpy as np
import pytest

from conftest import needs_ros1
from amr_twin.ros import ros_state
from amr_twin.ros.geometry_messages import Quaternion, Vector3
from amr_twin.ros.messages import (
    Float64,
    Float64MultiArray,
    Header,
    MultiArrayDimension,
    MultiArrayLayout,
    Time,
)
from amr_twin.ros.sensor_messages import Imu, LaserScan, MagneticField
from amr_twin.ros1.serialization import WRITERS

pytestmark = needs_ros1
rng = np.random.default_rng(0)
HEADER = Header(7, Time(12, 345_678_000), "imu_link")


def _cases():
    yield Imu(
        HEADER,
        Quaternion(0.1, -0.2, 0.3, 0.9),
        rng.normal(size=9),
        Vector3(0.01, -0.02, 0.5),
        rng.normal(size=9),
        Vector3(9.7, 0.1, -0.3),
        rng.normal(size=9),
    )
    yield Imu(  # covariances as plain lists and a strided view; signed zeros
        HEADER,
        Quaternion(-0.0, 0.0, -1.0, 0.0),
        [0.0, -0.0, *rng.normal(size=7).tolist()],
        Vector3(-0.0, 1e300, -1e-300),
        rng.normal(size=18)[1::2],
        Vector3(9.7, 0.1, -0.3),
        list(range(9)),
    )
    yield MagneticField(HEADER, Vector3(2e-5, -3e-6, 4e-5), rng.normal(size=9))
    yield MagneticField(
        HEADER, Vector3(0, 0, 1e-5), np.arange(18.0)[::2]
    )  # a strided view: its values, in order
    yield ros_state.ground_truth(
        1_234_567, [1.0, -2.0, 0.1], [0.9, 0.0, 0.1, 0.4], [0.5, 0.01, 0.0], [0.0, 0.0, -0.3]
    )
    yield ros_state.joint_state(
        20_000, ["wheel_left_joint", "caster_front_left_joint"], [1.5, -0.002], [3.0, 0.01]
    )
    yield ros_state.link_transforms(
        40_000,
        ["wheel_left_link", "wheel_right_link"],
        rng.normal(size=(2, 3)),
        rng.normal(size=(2, 4)),
    )
    yield ros_state.link_transforms(
        60_000, ["base_link"], rng.normal(size=(1, 3)), rng.normal(size=(1, 4))
    )
    yield LaserScan(
        Header(3, Time(5, 0), "laser"),
        -3.14,
        3.1,
        0.0172,
        -1.3e-4,
        0.18,
        0.15,
        12.0,
        rng.uniform(0.15, 12, 364).astype(np.float32),
        np.zeros(0, np.float32),
    )
    yield Float64MultiArray(
        MultiArrayLayout([MultiArrayDimension("motionL,speedL,motionR,speedR", 4, 4)], 0),
        [1.0, 53.476, 1.0, 53.476],
    )
    yield Float64(76.39437103271484)


@pytest.mark.parametrize("msg", list(_cases()), ids=lambda m: m._type)
def test_the_writer_gives_genpys_bytes(msg):
    from amr_twin.ros1.messages import Ros1Messages

    conv = Ros1Messages()
    buff = io.BytesIO()
    conv.to_ros(msg).serialize(buff)  # genpy, through the generic converter
    assert WRITERS[msg._type](msg) == buff.getvalue()
    back = conv.ros_class(msg._type)().deserialize(
        WRITERS[msg._type](msg)
    )  # and genpy reads it back
    assert back._type == msg._type
