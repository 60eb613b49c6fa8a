"""A block of the bridge's grid-sampled topics is, frame by frame, what genpy (Debian's ROS 1)
writes for each message: the length, then the message's bytes, in the instants' order."""

import io
import struct

import numpy as np

from conftest import needs_ros1
from amr_twin.ros import ros_state
from amr_twin.ros.messages import Float64MultiArray
from amr_twin.ros1.frame_blocks import StateBlocks, battery_block, clock_block, float64_rows_block

pytestmark = needs_ros1
rng = np.random.default_rng(3)
TIMES = np.array([0, 10_000, 20_000, 1_234_560_000, 4_294_967_295_000_000 - 10_000], np.int64)


def _genpy(conv, msg) -> bytes:
    """The TCPROS frame genpy writes for ``msg`` (a genpy message, or a twin message to convert)."""
    buff = io.BytesIO()
    (msg if hasattr(msg, "serialize") else conv.to_ros(msg)).serialize(buff)
    return struct.pack("<I", len(buff.getvalue())) + buff.getvalue()


def _conv():
    from amr_twin.ros1.messages import Ros1Messages

    return Ros1Messages()


def test_the_state_blocks_are_genpys_frames_of_ros_states_messages():
    conv = _conv()
    joints = ["wheel_left_joint", "wheel_right_joint", "caster_front_left_joint"]
    links = ["wheel_left_link", "wheel_right_link", "caster_front_left_link"]
    blocks = StateBlocks(joints, links, "base_link", "world")
    m = len(TIMES)
    q, qd = rng.normal(size=(m, 3)), rng.normal(size=(m, 3))
    link_pos, link_quat = rng.normal(size=(m, 3, 3)), rng.normal(size=(m, 3, 4))
    pos, quat, v, w = (rng.normal(size=(m, n)) for n in (3, 4, 3, 3))
    t = TIMES.tolist()
    assert blocks.joint_states(TIMES, q, qd) == b"".join(
        _genpy(conv, ros_state.joint_state(t[i], joints, q[i], qd[i])) for i in range(m)
    )
    assert blocks.link_transforms(TIMES, link_pos, link_quat) == b"".join(
        _genpy(conv, ros_state.link_transforms(t[i], links, link_pos[i], link_quat[i]))
        for i in range(m)
    )
    assert blocks.ground_truth(TIMES, pos, quat, v, w) == b"".join(
        _genpy(conv, ros_state.ground_truth(t[i], pos[i], quat[i], v[i], w[i])) for i in range(m)
    )


def test_the_clock_rows_and_battery_blocks_are_genpys_frames():
    conv = _conv()
    rospy = conv.rospy
    t = TIMES.tolist()
    clock = conv.ros_class("rosgraph_msgs/Clock")
    assert clock_block(TIMES) == b"".join(
        _genpy(conv, clock(rospy.Time(s // 1_000_000, s % 1_000_000 * 1000))) for s in t
    )
    for width in (1, 2, 5):
        rows = rng.normal(size=(len(t), width))
        assert float64_rows_block(rows) == b"".join(
            _genpy(conv, Float64MultiArray(data=list(r))) for r in rows
        )
    assert float64_rows_block(
        np.array([[-255, 255], [3, 0]])
    ) == b"".join(  # integer counts, as floats
        _genpy(conv, Float64MultiArray(data=[float(x) for x in r])) for r in ([-255, 255], [3, 0])
    )
    battery = conv.ros_class("sensor_msgs/BatteryState")
    volts, amps, soc, cap = (
        rng.uniform(22, 25, len(t)),
        rng.normal(size=len(t)),
        rng.uniform(0, 1, len(t)),
        20.0,
    )
    want = []
    for i, s in enumerate(t):
        msg = battery(
            voltage=volts[i],
            current=amps[i],
            charge=soc[i] * cap,
            capacity=cap,
            design_capacity=cap,
            percentage=soc[i],
            present=True,
        )
        msg.header.stamp = rospy.Time(s // 1_000_000, s % 1_000_000 * 1000)
        want.append(_genpy(conv, msg))
    assert battery_block(TIMES, volts, amps, soc * cap, cap, soc) == b"".join(want)


def _sampler(table: np.ndarray) -> ros_state.StateSampler:
    """A state sampler holding the sample rows ``table`` (no twin)."""
    sampler = object.__new__(ros_state.StateSampler)
    sampler.joint_names, sampler.child_frames = ros_state.MOVING_JOINTS, LINKS
    sampler._taken = table
    return sampler


LINKS = tuple(j.replace("_joint", "_link") for j in ros_state.MOVING_JOINTS)


def test_a_ticks_blocks_in_c_are_the_python_forms_bytes():
    rows = 41
    table = rng.normal(size=(rows, 1 + 12 + 6 + 7 * 7)) * rng.choice([1e-9, 1.0, 1e6], (rows, 68))
    table[:, 0] = np.arange(rows) * 10_000 + 4_294_000_000_000
    quat = table[:, 1 + 12 + 6 + 21 :].reshape(rows, 7, 4)
    quat[:20] /= np.linalg.norm(quat[:20], axis=2, keepdims=True)  # unit ones too
    table[3:6, 20:] = -0.0  # signed zeros through the rotations and products
    native = StateBlocks(ros_state.MOVING_JOINTS, LINKS, "base_link", "world")
    python = StateBlocks(ros_state.MOVING_JOINTS, LINKS, "base_link", "world", native=False)
    assert native.engine == "C" and python.engine.startswith("Python")
    for wanted in (
        (True, True, True),
        (False, True, True),
        (False, False, True),
        (True, False, False),
    ):
        c = native.blocks(_sampler(table), 20_000, *wanted)
        assert c == python.blocks(_sampler(table), 20_000, *wanted)
        assert len(c.kept_us) == 21 and (c.ground_truth is None) != wanted[0]
