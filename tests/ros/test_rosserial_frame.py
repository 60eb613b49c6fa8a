"""rosserial frames: bytes checked against rosbags' ROS 1 serialiser and md5sums, checksums, parser
resync."""

import struct

import numpy as np
import pytest

from amr_twin.ros.rosserial_frame import (
    MD5SUM,
    FrameParser,
    TopicInfo,
    deserialize_float64,
    deserialize_float64_multiarray,
    frame,
    serialize_float64,
    serialize_float64_multiarray,
    topic_request,
)

rosbags = pytest.importorskip("rosbags.typesys")


@pytest.fixture(scope="module")
def typestore():
    return rosbags.get_typestore(rosbags.Stores.ROS1_NOETIC)


def test_messages_serialise_as_rosbags_does(typestore):
    arr = typestore.types["std_msgs/msg/Float64MultiArray"]
    layout = typestore.types["std_msgs/msg/MultiArrayLayout"]
    data = [1.0, 76.39, -1.0, 0.0]
    ours = serialize_float64_multiarray(data)
    theirs = typestore.serialize_ros1(
        arr(layout=layout(dim=[], data_offset=0), data=np.array(data)),
        "std_msgs/msg/Float64MultiArray",
    )
    assert ours == bytes(theirs)
    f64 = typestore.types["std_msgs/msg/Float64"]
    assert serialize_float64(44.491) == bytes(
        typestore.serialize_ros1(f64(data=44.491), "std_msgs/msg/Float64")
    )
    assert deserialize_float64(serialize_float64(-3.5)) == -3.5
    assert deserialize_float64_multiarray(ours) == data


def test_multiarray_with_dimensions_is_read_past_them(typestore):
    arr = typestore.types["std_msgs/msg/Float64MultiArray"]
    layout = typestore.types["std_msgs/msg/MultiArrayLayout"]
    dim = typestore.types["std_msgs/msg/MultiArrayDimension"]
    msg = arr(
        layout=layout(dim=[dim(label="wheels", size=2, stride=4)], data_offset=0),
        data=np.array([1.0, 2.0]),
    )
    assert deserialize_float64_multiarray(
        bytes(typestore.serialize_ros1(msg, "std_msgs/msg/Float64MultiArray"))
    ) == [1.0, 2.0]


def test_md5sums_are_the_ros_ones(typestore):
    for name, md5 in MD5SUM.items():
        package, msg = name.split("/")
        assert typestore.generate_msgdef(f"{package}/msg/{msg}")[1] == md5


def test_frame_checksums():
    f = frame(125, serialize_float64(76.25))
    assert f[:2] == b"\xff\xfe" and len(f) == 8 + 8
    assert (f[2] + f[3] + f[4]) % 256 == 255
    assert sum(f[5:]) % 256 == 255
    assert struct.unpack("<H", f[5:7])[0] == 125
    assert topic_request() == bytes([0xFF, 0xFE, 0, 0, 0xFF, 0, 0, 0xFF])


def test_parser_finds_frames_among_noise_and_drops_corrupted_ones():
    a, b, c = (
        frame(125, serialize_float64(1.0)),
        frame(126, serialize_float64(2.0)),
        frame(100, b""),
    )
    bad = bytearray(frame(125, serialize_float64(3.0)))
    bad[9] ^= 0x10  # a flipped bit in the message: the checksum fails
    stream = b"\x00\x12\xff" + a + bytes(bad) + b"\xfe" + b + c
    parser = FrameParser()
    frames = []
    for i in range(0, len(stream), 5):  # fed in pieces, as the UART delivers them
        frames += parser.feed(stream[i : i + 5])
    assert [(f.topic_id, f.message) for f in frames] == [(125, a[7:-1]), (126, b[7:-1]), (100, b"")]
    assert parser.dropped == 1
    assert stream[frames[1].first : frames[1].last + 1] == b
    assert parser.pending == (0, None)


def test_parser_reports_a_frame_in_progress():
    parser = FrameParser()
    f = frame(125, serialize_float64(1.0))
    assert parser.feed(f[:9]) == []
    assert parser.pending == (9, 16)


def test_topic_info_reads_what_rosserial_sends():
    def string(s):
        return struct.pack("<I", len(s)) + s.encode()

    raw = (
        struct.pack("<H", 125)
        + string("wheel0_Vel")
        + string("std_msgs/Float64")
        + string(MD5SUM["std_msgs/Float64"])
        + struct.pack("<i", 512)
    )
    assert TopicInfo.deserialize(raw) == TopicInfo(
        125, "wheel0_Vel", "std_msgs/Float64", MD5SUM["std_msgs/Float64"], 512
    )
