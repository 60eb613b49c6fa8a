"""amr-twin run: options before or after the command kind, bounds, usage errors in one line."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.controllers.firmware import FIRMWARES

runner = CliRunner()
AMR_TWIN = Path(sys.executable).with_name("amr-twin")


def _json(args):
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    info = json.loads(res.stdout)
    info.pop("wall_s")
    return info


def test_options_before_the_kind_are_the_same_run_as_after_it(tmp_path):
    before, after = tmp_path / "before.csv", tmp_path / "after.csv"
    a = _json(
        [
            "run",
            "--payload-kg",
            "40",
            "--csv",
            str(before),
            "--world",
            "empty",
            "linear",
            "--speed-m-s",
            "0.7",
            "--duration-s",
            "2",
            "--json",
        ]
    )
    b = _json(
        [
            "run",
            "linear",
            "--speed-m-s",
            "0.7",
            "--duration-s",
            "2",
            "--json",
            "--payload-kg",
            "40",
            "--csv",
            str(after),
            "--world",
            "empty",
        ]
    )
    assert a == b and before.read_bytes() == after.read_bytes()
    plain = _json(
        ["run", "linear", "--speed-m-s", "0.7", "--duration-s", "2", "--json", "--world", "empty"]
    )
    assert plain["final_pose"] != a["final_pose"]  # the payload did act


def test_repeatable_options_collect_both_places_and_conflicts_are_refused():
    info = _json(
        [
            "run",
            "--fault",
            "estop@1",
            "--world",
            "empty",
            "stop",
            "--fault",
            "battery-sag@0.5",
            "--duration-s",
            "1.5",
            "--json",
        ]
    )
    assert [f["kind"] for f in info["faults"]] == ["estop", "battery-sag"]
    res = runner.invoke(
        app, ["run", "--payload-kg", "150", "linear", "--speed-m-s", "0.7", "--payload-kg", "20"]
    )
    assert res.exit_code == 2 and "--payload-kg given before and after 'linear'" in res.stderr


@pytest.mark.parametrize(
    "args, text",
    [
        (["--duration-s", "1e12"], "--duration-s 1e+12: must be in [0.1, 3600] s"),
        (["--duration-s", "0"], "must be in [0.1, 3600] s"),
        (["--firmware", "avx"], f"--firmware 'avx': must be one of {FIRMWARES.choices()}"),
        (["--fault", "hall-left-dead@30"], "not before the end of the run (10 s)"),
        (["--fault", "imu-stuck@1"], "needs the sensors"),
        (["--start", "1,2"], "--start '1,2': expected X_M,Y_M,YAW_DEG"),
    ],
)
def test_bounds_are_one_line_before_the_run(args, text, tmp_path):
    out = tmp_path / "never.csv"
    res = runner.invoke(app, ["run", "linear", "--speed-m-s", "0.5", "--csv", str(out), *args])
    assert res.exit_code == 2 and text in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_firmware_choices_come_from_the_firmware_factory():
    res = runner.invoke(app, ["run", "--help"])
    assert FIRMWARES.choices() in " ".join(res.output.replace("│", " ").split())
    res = runner.invoke(app, ["run", "stop", "--firmware", "avx"])
    assert res.exit_code == 2 and f"must be one of {FIRMWARES.choices()}" in res.stderr


@pytest.mark.parametrize(
    "command, default",
    [
        (["run"], "faithful"),
        (["experiment", "chapter5"], "faithful"),
        (["experiment", "fusion"], "improved"),
        (["sweep", "payload"], "faithful"),
    ],
)
def test_each_commands_default_firmware_is_in_its_help(command, default):
    """`experiment fusion` runs the improved firmware unless told otherwise, and its
    --help did not say so."""
    res = runner.invoke(app, [*command, "--help"], terminal_width=200)
    text = " ".join(res.output.replace("│", " ").split())
    assert f"or avr; default {default} (firmware.md in docs/explanation/" in text


def test_parser_errors_and_misplaced_options_are_one_line():
    def run(*args):
        return subprocess.run([str(AMR_TWIN), *args], capture_output=True, text=True, timeout=60)

    res = run("run", "linear", "--speed-m-s", "fast")
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "--speed-m-s" in res.stderr
    res = run("experiment", "--jobs", "2", "chapter5", "--out", "x")
    assert res.returncode == 2 and res.stderr.count("\n") == 1
    assert "put it after the command, e.g. amr-twin experiment chapter5 --jobs" in res.stderr
    res = run("run", "linear", "--mission", "m.yaml")
    assert res.returncode == 2 and "put it before 'linear'" in res.stderr


def test_only_the_invoked_group_is_built_and_the_app_is_restored():
    import typer.main

    full = {c.name or c.callback.__name__ for c in app.registered_commands} | {
        g.name for g in app.registered_groups
    }
    with app._only_group(["run", "linear", "--speed-m-s", "0.5"]):
        assert sorted(typer.main.get_command(app).commands) == ["run"]
    for argv in ([], ["--help"], ["model"], ["nosuch"], ["--config", "x", "run"]):
        with app._only_group(argv):
            assert set(typer.main.get_command(app).commands) == full
    assert {c.name or c.callback.__name__ for c in app.registered_commands} | {
        g.name for g in app.registered_groups
    } == full
    assert {"run", "experiment", "sweep", "model", "bench"} <= full


def test_start_up_gc_settings_end_when_the_parameters_are_loaded():
    """Rare collections only while a command starts: once its parameters are loaded the usual
    thresholds are back (a long sweep frees each point's twin) and the start-up objects are
    frozen."""
    code = (
        "import gc; from amr_twin.cli import common; default = gc.get_threshold(); "
        "common.start_up(); "
        "during = gc.get_threshold(); common._config(None, None, []); "
        "print(default == gc.get_threshold(), during == common.START_UP_GC_THRESHOLDS, "
        "gc.get_freeze_count() > 10000)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert out.stdout.split() == ["True", "True", "True"]
