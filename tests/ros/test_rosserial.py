"""Frame timing, serialisation on the wire, extra latency and loss of amr_twin.ros.rosserial."""

import pytest


from amr_twin.ros.bus import Bus
from amr_twin.base.clock import VirtualClock
from amr_twin.ros.messages import Float64, Float64MultiArray, MultiArrayDimension, MultiArrayLayout
from amr_twin.ros.rosserial import (
    ARDUINO_TO_PC,
    PC_TO_ARDUINO,
    RosserialLink,
    frame_bytes,
    frame_time_us,
)

WHEEL_COMMAND = Float64MultiArray(data=[1.0, 38.19718551635742, 1.0, 38.19718551635742])


def _recorder(clock, log):
    return lambda topic, msg: log.append((clock.now_us, topic, msg))


def test_frame_sizes_and_times():
    # 8 bytes of framing + 8 bytes of float64
    assert frame_bytes(Float64(12.0)) == 16
    # 8 framing + (4 dim count + 4 data_offset) + (4 length + 4 x 8)
    assert frame_bytes(WHEEL_COMMAND) == 52
    # 16 bytes x 10 bits / 115200 bit/s = 1388.9 us -> 1389 us
    assert frame_time_us(16, 115200) == 1389
    assert frame_time_us(52, 115200) == 4514
    assert frame_time_us(12, 9600) == 12_500  # exact: no rounding up


def test_delay_equals_the_byte_time():
    clock = VirtualClock()
    link, log = RosserialLink(clock), []
    clock.run_until(1000)
    arrival = link.send(PC_TO_ARDUINO, "wheel_Command", WHEEL_COMMAND, _recorder(clock, log))
    expected = 1000 + -(-52 * 10 * 1_000_000 // 115200)
    assert arrival == expected
    clock.run_until(expected - 1)
    assert log == []
    clock.run_until(expected)
    assert log[0][:2] == (expected, "wheel_Command")
    assert log[0][2].data == WHEEL_COMMAND.data


def test_frames_wait_for_the_previous_one_on_the_same_direction():
    clock = VirtualClock()
    link, log = RosserialLink(clock), []
    deliver = _recorder(clock, log)
    link.send(ARDUINO_TO_PC, "wheel0_Vel", Float64(40.0), deliver)
    link.send(ARDUINO_TO_PC, "wheel1_Vel", Float64(41.0), deliver)
    link.send(PC_TO_ARDUINO, "wheel_Command", WHEEL_COMMAND, deliver)  # other wire: no wait
    clock.run_until(100_000)
    assert [(t, topic) for t, topic, _ in log] == [
        (1389, "wheel0_Vel"),
        (2778, "wheel1_Vel"),
        (4514, "wheel_Command"),
    ]
    assert link.bytes_sent[ARDUINO_TO_PC] == 32 and link.frames_sent[PC_TO_ARDUINO] == 1


def test_an_idle_wire_starts_now():
    clock = VirtualClock()
    link = RosserialLink(clock)
    link.send(ARDUINO_TO_PC, "wheel0_Vel", Float64(1.0), lambda t, m: None)
    clock.run_until(50_000)
    assert link.send(ARDUINO_TO_PC, "wheel0_Vel", Float64(1.0), lambda t, m: None) == 51_389


def test_extra_latency_and_baud():
    clock = VirtualClock()
    link = RosserialLink(clock, baud=57600, extra_latency_us=1000)
    assert link.send(ARDUINO_TO_PC, "wheel0_Vel", Float64(1.0), lambda t, m: None) == 2778 + 1000


def test_delivery_is_a_snapshot_and_can_publish_on_the_bus():
    clock = VirtualClock()
    bus, link, seen = Bus(clock), RosserialLink(clock), []
    bus.subscribe("wheel0_Vel", lambda msg: seen.append((clock.now_us, msg.data)))
    msg = Float64(10.0)
    link.send(ARDUINO_TO_PC, "wheel0_Vel", msg, bus.publish)
    msg.data = 99.0  # the sender reuses its message object, as firmware does
    clock.run_until(10_000)
    assert seen == [(1389, 10.0)]


@pytest.mark.parametrize("dims", [0, 1])
def test_a_multi_array_is_delivered_as_sent(dims):
    clock = VirtualClock()
    link, seen = RosserialLink(clock), []
    layout = MultiArrayLayout([MultiArrayDimension("wheels", 4, 4)] * dims, data_offset=1)
    msg = Float64MultiArray(layout, [1.0, 50.0, -1.0, 60.0])
    link.send(PC_TO_ARDUINO, "wheel_Command", msg, lambda _topic, m: seen.append(m))
    msg.data[1] = 0.0  # the sender reuses its message object and list
    msg.layout.data_offset = 7
    if dims:
        msg.layout.dim[0].size = 9
    clock.run_until(10_000)
    assert seen == [
        Float64MultiArray(
            MultiArrayLayout([MultiArrayDimension("wheels", 4, 4)] * dims, data_offset=1),
            [1.0, 50.0, -1.0, 60.0],
        )
    ]


def test_loss_is_seeded_and_still_occupies_the_wire():
    def run(seed):
        clock = VirtualClock()
        link, log = RosserialLink(clock, loss_prob=0.3, seed=seed), []
        arrivals = [
            link.send(ARDUINO_TO_PC, "w", Float64(i), _recorder(clock, log)) for i in range(2000)
        ]
        clock.run_until(10**9)
        return link, arrivals, log

    link, arrivals, log = run(7)
    assert arrivals == run(7)[1]
    assert arrivals != run(8)[1]
    assert link.frames_lost[ARDUINO_TO_PC] == arrivals.count(None) == 2000 - len(log)
    assert 0.25 < arrivals.count(None) / 2000 < 0.35
    # every frame, delivered or lost, took its slot: frame k ends at (k + 1) * 1389 us
    assert all(t == (k + 1) * 1389 for k, t in enumerate(arrivals) if t is not None)


@pytest.mark.parametrize("kwargs", [dict(baud=0), dict(loss_prob=1.5), dict(extra_latency_us=-1)])
def test_bad_parameters(kwargs):
    with pytest.raises(ValueError):
        RosserialLink(VirtualClock(), **kwargs)


def test_unknown_direction():
    with pytest.raises(ValueError):
        RosserialLink(VirtualClock()).send("sideways", "x", Float64(), lambda t, m: None)
