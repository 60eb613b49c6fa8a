"""Topics, latency, queues, latching, services, taps and tf of amr_twin.ros.bus."""

import math

import pytest


from amr_twin.ros.bus import Bus, ServiceCallError
from amr_twin.ros.tf_buffer import TransformError
from amr_twin.base.clock import VirtualClock
from amr_twin.ros.geometry_messages import (
    Quaternion,
    TFMessage,
    Transform,
    TransformStamped,
    Twist,
    Vector3,
)
from amr_twin.ros.messages import Float64, Header


@pytest.fixture
def clock():
    return VirtualClock()


@pytest.fixture
def bus(clock):
    return Bus(clock)


def test_zero_latency_runs_callbacks_immediately_in_subscription_order(bus):
    calls = []
    bus.subscribe("x", lambda msg: calls.append(("a", msg.data)))
    bus.subscribe("/x", lambda msg: calls.append(("b", msg.data)))  # leading slash: same topic
    bus.publish("x", Float64(1.0))
    assert calls == [("a", 1.0), ("b", 1.0)]


def test_latency_delivers_at_the_delivery_time(bus, clock):
    seen = []
    bus.subscribe("x", lambda msg: seen.append((clock.now_us, msg.data)), latency_us=2500)
    clock.run_until(1000)
    bus.publish("x", Float64(3.0))
    assert seen == []
    assert clock.next_event_us() == 3500
    clock.run_until(10_000)
    assert seen == [(3500, 3.0)]


def test_queue_size_drops_the_oldest_in_flight(bus, clock):
    seen = []
    sub = bus.subscribe("x", lambda msg: seen.append(msg.data), queue_size=2, latency_us=100)
    for value in (1.0, 2.0, 3.0):
        bus.publish("x", Float64(value))
    clock.run_until(1000)
    assert seen == [2.0, 3.0] and sub.dropped == 1


def test_unregister_discards_in_flight(bus, clock):
    seen = []
    sub = bus.subscribe("x", lambda msg: seen.append(msg), latency_us=100)
    bus.publish("x", Float64(1.0))
    sub.unregister()
    bus.publish("x", Float64(2.0))
    clock.run_until(1000)
    assert seen == []


def test_latched_topic_reaches_late_subscribers(bus, clock):
    bus.advertise("map_info", Float64, latch=True)
    bus.publish("map_info", Float64(7.0))
    seen = []
    bus.subscribe("map_info", lambda msg: seen.append((clock.now_us, msg.data)))
    clock.run_until(0)
    assert seen == [(0, 7.0)]
    bus.subscribe("not_latched", lambda msg: seen.append(msg))
    clock.run_until(10)
    assert len(seen) == 1


def test_type_checking(bus):
    bus.advertise("cmd_vel", Twist)
    with pytest.raises(TypeError):
        bus.publish("cmd_vel", Float64(1.0))
    with pytest.raises(TypeError):
        bus.advertise("cmd_vel", Float64)


def test_taps_see_every_message_with_its_time(bus, clock):
    log = []
    tap = lambda topic, msg, t_us: log.append((topic, t_us))  # noqa: E731
    bus.add_tap(tap)
    bus.publish("a", Float64(1.0))
    clock.run_until(42)
    bus.publish("/b", Float64(2.0))
    assert log == [("a", 0), ("b", 42)]
    bus.remove_tap(tap)
    bus.publish("a", Float64(1.0))
    assert len(log) == 2
    with pytest.raises(ValueError):
        bus.remove_tap(tap)


def test_a_tap_of_some_topics_sees_only_them_in_the_order_taps_were_added(bus, clock):
    log = []
    bus.add_tap(lambda topic, msg, t_us: log.append(("all", topic)))
    bus.publish("odom", Float64(0.0))  # before the others were added
    bus.add_tap(
        lambda topic, msg, t_us: log.append(("odom", topic)), topics=("/odom", "stop/request")
    )
    bus.add_tap(lambda topic, msg, t_us: log.append(("all2", topic)))
    bus.advertise_service("stop", lambda req: None)
    for topic in ("imu/data_raw", "odom", "scan"):
        bus.publish(topic, Float64(1.0))
    bus.call_service("stop", None)
    assert log == [
        ("all", "odom"),
        ("all", "imu/data_raw"),
        ("all2", "imu/data_raw"),
        ("all", "odom"),
        ("odom", "odom"),
        ("all2", "odom"),
        ("all", "scan"),
        ("all2", "scan"),
        ("all", "stop/request"),
        ("odom", "stop/request"),
        ("all2", "stop/request"),
    ]


