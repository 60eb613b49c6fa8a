"""Pacing a twin to the wall clock changes nothing it computes; other threads act on it
only at the pacer's ticks, in its own thread, and cannot stop it."""

import threading

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.live.pacer import Pacer, PacerClosed
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.rerun_capture import attach
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

STEPS = [
    (0.0, Command("linear", speed_m_s=0.5)),
    (2.5, Command("angular", speed_deg_s=-60.0, icc_m=-1.0)),
]


def _run(options, live: bool):
    cfg = load_config()
    twin = Twin(cfg, options)
    capture = attach(twin)
    session = None
    if (
        live
    ):  # the whole live session: pacer (unpaced), Foxglove server and its samplers, diff-drive node
        from amr_twin.live.session import LiveOptions, LiveSession

        session = LiveSession(twin, LiveOptions(port=0, rate=0.0), say=lambda _line: None)
    result = run_mission(cfg, STEPS, 5.0, options, twin=twin)
    if session is not None:
        assert session.pacer.ticks == 250  # 5 s at 20 ms: the ticks did run
        session.close()
    return result.series, capture


@pytest.mark.parametrize(
    "options",
    [
        TwinOptions(world="empty", sensors=("imu", "lidar")),
        TwinOptions(world="empty", firmware="improved", seed=3),
    ],
    ids=["faithful+sensors", "improved"],
)
def test_a_live_run_computes_what_a_plain_run_does(options):
    plain, plain_capture = _run(options, live=False)
    live, live_capture = _run(options, live=True)
    for name in ("t_s", "true_rpm", "pose", "pwm_counts", "odom", "battery_v", "current_a"):
        assert np.array_equal(getattr(plain, name), getattr(live, name)), name
    for w in (0, 1):
        assert np.array_equal(plain.published[w], live.published[w])
    a, b = plain_capture.state.arrays(), live_capture.state.arrays()
    assert all(np.array_equal(a[k], b[k]) for k in a)
    scans_a, scans_b = plain_capture.messages.get("scan", []), live_capture.messages.get("scan", [])
    assert len(scans_a) == len(scans_b)
    assert all(np.array_equal(x.ranges, y.ranges) for (_t, x), (_u, y) in zip(scans_a, scans_b))


def test_ticks_only_on_the_record_grid():
    twin = Twin(load_config(), TwinOptions(world="empty"))
    # a tick between grid instants moves the hall edges' interpolation points (1 us, 1e-4 RPM)
    with pytest.raises(ValueError, match="multiple of the record grid"):
        Pacer(twin, tick_us=15_000)
    with pytest.raises(ValueError, match="rate"):
        Pacer(twin, rate=-1.0)


def test_calls_run_at_ticks_in_the_twin_thread_and_cannot_stop_it(caplog):
    twin = Twin(load_config(), TwinOptions(world="empty"))
    pacer = Pacer(twin, rate=0.0)
    seen = []
    futures = []

    def other_thread():
        futures.append(
            pacer.post(lambda: seen.append((threading.current_thread().name, twin.clock.now_us)))
        )
        futures.append(pacer.post(lambda: 1 / 0))
        futures.append(pacer.post(lambda: twin.client.linear(0.4)))

    worker = threading.Thread(target=other_thread, name="client")
    worker.start()
    worker.join()
    assert seen == []  # nothing runs before the twin reaches a tick
    twin.advance(0.05)
    assert seen == [
        (threading.current_thread().name, 20_000)
    ]  # the first tick, in the twin's thread
    with pytest.raises(ZeroDivisionError):
        futures[1].result(timeout=0)
    assert futures[2].result(timeout=0) == 0 and "division by zero" in caplog.text
    late = pacer.post(lambda: None)
    pacer.close()
    with pytest.raises(PacerClosed):
        late.result(timeout=0)
    with pytest.raises(PacerClosed):
        pacer.post(lambda: None)
    twin.advance(0.1)  # the twin itself goes on; the closed pacer's ticks do nothing
    assert pacer.ticks == 2 and twin.t_s == pytest.approx(0.15)
