"""Virtual clock: one time order for synced and publishing events, and the physics horizon."""

import pytest

from amr_twin.base.clock import NEVER_US, VirtualClock


def test_both_kinds_run_in_time_order_ties_in_scheduling_order():
    clock, calls = VirtualClock(), []
    clock.schedule(20, lambda: calls.append(("sync", 20, clock.now_us)))
    clock.schedule(10, lambda: calls.append(("pub", 10, clock.now_us)), publishes=("odom",))
    clock.schedule(20, lambda: calls.append(("pub", 20, clock.now_us)), publishes=("odom",))
    clock.schedule(10, lambda: calls.append(("sync", 10, clock.now_us)))
    assert clock.run_until(15) == 2 and clock.now_us == 15
    assert clock.run_until(20) == 2
    assert calls == [("pub", 10, 10), ("sync", 10, 10), ("sync", 20, 20), ("pub", 20, 20)]


def test_next_synced_event_ignores_publishing_events_and_cancelled_ones():
    clock = VirtualClock()
    clock.schedule(5, lambda: None, publishes=["/imu/data_raw"])
    handle = clock.schedule(7, lambda: None)
    clock.schedule(9, lambda: None)
    assert clock.next_event_us() == 5 and clock.next_synced_event_us() == 7
    handle.cancel()
    assert clock.next_synced_event_us() == 9 and handle.publishes is None
    assert VirtualClock().next_synced_event_us() == NEVER_US


def test_physics_horizon_is_bounded_by_the_lookahead_of_due_publishing_events():
    clock = VirtualClock()
    clock.schedule(100, lambda: None, publishes=("odom", "tf"))
    clock.schedule(300, lambda: None, publishes=("scan",))
    lookahead = {("odom", "tf"): 50, ("scan",): 0}
    assert clock.physics_horizon_us(1000, lookahead.__getitem__) == 150
    assert clock.physics_horizon_us(120, lookahead.__getitem__) == 120  # the target comes first
    assert clock.physics_horizon_us(90, lookahead.__getitem__) == 90  # nothing due before it
    never = {("odom", "tf"): NEVER_US, ("scan",): NEVER_US}
    assert clock.physics_horizon_us(1000, never.__getitem__) == 1000


def test_schedule_in_the_past_is_refused():
    clock = VirtualClock(start_us=10)
    with pytest.raises(ValueError, match="in the past"):
        clock.schedule(9, lambda: None, publishes=())


def test_a_periodic_event_fires_like_one_that_reschedules_itself_and_stops_when_cancelled():
    """Ties with other events resolve as if the callback had scheduled its next occurrence first."""

    def run(periodic: bool) -> list:
        clock, log = VirtualClock(), []
        handles = []

        def tick():
            if not periodic:
                handles.append(clock.schedule(clock.now_us + 300, tick, publishes=("t",)))
            log.append(("tick", clock.now_us))
            clock.schedule(clock.now_us + 300, lambda t=clock.now_us: log.append(("other", t)))

        if periodic:
            handles.append(clock.schedule_every(100, 300, tick, publishes=("t",)))
        else:
            handles.append(clock.schedule(100, tick, publishes=("t",)))
        clock.run_until(1000)
        handles[-1].cancel()
        clock.run_until(3000)
        return log

    log = run(periodic=True)
    assert log == run(periodic=False)
    assert [t for kind, t in log if kind == "tick"] == [100, 400, 700, 1000]
    assert log[-1] == ("other", 1000)  # nothing after the cancel but what the last tick scheduled


def test_a_period_must_be_positive():
    with pytest.raises(ValueError, match="period_us=0"):
        VirtualClock().schedule_every(0, 0, lambda: None)
