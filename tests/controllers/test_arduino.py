"""Emulated Arduino runtime: pins, timer, interrupt flags and masking, delay() in main context."""

from amr_twin.base.clock import VirtualClock
from amr_twin.base.pins import HIGH, LOW
from amr_twin.controllers.arduino import ArduinoRuntime
from amr_twin.controllers.firmware import BoardParams

BOARD = BoardParams(record_pin_log=True)


def make(board=BOARD):
    clock = VirtualClock()
    return clock, ArduinoRuntime(clock, board)


def test_analog_write_truncates_and_clamps_and_logs():
    clock, rt = make()
    rt.analogWrite(BOARD.pwm_pins[0], 76.39 / 1054 * 255)  # 18.48 -> 18
    assert rt.pins[0].pwm_counts == 18
    rt.analogWrite(BOARD.pwm_pins[1], 300.0)
    assert rt.pins[1].pwm_counts == 255
    rt.analogWrite(BOARD.pwm_pins[1], -3.0)
    assert rt.pins[1].pwm_counts == 0
    assert rt.pin_log == [(0, 0, 18), (0, 1, 255), (0, 1, 0)]
    rt.digitalWrite(BOARD.brake_pins[0], HIGH)
    rt.digitalWrite(BOARD.stop_pins[1], LOW)
    assert rt.pins[0].braking and not rt.pins[1].enabled


def test_micros_millis_follow_the_clock():
    clock, rt = make()
    clock.set_time(1_234_567)
    assert rt.micros() == 1_234_567 and rt.millis() == 1234


def test_timer_ticks_every_period():
    clock, rt = make()
    ticks = []
    rt.timer_initialize(200_000, lambda: ticks.append(clock.now_us))
    clock.run_until(1_000_000)
    assert ticks == [200_000, 400_000, 600_000, 800_000, 1_000_000]


def test_edges_while_disabled_collapse_into_one_pending_call():
    clock, rt = make()
    calls = []
    rt.attachInterrupt(0, lambda: calls.append(clock.now_us))
    rt.noInterrupts()
    for t in (10, 20, 30):
        clock.set_time(t)
        rt.external_edge(0)
    assert calls == []
    clock.set_time(40)
    rt.interrupts()
    assert calls == [40]


def test_reti_reenables_interrupts_even_after_no_interrupts_in_the_isr():
    clock, rt = make()
    states = []

    def isr():
        rt.noInterrupts()
        states.append(rt.sreg_i)

    rt.timer_initialize(1000, isr)
    clock.run_until(1000)
    assert states == [False] and rt.sreg_i is True


def test_interrupts_inside_an_isr_nests_pending_isrs():
    clock, rt = make()
    rt.attachInterrupt(1, lambda: None)

    def timer_isr():
        rt.external_edge(1)  # arrives while I = 0: pending
        rt.interrupts()  # nested service at depth 2

    rt.timer_initialize(1000, timer_isr)
    clock.run_until(1000)
    assert rt.isr_trace == [(1000, "TIMER1", 1), (1000, "INT1", 2)]


def test_latched_flag_fires_on_attach_only_with_latching_and_after_a_first_attach():
    for latch, expected in ((True, [5]), (False, [])):
        clock, rt = make(BoardParams(latch_int_flag_while_detached=latch))
        calls = []
        rt.external_edge(0)  # mode never set: no flag
        rt.attachInterrupt(0, lambda: calls.append(clock.now_us))
        assert calls == []
        rt.detachInterrupt(0)
        clock.set_time(3)
        rt.external_edge(0)  # edge while detached
        clock.set_time(5)
        rt.attachInterrupt(0, lambda: calls.append(clock.now_us))
        assert calls == expected


def test_priority_int0_int1_then_timer():
    clock, rt = make()
    order = []
    rt.attachInterrupt(0, lambda: order.append("INT0"))
    rt.attachInterrupt(1, lambda: order.append("INT1"))
    rt.timer_initialize(1000, lambda: order.append("T1"))
    clock.run_until(999)
    rt.noInterrupts()
    clock.run_until(1000)
    rt.external_edge(1)
    rt.external_edge(0)
    rt.interrupts()
    assert order == ["INT0", "INT1", "T1"]


def test_delay_blocks_main_context_but_not_interrupts():
    clock, rt = make()
    log = []

    def task(name):
        log.append((clock.now_us, name, "start"))
        yield 50
        yield 50
        log.append((clock.now_us, name, "end"))

    rt.timer_initialize(30_000, lambda: log.append((clock.now_us, "tick", "")))
    rt.post_main(lambda: task("a"))
    clock.run_until(20_000)
    rt.post_main(lambda: task("b"))  # queued: main is blocked
    assert rt.main_blocked
    clock.run_until(250_000)
    assert [e for e in log if e[1] != "tick"] == [
        (0, "a", "start"),
        (100_000, "a", "end"),
        (100_000, "b", "start"),
        (200_000, "b", "end"),
    ]
    assert [e[0] for e in log if e[1] == "tick"] == [
        30_000,
        60_000,
        90_000,
        120_000,
        150_000,
        180_000,
        210_000,
        240_000,
    ]
    assert not rt.main_blocked