def test_services(bus):
    with pytest.raises(ServiceCallError):
        bus.call_service("add", (1, 2))
    bus.advertise_service("add", lambda req: req[0] + req[1])
    assert bus.has_service("/add")
    assert bus.call_service("add", (1, 2)) == 3
    with pytest.raises(ValueError):
        bus.advertise_service("add", lambda req: 0)
    bus.unadvertise_service("add")
    with pytest.raises(ServiceCallError):
        bus.call_service("add", (1, 2))


def test_failing_server_is_a_failed_call(bus):
    def broken(req):
        raise RuntimeError("boom")

    bus.advertise_service("broken", broken)
    with pytest.raises(ServiceCallError, match="boom"):
        bus.call_service("broken", None)


def _ts(parent, child, x, y, yaw):
    return TransformStamped(
        Header(frame_id=parent), child, Transform(Vector3(x, y, 0.0), Quaternion.from_yaw(yaw))
    )


def test_tf_chain_odom_base_laser(bus):
    published = []
    bus.subscribe("tf", published.append)
    bus.send_transform(_ts("odom", "base_link", 1.0, 2.0, math.pi / 2))
    bus.send_transform(
        [_ts("base_link", "laser", 0.2, 0.0, 0.0), _ts("base_link", "imu_link", 0.0, 0.1, 0.0)],
        static=True,
    )
    assert len(published) == 1 and isinstance(published[0], TFMessage)
    laser = bus.tf.lookup_transform("odom", "laser")
    assert (laser.translation.x, laser.translation.y) == pytest.approx((1.0, 2.2))
    assert bus.tf.yaw_rad("odom", "laser") == pytest.approx(math.pi / 2)
    # the inverse direction and a sibling lookup
    back = bus.tf.lookup_transform("laser", "odom")
    assert (back.translation.x, back.translation.y) == pytest.approx((-2.2, 1.0))
    imu_in_laser = bus.tf.lookup_transform("laser", "imu_link")
    assert (imu_in_laser.translation.x, imu_in_laser.translation.y) == pytest.approx((-0.2, 0.1))
    assert bus.tf.frames() == {"odom", "base_link", "laser", "imu_link"}
    with pytest.raises(TransformError):
        bus.tf.lookup_transform("map", "laser")


def test_tf_keeps_the_latest(bus):
    bus.send_transform(_ts("odom", "base_link", 1.0, 0.0, 0.0))
    bus.send_transform(_ts("odom", "base_link", 3.0, 0.0, 0.0))
    assert bus.tf.lookup_transform("odom", "base_link").translation.x == 3.0


def test_static_tf_is_latched(bus, clock):
    bus.send_transform(_ts("base_link", "laser", 0.2, 0.0, 0.0), static=True)
    seen = []
    bus.subscribe("tf_static", seen.append)
    clock.run_until(0)
    assert len(seen) == 1 and seen[0].transforms[0].child_frame_id == "laser"


def test_static_tf_carries_every_static_frame_sent_so_far(bus, clock):
    bus.send_transform(_ts("base_link", "laser", 0.2, 0.0, 0.0), static=True)
    bus.send_transform(_ts("map", "uwb_anchor_0", 9.5, 6.5, 0.0), static=True)
    bus.send_transform(
        _ts("base_link", "laser", 0.3, 0.0, 0.0), static=True
    )  # replaces, as tf2 does
    seen = []
    bus.subscribe("tf_static", seen.append)
    clock.run_until(0)
    assert [t.child_frame_id for t in seen[0].transforms] == ["laser", "uwb_anchor_0"]
    assert seen[0].transforms[0].transform.translation.x == 0.3
    assert bus.static_transforms() == seen[0].transforms


def test_taps_see_service_requests_failed_calls_included(bus, clock):
    seen = []
    bus.add_tap(lambda topic, msg, t_us: seen.append((topic, msg, t_us)))
    with pytest.raises(ServiceCallError):
        bus.call_service("/add", (1, 2))
    bus.advertise_service("add", lambda req: req[0] + req[1])
    clock.run_until(5)
    assert bus.call_service("add", (3, 4)) == 7
    assert seen == [("add/request", (1, 2), 0), ("add/request", (3, 4), 5)]


def test_lookahead_is_the_smallest_subscriber_latency_and_taps_do_not_count(bus):
    from amr_twin.base.clock import NEVER_US

    bus.add_tap(lambda topic, msg, t_us: None)
    assert bus.lookahead_us(("odom", "tf")) == NEVER_US
    bus.subscribe("tf", lambda msg: None, latency_us=3000)
    assert bus.lookahead_us(("odom", "tf")) == 3000
    sub = bus.subscribe("odom", lambda msg: None)
    assert bus.lookahead_us(("odom", "tf")) == 0 and bus.lookahead_us(("scan",)) == NEVER_US
    sub.unregister()
    assert bus.lookahead_us(("odom", "tf")) == 3000
