"""The sketch on the emulated ATmega2560 against the faithful Python port, sample by sample.

Needs the Debian packages named in the README (gcc-avr, avr-libc, arduino-core-avr, simavr,
libsimavr-dev); without them every test here is skipped with that reason. Runs are short (a few
simulated seconds); the whole chapter 5 comparison is `amr-twin experiment chapter5 --firmware avr`.
"""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.model.config import load_config
from amr_twin.controllers.avr_build import DEFAULT_SKETCH, SketchError, build_sketch, missing_tools
from amr_twin.controllers.firmware import AvrParams
from amr_twin.assembly.twin import TwinOptions
from amr_twin.ros.rosserial import PC_TO_ARDUINO
from amr_twin.ros.rosserial_frame import MD5SUM
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_command
from amr_twin.recording.recorder import attach_recorder, recorder_of

MISSING = missing_tools()
needs_avr = pytest.mark.skipif(MISSING is not None, reason=MISSING or "")
runner = CliRunner()
LINEAR = Command("linear", speed_m_s=0.7)


@pytest.fixture(scope="module")
def cfg():
    return load_config()


def _run(cfg, firmware, seconds, command=LINEAR, params=None, **options):
    opts = TwinOptions(firmware=firmware, world="empty", firmware_params=params, **options)
    return run_command(cfg, command, seconds, opts).series


def _sketch_copy(tmp_path: Path, old: str, new: str) -> Path:
    sketch = tmp_path / "motor_control"
    shutil.copytree(DEFAULT_SKETCH, sketch)
    ino = sketch / "motor_control.ino"
    text = ino.read_text()
    assert old in text
    ino.write_text(text.replace(old, new))
    return sketch


def test_sketch_option_needs_the_avr_firmware():
    result = runner.invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.5",
            "--duration-s",
            "0.1",
            "--sketch",
            str(DEFAULT_SKETCH),
        ],
    )
    assert result.exit_code == 2
    assert "--sketch is used with --firmware avr only" in result.output
    result = runner.invoke(
        app, ["run", "linear", "--speed-m-s", "0.5", "--firmware", "avr", "--sketch", "/no/such"]
    )
    assert (
        result.exit_code == 2
        and result.output.count("\n") == 1
        and "--sketch /no/such: not a folder" in result.output
    )


@needs_avr
def test_emulated_board_matches_the_faithful_port_sample_by_sample(tmp_path):
    # chapter 5 run 1 (left wheel 76.39 RPM) through the CLI, which also runs faithful and compares
    result = runner.invoke(
        app,
        [
            "experiment",
            "chapter5",
            "--firmware",
            "avr",
            "--runs",
            "1",
            "--duration-s",
            "5",
            "--out",
            str(tmp_path),
            "--no-progress",
        ],
    )
    assert result.exit_code == 0, result.output
    comp = json.loads((tmp_path / "metrics.json").read_text())["firmware_comparison"]
    (row,) = comp["rows"]
    assert row["samples"][0] == row["samples"][1] >= 3
    # the board answers later (UART, parsing, a ramp that drifts 50 us a step): samples ~1 ms later;
    # the first one, taken while the wheel accelerates, a few hundredths of an RPM apart, then equal
    # to float32 and 4 us micros()
    assert 0.0 < row["first_dt_ms"] < 5.0 and row["max_abs_dt_ms"] < 10.0
    assert row["max_abs_drpm"] < 0.1 and abs(row["final_drpm"]) < 0.01
    assert row["pwm_differs_pct"] < 1.0 and row["true_rms_drpm"] < 0.1
    assert comp["verdict"] == "pass"
    # paced, the reference samples the physics as the board's loop does: the same differences remain
    assert abs(row["paced"]["final_drpm"]) < 0.01 and row["paced"]["max_abs_drpm"] < 0.1
    # the command's path on the board: the first pin write 0.1 to 0.5 ms after the port's, and each
    # 50 ms ramp step some tens of microseconds longer
    tl = [r for r in comp["timeline"]["rows"] if r["wheel"] == "left" and r["pin"] == "pwm"]
    assert 100 < tl[0]["dt_us"] < 500
    assert 10 < (tl[-1]["dt_us"] - tl[0]["dt_us"]) / (len(tl) - 1) < 200
    assert "## Firmware against firmware, sample by sample" in (tmp_path / "report.md").read_text()


