"""The bridge's outbox: each publisher's frames, length-prefixed as rospy writes them, one write per
connection and flush, in order; a broken connection is closed and the others still get theirs."""

import struct
from types import SimpleNamespace

from amr_twin.ros1.outbox import Outbox


class _Connection:
    def __init__(self, broken=False):
        self.data, self.broken, self.closed = [], broken, False

    def write_data(self, data):
        if self.broken:
            raise OSError("broken pipe")
        self.data.append(data)

    def close(self):
        self.closed = True


class _Impl:  # rospy's _PublisherImpl: its connections, whether it is closed (hashable, as rospy's objects)
    def __init__(self, connections):
        self.connections, self.closed = connections, False


def _publisher(*connections):
    return SimpleNamespace(impl=_Impl(list(connections)))


def _frames(data: bytes) -> list[bytes]:
    out = []
    while data:
        (n,) = struct.unpack_from("<I", data)
        out.append(data[4:4 + n])
        data = data[4 + n:]
    return out


def test_a_flush_writes_each_publishers_frames_once_per_connection_in_order():
    a, b, broken = _Connection(), _Connection(), _Connection(broken=True)
    imu, clock, nobody = _publisher(broken, a, b), _publisher(a), _publisher()
    out = Outbox()
    assert Outbox.wanted(imu) and not Outbox.wanted(nobody) and not Outbox.wanted(SimpleNamespace(impl=None))
    for k in range(3):
        out.put(imu, bytes([k]) * (k + 1))
        out.put(clock, struct.pack("<II", k, 0))
    assert a.data == [] and out.messages == 0  # nothing written before the flush
    out.flush()
    assert len(a.data) == 2 and len(b.data) == 1 and out.writes == 3  # one write per publisher and connection
    assert _frames(b.data[0]) == [b"\x00", b"\x01\x01", b"\x02\x02\x02"] == _frames(a.data[0])
    assert _frames(a.data[1]) == [struct.pack("<II", k, 0) for k in range(3)]
    assert broken.closed and not a.closed and out.messages == 6
    out.flush()  # nothing new: nothing written
    assert out.writes == 3
