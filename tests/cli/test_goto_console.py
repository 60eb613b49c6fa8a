"""``run goto`` as a user drives it: help that states what runs, a progress line on stderr, Ctrl-C
that stops the robot and keeps the outputs."""

import json
import math
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from amr_twin.cli.main import app

RUN = CliRunner()
AMR_TWIN = str(Path(sys.executable).with_name("amr-twin"))


def _goto_params() -> dict:
    from amr_twin.cli.run import app as run_app

    command = typer.main.get_command(run_app).commands["goto"]
    return {p.opts[0]: p for p in command.params if p.opts[0] != "--help"}


def _stated(param) -> str | None:
    """The default an option's help states: its own text's 'default ...', else the [default: X]
    typer shows."""
    found = re.search(r"\bdefault:? ([^;,()]+?)(?:[;,()]|\.? *$)", param.help or "")
    if found:
        return found.group(1).strip()
    if (
        param.default is not None
        and param.default is not False
        and param.default != []
        and not param.is_flag
    ):
        return str(param.default)
    return None


def test_every_default_goto_help_states_is_what_runs(monkeypatch):
    """goto --help used to state the faithful firmware and 10 s while goto ran the improved one for
    60 s + 4 s per metre: each stated default is checked here against what reaches the navigation
    stack."""
    import amr_twin.cli.live_options as live_options
    import amr_twin.navigation.navigation_run as navigation_run
    from amr_twin.live.session import RERUN_WEB_PORT
    from amr_twin.model.config import load_config

    seen = {}
    real_live = live_options.checked_live

    def live(*a, **k):
        seen["live"] = real_live(*a, **k)
        return seen["live"]

    def navigate(cfg, twin_options, nav_options, **k):
        seen.update(cfg=cfg, twin=twin_options, nav=nav_options)
        raise SystemExit(0)

    monkeypatch.setattr(live_options, "checked_live", live)
    monkeypatch.setattr(navigation_run, "navigate", navigate)
    res = RUN.invoke(app, ["run", "goto", "--goal=-6,0", "--live"])
    assert "cfg" in seen, res.output
    cfg, twin, nav, live_opts = seen["cfg"], seen["twin"], seen["nav"], seen["live"]
    nominal = load_config()
    limit = re.search(r"(\d+) s \+ (\d+) s per metre", _goto_params()["--duration-s"].help)
    checks = {
        "--map": lambda d: d.startswith("the world's true map") and nav.map_yaml is None,
        "--localisation": lambda d: d == nav.localisation,
        "--controller": lambda d: d == nav.controller,
        "--xy-tolerance-m": lambda d: float(d) == cfg.navigation.navigator.xy_tolerance_m,
        "--yaw-tolerance-deg": lambda d: (
            abs(math.radians(float(d)) - cfg.navigation.navigator.yaw_tolerance_rad) < 1e-3
        ),
        "--inflation-radius-m": lambda d: float(d) == cfg.navigation.costmap.inflation_radius_m,
        "--duration-s": lambda d: (
            nav.timeout_s is None
            and limit is not None
            and (float(limit.group(1)), float(limit.group(2)))
            == (navigation_run.LIMIT_BASE_S, navigation_run.LIMIT_S_PER_M)
        ),
        "--firmware": lambda d: d.split()[0] == twin.firmware,
        "--seed": lambda d: int(d) == twin.seed,
        "--world": lambda d: d == twin.world,
        "--start": lambda d: d.startswith("the world's") and twin.start_xy_yaw is None,
        "--config": lambda d: (
            d == "models/amr/amr.yaml" and cfg.model_dump() == nominal.model_dump()
        ),
        "--host": lambda d: d == live_opts.host,
        "--rate": lambda d: float(d.split()[0]) == live_opts.rate,
        "--web-port": lambda d: (
            _goto_params()["--web-port"].default is None and int(d) == RERUN_WEB_PORT
        ),
    }
    stated = {flag: _stated(p) for flag, p in _goto_params().items()}
    stated = {flag: d for flag, d in stated.items() if d is not None}
    assert set(stated) == set(checks), set(stated) ^ set(
        checks
    )  # a new stated default needs its check here
    wrong = {flag: d for flag, d in stated.items() if not checks[flag](d)}
    assert not wrong, wrong


