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


# rospy's _PublisherImpl: its connections, whether it is closed (hashable, as rospy's objects)
class _Impl:
    def __init__(self, connections):
        self.connections, self.closed = connections, False


def _publisher(*connections):
    return SimpleNamespace(impl=_Impl(list(connections)))


def _frames(data: bytes) -> list[bytes]:
    out = []
    while data:
        (n,) = struct.unpack_from("<I", data)
        out.append(data[4 : 4 + n])
        data = data[4 + n :]
    return out


def test_a_flush_writes_each_publishers_frames_once_per_connection_in_order():
    a, b, broken = _Connection(), _Connection(), _Connection(broken=True)
    imu, clock, nobody = _publisher(broken, a, b), _publisher(a), _publisher()
    out = Outbox()
    assert (
        Outbox.wanted(imu)
        and not Outbox.wanted(nobody)
        and not Outbox.wanted(SimpleNamespace(impl=None))
    )
    for k in range(3):
        out.put(imu, bytes([k]) * (k + 1))
        out.put(clock, struct.pack("<II", k, 0))
    assert a.data == [] and out.messages == 0  # nothing written before the flush
    out.flush()
    assert (
        len(a.data) == 2 and len(b.data) == 1 and out.writes == 3
    )  # one write per publisher and connection
    assert _frames(b.data[0]) == [b"\x00", b"\x01\x01", b"\x02\x02\x02"] == _frames(a.data[0])
    assert _frames(a.data[1]) == [struct.pack("<II", k, 0) for k in range(3)]
    assert broken.closed and not a.closed and out.messages == 6
    out.flush()  # nothing new: nothing written
    assert out.writes == 3


class _Clocked(
    _Connection
):  # records each write with the simulated instant the wall clock was brought to
    def __init__(self, name, now):
        super().__init__()
        self.name, self.now = name, now

    def write_data(self, data):
        self.now.append((self.now[0], self.name, _frames(data)))


def test_paced_each_message_goes_at_its_clock_instant_after_that_clock_and_unpaced_clock_first():
    now = [0]
    log = now  # now[0]: the instant waited for; then (instant, topic, frames) for each write
    clock, imu, scan = (_publisher(_Clocked(n, log)) for n in ("clock", "imu", "scan"))
    out = Outbox(period_us=10_000, lead=clock, gap_us=1_000)
    waits = []

    def wait(t_us):
        waits.append(t_us)
        now[0] = t_us

    for t in (0, 10_000, 20_000):
        out.put(imu, b"i%d" % t, t)
    out.put(scan, b"s", 12_345)  # published between two clock instants: written at the next one
    for t in (0, 10_000, 20_000):
        out.put(clock, struct.pack("<I", t), t)
    out.release(20_000, wait)
    writes = log[1:]
    assert waits == [0, 1_000, 10_000, 11_000, 20_000, 21_000]
    assert writes == [
        (0, "clock", [struct.pack("<I", 0)]),
        (1_000, "imu", [b"i0"]),
        (10_000, "clock", [struct.pack("<I", 10_000)]),
        (11_000, "imu", [b"i10000"]),
        (20_000, "clock", [struct.pack("<I", 20_000)]),
        (21_000, "scan", [b"s"]),
        (21_000, "imu", [b"i20000"]),
    ]  # in stamp order
    # published at an instant already released (after the pacer's tick): written first at the next
    # release
    out.put(imu, b"late", 20_000)
    del log[1:]
    out.release(20_000, wait)
    assert log[1:] == [(21_000, "imu", [b"late"])] and waits[-1] == 21_000
    # unpaced: one write a publisher, /clock first, whatever the order they were put in
    del log[1:]
    for t in (30_000, 40_000):
        out.put(imu, b"i%d" % t, t)
        out.put(clock, struct.pack("<I", t), t)
    out.put(imu, b"next", 50_000)  # after the release's instant: stays
    out.release(40_000)
    assert [(name, frames) for _t, name, frames in log[1:]] == [
        ("clock", [struct.pack("<I", 30_000), struct.pack("<I", 40_000)]),
        ("imu", [b"i30000", b"i40000"]),
    ]
    out.flush()
    assert log[-1][1:] == ("imu", [b"next"]) and out.messages == 13


def _block(payloads: list[bytes]) -> bytes:
    return b"".join(struct.pack("<I", len(p)) + p for p in payloads)


def test_a_block_is_filed_message_by_message_in_instant_order_with_single_puts():
    a = _Connection()
    imu = _publisher(a)
    out = Outbox()
    out.put(imu, b"a0", 0)
    out.put(imu, b"c20", 20_000)
    out.put_block(
        imu, [0, 10_000, 20_000], _block([b"x0", b"x1", b"x2"])
    )  # behind the last put: sorted in
    out.put(imu, b"b10", 10_000)
    out.release(10_000)
    assert [_frames(d) for d in a.data] == [[b"a0", b"x0", b"x1", b"b10"]] and out.messages == 4
    out.put_block(imu, [30_000, 40_000], _block([b"y3", b"y4"]))
    out.flush()  # within an instant, put order: c20 before x2
    assert (
        _frames(a.data[1]) == [b"c20", b"x2", b"y3", b"y4"]
        and out.messages == 8
        and out.writes == 2
    )


def test_paced_a_blocks_messages_go_each_at_its_own_clock_instant():
    now = [0]
    log = now
    clock, imu = (_publisher(_Clocked(n, log)) for n in ("clock", "imu"))
    out = Outbox(period_us=10_000, lead=clock, gap_us=1_000)
    times = [0, 10_000, 20_000]
    out.put_block(imu, times, _block([b"i%05d" % t for t in times]))  # frames of one length
    out.put_block(clock, times, _block([struct.pack("<I", t) for t in times]))

    def wait(t_us):
        now[0] = t_us

    out.release(10_000, wait)
    assert log[1:] == [
        (0, "clock", [struct.pack("<I", 0)]),
        (1_000, "imu", [b"i00000"]),
        (10_000, "clock", [struct.pack("<I", 10_000)]),
        (11_000, "imu", [b"i10000"]),
    ]
    out.release(20_000, wait)
    assert log[-2:] == [
        (20_000, "clock", [struct.pack("<I", 20_000)]),
        (21_000, "imu", [b"i20000"]),
    ]
    assert out.messages == 6


def test_a_feeder_queues_as_put_does_and_keeps_puts_order_of_publishers():
    conn = _Connection()
    imu, odom, nobody = _publisher(conn), _publisher(conn), _publisher()
    out = Outbox()
    feed = out.feeder(imu, lambda msg: msg)  # made before odom's first put
    quiet = out.feeder(nobody, lambda msg: 1 / 0)  # no subscriber: never written
    out.put(odom, b"odom", 5)
    feed("imu/data_raw", b"a", 5)
    feed("imu/data_raw", b"c", 7)
    feed("imu/data_raw", b"b", 6)  # behind the last: sorted at the take, as put's
    quiet("imu/mag", b"x", 5)
    out.flush()
    # the same first instant: odom's frames first, its first message came first, whenever the
    # feeder was made
    assert [_frames(d) for d in conn.data] == [[b"odom"], [b"a", b"b", b"c"]]
    assert out.messages == 4 and out.writes == 2