@needs_avr
def test_changing_ki_in_the_sketch_changes_the_result(cfg, tmp_path):
    sketch = _sketch_copy(tmp_path, "double ki = 0.15;", "double ki = 1.5;")
    base = _run(cfg, "avr", 3.5)
    changed = _run(cfg, f"avr:{sketch}", 3.5)
    faithful = _run(cfg, "faithful", 3.5)
    # the first samples come before any PI action: identical; the PI's first write differs
    np.testing.assert_array_equal(base.published[0][0], changed.published[0][0])
    first_pi = np.argmax(np.any(base.pwm_counts != faithful.pwm_counts, axis=1) | (base.t_s > 1.6))
    assert np.array_equal(base.pwm_counts[:first_pi], changed.pwm_counts[:first_pi])
    assert not np.array_equal(base.pwm_counts, changed.pwm_counts)
    assert (
        changed.pwm_counts[-1, 0] > base.pwm_counts[-1, 0]
    )  # a larger integral gain adds more duty
    assert abs(base.published[0][1, 1] - changed.published[0][1, 1]) > 0.5


@needs_avr
def test_idle_sleep_of_spin_once_changes_nothing_observable(cfg):
    sleeping = _run(cfg, "avr", 2.5, Command("motor", wheel="left", speed_m_s=1.0))
    busy = _run(
        cfg, "avr", 2.5, Command("motor", wheel="left", speed_m_s=1.0), AvrParams(idle_sleep=False)
    )
    assert len(sleeping.published[0]) == len(busy.published[0]) >= 1
    # the sleeping loop and the busy one wait in delay() with different instructions, so a ramp step
    # can end a few cycles apart and cross a 1 ms physics step in one and not the other: the samples
    # then differ by a few thousandths of an RPM (0.004 seen), their times by a tenth of a
    # millisecond
    np.testing.assert_allclose(sleeping.published[0][:, 1], busy.published[0][:, 1], atol=0.01)
    np.testing.assert_allclose(sleeping.published[0][:, 0], busy.published[0][:, 0], atol=3e-4)
    np.testing.assert_array_equal(sleeping.pwm_counts, busy.pwm_counts)


@needs_avr
def test_published_speeds_are_the_boards_32_bit_doubles(cfg):
    avr = np.concatenate([_run(cfg, "avr", 3.0).published[w][:, 1] for w in (0, 1)])
    faithful = np.concatenate([_run(cfg, "faithful", 3.0).published[w][:, 1] for w in (0, 1)])
    assert len(avr) >= 2
    assert np.all(avr.astype(np.float32).astype(np.float64) == avr)
    assert not np.all(faithful.astype(np.float32).astype(np.float64) == faithful)


@needs_avr
def test_a_corrupted_command_frame_is_refused_by_the_boards_checksum(cfg):
    from amr_twin.assembly.twin import Twin

    twin = Twin(cfg, TwinOptions(firmware="avr", world="empty", rosserial_loss_prob=1.0))
    LINEAR.send(twin)
    twin.advance(1.0)
    assert twin.link.frames_lost[PC_TO_ARDUINO] == 1
    assert all(
        p.pwm_counts == 0 and p.brake_level == 1 for p in twin.firmware.pins
    )  # as setup() left them
    ok = Twin(cfg, TwinOptions(firmware="avr", world="empty"))
    LINEAR.send(ok)
    ok.advance(1.0)
    assert all(p.pwm_counts > 0 and p.brake_level == 0 for p in ok.firmware.pins)


@needs_avr
def test_the_sketch_announces_its_topics_as_rosserial_does():
    from amr_twin.controllers.avr_sketch import topic_table

    pubs, subs = topic_table(str(build_sketch()))
    assert [(p.topic_id, p.topic_name, p.message_type, p.md5sum) for p in pubs] == [
        (125, "wheel0_Vel", "std_msgs/Float64", MD5SUM["std_msgs/Float64"]),
        (126, "wheel1_Vel", "std_msgs/Float64", MD5SUM["std_msgs/Float64"]),
    ]
    assert [(s.topic_id, s.topic_name, s.message_type) for s in subs] == [
        (100, "wheel_Command", "std_msgs/Float64MultiArray")
    ]


@needs_avr
def test_build_is_cached_per_source(tmp_path):
    elf = build_sketch()
    mtime = elf.stat().st_mtime_ns
    assert build_sketch() == elf and elf.stat().st_mtime_ns == mtime
    other = build_sketch(_sketch_copy(tmp_path, "double kp = 0.001;", "double kp = 0.002;"))
    assert other != elf and other.exists()


