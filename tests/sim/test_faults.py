"""Fault injection: the specification grammar, and each fault's effect on the twin."""

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.sim.faults import FaultError, kind_names, parse_fault, parse_faults
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

CFG = load_config()


def _run(faults, firmware="improved", duration_s=4.0, speed=0.5, sensors=False, steps=None, seed=0):
    options = TwinOptions(
        world="empty",
        firmware=firmware,
        sensors=("imu", "lidar") if sensors else (),
        seed=seed,
        faults=parse_faults(faults, sensors=sensors),
    )
    return run_mission(
        CFG, steps or [(0.0, Command("linear", speed_m_s=speed))], duration_s, options
    )


def _mean(series, w, t0, t1):
    sel = (series.t_s >= t0) & (series.t_s < t1)
    return float(np.mean(series.true_rpm[sel, w]))


# -- grammar ---------------------------------------------------------------------------


def test_specifications_parse_into_kind_wheel_time_value_and_end():
    f = parse_fault("hall-right-dead@3.5:b")
    assert (f.kind, f.wheel, f.t_s, f.until_s, f.value, f.name) == (
        "hall-dead",
        1,
        3.5,
        None,
        "b",
        "hall-right-dead",
    )
    f = parse_fault("rosserial-loss@2:p=0.3,for=5")
    assert (f.kind, f.wheel, f.value, f.until_s) == ("rosserial-loss", None, 0.3, 7.0)
    assert parse_fault("estop@1").value is None and parse_fault("battery-sag@0").value == 10.0
    assert len(kind_names()) == 15 and "wheel-left-lifted" in kind_names()


@pytest.mark.parametrize(
    "text, message",
    [
        ("hall-left-dead", "expected KIND@T"),
        ("hall-middle-dead@3", "unknown fault 'hall-middle-dead'"),
        ("hall-left-dead@x", "T='x' is not a number"),
        ("hall-left-dead@-1", "must be >= 0"),
        ("hall-left-dead@1:d", "sensor='d' must be one of all, a, b, c"),
        ("rosserial-loss@1:0", "p=0 must lie in (0, 1]"),
        ("rosserial-loss@1:1.5", "must lie in (0, 1]"),
        ("estop@1:3", "estop takes only for=S"),
        ("estop@1:for=0", "for=0 s must be > 0"),
        ("battery-sag@1:volts=3", "unknown argument 'volts'"),
        ("hall-left-chatter@1:nan", "must be finite"),
    ],
)
def test_bad_specifications_are_one_line_naming_them(text, message):
    with pytest.raises(FaultError) as exc:
        parse_fault(text)
    assert message in str(exc.value) and text in str(exc.value) and "\n" not in str(exc.value)


def test_faults_are_checked_against_the_run():
    with pytest.raises(FaultError, match="not before the end of the run"):
        parse_faults(["estop@12"], duration_s=10)
    with pytest.raises(FaultError, match="needs the sensors"):
        parse_faults(["lidar-dead@1"], sensors=False)
    with pytest.raises(FaultError, match="at most 64"):
        parse_faults(["estop@1"] * 65)


# -- effects ------------------------------------------------------------------------------


def test_hall_dead_silences_the_wheel_and_the_improved_firmware_runs_it_away():
    faithful = _run(["hall-left-dead@2"], firmware="faithful", duration_s=6.0).series
    pub_after = faithful.published[0][faithful.published[0][:, 0] >= 2.0]
    assert (
        len(pub_after) == 0 and len(faithful.published[1][faithful.published[1][:, 0] >= 2.0]) >= 2
    )
    assert _mean(faithful, 0, 5.0, 6.0) == pytest.approx(
        _mean(faithful, 0, 1.5, 2.0), abs=2.0
    )  # open loop
    improved = _run(["hall-left-dead@2"]).series
    left = improved.published[0]
    assert np.all(left[left[:, 0] > 2.3, 1] == 0.0)  # reads the silent wheel as stopped
    assert _mean(improved, 0, 3.5, 4.0) > 50.0  # and winds it up (reference 38.2)
    assert _mean(improved, 1, 3.5, 4.0) == pytest.approx(38.2, abs=1.5)


def test_one_stuck_hall_sensor_reads_two_thirds_of_the_speed():
    s = _run(["hall-left-dead@2:a"], duration_s=4.0).series
    pub = s.published[0]
    late = pub[pub[:, 0] >= 3.0, 1]
    ratio = np.mean(late) / _mean(s, 0, 3.0, 4.0)
    assert ratio == pytest.approx(2 / 3, abs=0.04)


