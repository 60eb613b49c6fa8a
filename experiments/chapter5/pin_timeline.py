"""One wheel_Command's pin timeline, no physics: every change of a firmware's PWM, brake, stop and
direction pins after the command, wheels at rest (:func:`command_timeline`), and two firmwares'
timelines paired change by change (:func:`timeline_table`)."""

from __future__ import annotations

TIMELINE_COMMAND = (1.0, 99.2, 1.0, 60.8)
"""wheel_Command of :func:`command_timeline`: chapter 5 run 5 (left ramps 10 x 150 ms, right 10 x 50
ms)."""


def _pin_state(pins) -> tuple:
    return tuple((p.pwm_counts, p.brake_level, p.stop_level, p.dir_level) for p in pins)


def _changes(t_us: int, before: tuple, after: tuple) -> list[tuple[int, int, str, int]]:
    names = ("pwm", "brake", "stop", "dir")
    return [
        (t_us, w, names[k], after[w][k])
        for w in range(2)
        for k in range(4)
        if before[w][k] != after[w][k]
    ]


def command_timeline(
    firmware: str = "avr", data=TIMELINE_COMMAND, until_us: int = 2_500_000
) -> list:
    """``(t_us, wheel, pin, value)`` of every pin change after one wheel_Command, wheels at rest.

    No physics: the wheels never turn, so no speed is sampled and the PI stays idle; what is left
    is the command's path (UART, parsing, callback) and the ramps' ``delay()`` timing. For the
    Python ports the command arrives when the link's frame ends (115200 baud); for ``avr`` its
    bytes start at t = 0 and every instruction is checked for a pin change.
    """
    from amr_twin.base.clock import VirtualClock
    from amr_twin.controllers.firmware import SKETCH_EDGES_PER_REV, make_firmware
    from amr_twin.ros.messages import Float64MultiArray
    from amr_twin.ros.rosserial import frame_bytes, frame_time_us

    clock = VirtualClock()
    fw = make_firmware(
        firmware, clock, lambda topic, value: None, edges_per_rev=SKETCH_EDGES_PER_REV
    )  # never turn
    events = []
    if firmware.startswith("avr"):
        board, lead = fw.board, fw.lead_cycles
        fw._sync_pins()
        fw.on_wheel_command(list(data))
        state = _pin_state(fw.pins)
        while board.run_until_change(lead + until_us * 16):
            fw._sync_pins()
            new = _pin_state(fw.pins)
            events += _changes((board.cycle - lead) // 16, state, new)
            state = new
        fw.close()
        return events
    fw.start()
    arrival = frame_time_us(frame_bytes(Float64MultiArray(data=list(data))), 115200)
    clock.schedule(arrival, lambda: fw.on_wheel_command(list(data)))
    state = _pin_state(fw.pins)
    while clock.next_event_us() <= until_us:
        clock.run_until(clock.next_event_us())
        new = _pin_state(fw.pins)
        events += _changes(clock.now_us, state, new)
        state = new
    return events


def timeline_table(port: list, board: list) -> dict:
    """Pair the pin changes of two :func:`command_timeline` lists (k-th change of each pin)."""
    rows = []
    for w in range(2):
        for pin in ("brake", "stop", "pwm"):
            a = [e for e in port if e[1] == w and e[2] == pin]
            b = [e for e in board if e[1] == w and e[2] == pin]
            for k, (ea, eb) in enumerate(zip(a, b)):
                rows.append(
                    {
                        "wheel": ("left", "right")[w],
                        "pin": pin,
                        "k": k + 1,
                        "value": [ea[3], eb[3]],
                        "t_port_ms": ea[0] / 1e3,
                        "t_board_ms": eb[0] / 1e3,
                        "dt_us": eb[0] - ea[0],
                    }
                )
            if len(a) != len(b):
                rows.append(
                    {
                        "wheel": ("left", "right")[w],
                        "pin": pin,
                        "k": None,
                        "value": [len(a), len(b)],
                        "t_port_ms": None,
                        "t_board_ms": None,
                        "dt_us": None,
                    }
                )
    return {"command": list(TIMELINE_COMMAND), "rows": rows}