@needs_avr
def test_a_sketch_that_does_not_compile_is_one_line_naming_the_file(tmp_path):
    sketch = _sketch_copy(tmp_path, "void loop()", "void loop() oops")
    with pytest.raises(SketchError, match=r"motor_control\.ino:\d+:\d+: error"):
        build_sketch(sketch)
    result = runner.invoke(
        app, ["run", "linear", "--speed-m-s", "0.7", "--firmware", "avr", "--sketch", str(sketch)]
    )
    assert result.exit_code == 2
    assert result.output.count("\n") == 1 and "motor_control.ino" in result.output


@needs_avr
def test_cli_run_with_the_emulated_board(cfg):
    result = runner.invoke(
        app,
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.7",
            "--duration-s",
            "3",
            "--world",
            "empty",
            "--firmware",
            "avr",
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    info = json.loads(result.stdout)
    faithful = _run(cfg, "faithful", 3.0)
    for w, name in enumerate(("left", "right")):
        assert info["wheels"][name]["samples"] == len(faithful.published[w]) >= 1
        assert info["wheels"][name]["final_rpm"] == pytest.approx(
            faithful.published[w][-1, 1], abs=0.05
        )


def _pwm_log(kind: str, until_us: int) -> list[tuple[int, int]]:
    """Left PWM counts, on a bare clock: left wheel at 20 RPM of SC edges; commands at 0, 1.0, 1.1
    s."""
    from amr_twin.base.clock import VirtualClock
    from amr_twin.controllers.firmware import SKETCH_EDGES_PER_REV, make_firmware

    clock = VirtualClock()
    fw = make_firmware(kind, clock, lambda topic, value: None, edges_per_rev=SKETCH_EDGES_PER_REV)
    fw.start()
    period = int(60e6 / (SKETCH_EDGES_PER_REV * 20))

    def edge(t):
        fw.on_sc_edge(0)
        clock.schedule(t + period, lambda: edge(t + period))

    clock.schedule(period, lambda: edge(period))
    for t, cmd in ((0, [1, 20, 1, 0]), (1_000_000, [1, 150, 1, 0]), (1_100_000, [1, 300, 1, 0])):
        clock.schedule(t, lambda cmd=cmd: fw.on_wheel_command(cmd))
    log, last = [], None
    while clock.now_us < until_us:
        clock.run_until(clock.now_us + 1000)
        if fw.pins[0].pwm_counts != last:
            last = fw.pins[0].pwm_counts
            log.append((clock.now_us, last))
    return log


@needs_avr
def test_a_command_queued_during_a_ramp_waits_for_the_ramp_on_the_board_as_in_the_port():
    # listing 4.12 calls node.spinOnce() inside speedChangeInt; ros_lib's spinOnce() does nothing
    # inside an interrupt (no frame read or written there), so the third command, waiting in the
    # serial buffer while loop() sits in the second's ramp, runs in main context when that ramp ends
    # (3.5 s), as in the port; before, it ran inside the ISR at the next sample (~3.2 s) and its
    # ramp to 300 RPM (72 counts) collapsed into milliseconds (docs/explanation/firmware.md)
    board, port = _pwm_log("avr", 3_600_000), _pwm_log("faithful", 3_600_000)
    assert all(c < 60 for _, c in board) and all(c < 60 for _, c in port)
    late = [(t, c) for t, c in board if t > 2_900_000]
    assert [c for _, c in late] == [c for t, c in port if t > 2_900_000] == [32, 36, 33, 11]
    for (tb, _), (tp, _) in zip(late, [x for x in port if x[0] > 2_900_000]):
        assert (
            0 <= tb - tp < 10_000
        )  # each step a few ms later on the board (its ramp's arithmetic)


@needs_avr
def test_the_board_asks_the_time_every_5_s_and_keeps_publishing_while_answered(cfg, monkeypatch):
    from amr_twin.controllers.avr import AvrFirmware
    from amr_twin.assembly.twin import Twin

    def run(answer: bool):
        if not answer:
            monkeypatch.setattr(AvrFirmware, "_answer_time", lambda self: None)
        twin = Twin(cfg, TwinOptions(firmware="avr", world="empty"))
        attach_recorder(twin)
        Command("motor", wheel="left", speed_m_s=0.5).send(twin)
        twin.advance(19.0)
        return twin.firmware.time_requests, recorder_of(twin).series().published[0][:, 0]

    requests, t_s = run(True)
    assert (
        requests == 3
    )  # at 5, 10 and 15 s (ros_lib's SYNC_PERIOD_MS), each answered with the sim time
    assert t_s[-1] > 17.0
    # unanswered, the board takes the host for gone after 15 s (SYNC_TIMEOUT_MS) and stops
    # publishing
    requests, t_s = run(False)
    assert requests == 2 and 13.0 < t_s[-1] < 15.1  # the third request would be due as it gives up