def test_the_progress_line_is_bounded_in_rate_and_tells_what_is_left():
    from amr_twin.cli.goto_console import GotoConsole
    from amr_twin.navigation.navigator import GoalOutcome

    class Nav:
        outcomes = [GoalOutcome((10.0, -4.8, None))]
        active = outcomes[0]
        pose_source = type("P", (), {"ready": True, "velocity": (0.6, 0.0)})()
        distance_left_m = 30.0

    wall, lines = [0.0], []
    console = GotoConsole(lines.append, wall=lambda: wall[0], period_s=2.0)
    nav = Nav()
    for k in range(40):  # 20 simulated s at 0.5 s a call, 0.25 wall s a call: 10 wall s
        nav.distance_left_m = 30.0 - 0.3 * k
        wall[0] += 0.25
        console(nav, 2.0 + 0.5 * k)
    assert 4 <= len(lines) <= 5  # one every 2 wall s at most, none in the first 2
    last = lines[-1]
    assert "goal 1 of 1 (10, -4.8)" in last and "0.60 m/s" in last and "0 recoveries" in last
    left = float(re.search(r"([\d.]+) m left", last).group(1))
    eta = float(re.search(r"about (\d+) s left", last).group(1))
    assert eta == pytest.approx(left / 0.6, abs=1)  # 0.3 m per 0.5 s: 0.6 m/s of progress


def test_progress_goes_to_stderr_never_into_the_json(monkeypatch):
    import amr_twin.cli.goto_console as console

    monkeypatch.setattr(console, "PERIOD_S", 0.0)
    res = RUN.invoke(
        app,
        [
            "run",
            "goto",
            "--goal=-6,0",
            "--start=-9,0,0",
            "--localisation",
            "truth",
            "--controller",
            "rpp",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["goals"][0]["status"] == "succeeded"
    progress = [line for line in res.stderr.splitlines() if line.startswith("goto: t ")]
    assert len(progress) >= 5 and all(
        " m left" in line or "planning" in line for line in progress
    ), res.stderr


def _start(args):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.Popen(
        [AMR_TWIN, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )


def _wait_for(proc, prefix: str) -> list[str]:
    lines = []
    for line in proc.stderr:
        lines.append(line)
        if line.startswith(prefix):
            return lines
    pytest.fail(f"no line starting {prefix!r}: {''.join(lines)[-2000:]}")


LONG = [
    "run",
    "goto",
    "--world",
    "aisles",
    "--goal",
    "15,-4.8",
    "--start=-20,-4.8,0",
    "--localisation",
    "truth",
    "--controller",
    "rpp",
    "--live",
    "--port",
    "0",
]
"""35 m down an aisle, served live (paced): the robot is on its way when the first progress line
comes."""


@pytest.mark.parametrize("seed", [0, 1])
def test_ctrl_c_cancels_the_goal_stops_the_robot_and_keeps_the_outputs(tmp_path, seed):
    proc = _start(
        [
            *LONG,
            "--rate",
            "4",
            "--seed",
            str(seed),
            "--json",
            "--csv",
            str(tmp_path / "run.csv"),
            "--mcap",
            str(tmp_path / "run.mcap"),
        ]
    )
    try:
        _wait_for(proc, "goto: t ")
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 6, err[-2000:]
    goal = json.loads(out)["goals"][0]
    assert goal["status"] == "canceled" and "Ctrl-C" in goal["reason"], goal
    assert "canceled by Ctrl-C" in err and "the outputs are written" in err
    import numpy as np

    rows = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True, skip_header=1)
    speed = np.hypot(np.diff(rows["x_m"]), np.diff(rows["y_m"])) / np.diff(rows["t_s"])
    assert speed.max() > 0.3 and speed[-20:].max() < 0.02  # it was driving; it stands at the end
    assert rows["x_m"][-1] < 14.0  # short of the goal
    from mcap.reader import make_reader

    with open(tmp_path / "run.mcap", "rb") as f:
        topics = {c.topic for c in make_reader(f).get_summary().channels.values()}
    assert {"/plan", "/cmd_vel", "/scan"} <= topics


def test_a_second_ctrl_c_quits_at_once_writing_nothing(tmp_path):
    proc = _start([*LONG, "--rate", "1", "--json", "--csv", str(tmp_path / "run.csv")])
    try:
        _wait_for(proc, "goto: t ")
        proc.send_signal(signal.SIGINT)
        _wait_for(proc, "goto: Ctrl-C")
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err[-2000:]
    assert out == "" and "no output written" in err and not (tmp_path / "run.csv").exists()