def test_chatter_adds_counts_reproducibly_with_the_seed():
    a = _run(["hall-left-chatter@1:500"], duration_s=2.0).series
    pub = a.published[0]
    assert np.mean(pub[pub[:, 0] > 1.2, 1]) > 2.0 * _mean(
        a, 0, 1.2, 2.0
    )  # counts the glitches as rotation
    b = _run(["hall-left-chatter@1:500"], duration_s=2.0).series
    c = _run(["hall-left-chatter@1:500"], duration_s=2.0, seed=1).series
    assert np.array_equal(a.true_rpm, b.true_rpm) and not np.array_equal(a.true_rpm, c.true_rpm)


def test_motor_stall_holds_the_wheel_until_it_clears():
    s = _run(["motor-left-stall@2:for=1"], duration_s=4.5).series
    assert abs(_mean(s, 0, 2.5, 3.0)) < 5.0 and _mean(s, 1, 2.5, 3.0) > 30.0
    assert _mean(s, 0, 4.0, 4.5) > 30.0  # free again


def test_a_lifted_wheel_carries_no_load():
    twin = Twin(
        CFG, TwinOptions(world="empty", faults=parse_faults(["wheel-right-lifted@1:for=1"]))
    )
    twin.client.linear(0.3)
    twin.advance(1.5)
    loads = twin.physics.support.loads_n()
    assert loads["wheel_right"] == 0.0 and loads["wheel_left"] > 50.0
    twin.advance(1.0)
    assert twin.physics.support.loads_n()["wheel_right"] > 50.0


def test_a_cut_link_loses_the_stop_command():
    steps = [(0.0, Command("linear", speed_m_s=0.5)), (2.5, Command("stop"))]
    cut = _run(["rosserial-loss@2"], duration_s=4.0, steps=steps).series
    ok = _run([], duration_s=4.0, steps=steps).series
    assert abs(_mean(ok, 0, 3.5, 4.0)) < 1.0  # the stop arrived
    assert _mean(cut, 0, 3.5, 4.0) > 30.0  # no watchdog: still driving
    assert len(cut.published[0][cut.published[0][:, 0] > 2.0]) == 0


def test_latency_delays_the_command_by_its_value():
    def first_drive(series):
        return float(series.t_s[np.argmax(series.pwm_counts[:, 0] > 0)])

    late = _run(["rosserial-latency@0:200"], duration_s=1.0).series
    now = _run([], duration_s=1.0).series
    assert first_drive(late) - first_drive(now) == pytest.approx(0.2, abs=0.011)


def test_lidar_dead_and_imu_stuck_change_the_topics_not_the_motion():
    r = _run(["lidar-dead@1", "imu-stuck@1"], duration_s=2.0, sensors=True)
    lidar, imu = r.faults
    assert lidar["effect"]["scan_published_after"] == 0
    assert imu["effect"]["imu/data_raw_published_after"] == 101
    assert imu["effect"]["imu/data_raw_distinct_values_after"] == 1
    plain = _run([], duration_s=2.0)
    assert np.array_equal(r.series.pose, plain.series.pose)


def test_battery_sag_lowers_the_voltage_and_the_faithful_speed():
    s = _run(["battery-sag@2:12"], firmware="faithful", duration_s=5.0).series
    before, after = (
        np.mean(s.battery_v[(s.t_s > 1.5) & (s.t_s < 2.0)]),
        np.mean(s.battery_v[s.t_s > 4.5]),
    )
    assert before - after == pytest.approx(12.0, abs=0.5)
    assert _mean(s, 0, 4.5, 5.0) < 0.8 * _mean(s, 0, 1.5, 2.0)


@pytest.mark.parametrize("fault", ["battery-cut@2:for=1", "estop@2:for=1"])
def test_power_faults_let_the_wheels_coast_then_drive_again(fault):
    s = _run([fault], duration_s=4.5).series
    during = (s.t_s > 2.05) & (s.t_s < 3.0)
    assert np.all(s.mode[during] == 1)  # coast
    assert _mean(s, 0, 2.9, 3.0) < 0.8 * _mean(s, 0, 1.5, 2.0)
    assert np.all(s.mode[s.t_s > 3.05] == 0) and _mean(s, 0, 4.0, 4.5) > 30.0


def test_the_acceptance_command_shows_the_fault_and_its_effect():
    res = CliRunner().invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--duration-s",
            "10",
            "--world",
            "empty",
            "--fault",
            "hall-left-dead@3",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    (fault,) = info["faults"]
    assert fault["kind"] == "hall-left-dead" and fault["t_s"] == 3.0 and fault["wheel"] == "left"
    left = fault["effect"]["wheels"]["left"]
    assert left["published_after"] == 0 and left["last_published_t_s"] < 3.0
    assert left["true_rpm_end"] > 30.0  # the wheel turns, unseen
    assert fault["effect"]["wheels"]["right"]["published_after"] >= 3
    assert math.isclose(info["sim_s"], 10.0)
