"""Bad inputs of issue 33, each refused cleanly or answered correctly (the table: docs/bad_inputs.md).

A clean refusal: exit 2, one line on stderr naming the option or the file and what is allowed,
nothing written (the folder the test works in is unchanged), before the work. The commands are
called as a user calls them, through the app's own entry (``app(args=...)``: usage errors are
one line too), in this process. An output that is an input: tests/cli/test_path_options.py; an
output in use: tests/recording/test_output_lock.py.
"""

import gc
import os
import resource
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from amr_twin.cli.main import app

ROOT = Path(__file__).resolve().parents[2]
ROUTE = ROOT / "experiments" / "routes" / "warehouse_60m.yaml"
AMR_TWIN = Path(sys.executable).with_name("amr-twin")


def _listing(folder: Path) -> dict:
    return {p.relative_to(folder): (p.stat().st_mtime_ns, p.stat().st_size) if p.is_file() else None
            for p in sorted(folder.rglob("*"))}


def _call(args) -> int:
    thresholds = gc.get_threshold()
    try:
        app(args=[str(a) for a in args], prog_name="amr-twin")
    except SystemExit as exc:
        return exc.code
    finally:
        gc.set_threshold(*thresholds)  # the app's start-up settings stay in the app
    return 0


@pytest.fixture
def refused(tmp_path, capsys):
    """``refused(args, *words)``: exit 2, one line holding every word, ``tmp_path`` unchanged; the line."""
    def check(args, *words, code=2):
        before = _listing(tmp_path)
        got = _call(args)
        lines = capsys.readouterr().err.strip().splitlines()
        assert got == code, (args, lines)
        assert len(lines) == 1 and lines[0].startswith("error: "), (args, lines)
        assert all(w in lines[0] for w in words), (args, lines[0])
        assert _listing(tmp_path) == before, args
        return lines[0]
    return check


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


# ---------------------------------------------------------------------------------------------- bounds
def test_calibrate_refuses_unbounded_logs_before_simulating(tmp_path, refused):
    out = tmp_path / "never.yaml"
    late = _write(tmp_path / "late.csv", "t_s,wheel,rpm,command\n1e6,left,3,linear:0.5\n")
    refused(["calibrate", "--target", late, "--out", out], f"--target {late}:2: t_s 1e+06 must lie in [0, 3599.5] s")
    many = _write(tmp_path / "many.csv", "t_s,wheel,rpm,command\n" + "".join(
        f"3000,left,3,linear:0.{i}\n" for i in range(1, 3)))
    refused(["calibrate", "--target", many, "--out", out], "--target", "6001 s in all", "at most 3600 s")
    fast = _write(tmp_path / "fast.csv", "t_s,wheel,rpm,command\n1,left,1e300,linear:0.5\n")
    refused(["calibrate", "--target", fast, "--out", out], "rpm 1e+300 must lie within +-2000 RPM")
    refused(["calibrate", "--jobs", 10 ** 6, "--out", out], "--jobs 1000000: must be in 1..")
    refused(["calibrate", "--max-evaluations", 2, "--out", out], "--max-evaluations 2: must be in 6..2000")


def _route(tmp_path: Path, name: str, **changes) -> Path:
    text = ROUTE.read_text()
    for old, new in changes.items():
        text = text.replace(old.replace("_", " "), new)
    return _write(tmp_path / f"{name}.yaml", text)


def test_fusion_routes_outside_the_world_or_too_long_are_refused_before_the_drive(tmp_path, refused, monkeypatch):
    monkeypatch.setattr("amr_twin.experiments.fusion.drive", None)  # were one not refused, it would fail at once
    out = tmp_path / "never"
    goal = "  - [6.2, -1.4]\n"
    cases = {"outside": ("  - [60.0, -1.4]\n", "waypoints_xy_m[5] (60, -1.4) lies outside the world of warehouse"),
             "in_rack": ("  - [0.0, 3.0]\n", "waypoints_xy_m[5] (0, 3) is 0.00 m from rack_n_beam_low"),
             "crossing": ("  - [6.2, -1.4]\n  - [-3.0, 2.0]\n  - [-3.0, 5.5]\n",
                          "the leg to waypoints_xy_m[7] (-3, 5.5) crosses a geom")}
    for name, (waypoints, words) in cases.items():
        route = _write(tmp_path / f"{name}.yaml", ROUTE.read_text().replace(goal, waypoints))
        refused(["experiment", "fusion", "--route", route, "--out", out], f"--route {route}: ", words)
    slow = _write(tmp_path / "slow.yaml", ROUTE.read_text().replace("max_speed_m_s: 1.0", "max_speed_m_s: 0.01"))
    refused(["experiment", "fusion", "--route", slow, "--out", out], "may take 18153 s of simulation",
            "at most 3600 s")


def test_a_mission_s_duration_is_bounded_naming_the_file(tmp_path, refused):
    mission = _write(tmp_path / "m.yaml", "duration_s: 99999\nsteps:\n  - {t_s: 0, stop: {}}\n")
    refused(["run", "--mission", mission], f"mission {mission}: duration_s: 99999 must be in [0.1, 3600] s")
    square = ROOT / "experiments" / "missions" / "square.yaml"
    refused(["run", "--mission", square, "--duration-s", 1], "--duration-s 1: ends before the mission's last step")
    refused(["run", "stop", "--duration-s", "1e-9"], "--duration-s 1e-09: must be in [0.1, 3600] s")


def test_a_long_sweep_needs_yes_and_says_its_estimate(tmp_path, refused, monkeypatch, capsys):
    """201 masses x 9 positions x 5 commands: 9045 points of 8 s, ~13 min on 2 processes (7 on 4)."""
    args = ["sweep", "payload", "--out", tmp_path / "sweep", "--masses", "0:200:1", "--jobs", 1,
            "--positions", "center,front,rear,left,right,front-left-corner,front-right-corner,rear-left-corner,"
            "rear-right-corner", "--commands", "linear:0.7,linear:0.3,angular:60:-1,angular:30:0,motor:left:1"]

    class Started(Exception):
        pass

    def simulate(*_args, **_kwargs):
        raise Started

    monkeypatch.setattr("amr_twin.experiments.executor.run_all", simulate)  # no point is simulated here
    refused(args, "sweep payload: 9045 points to simulate (of 9045): about ", "add --yes")
    with pytest.raises(Started):  # with --yes the points start
        _call([*args, "--yes"])
    assert "note: sweep payload: 9045 points to simulate" in capsys.readouterr().err
    monkeypatch.setattr("amr_twin.experiments.chapter5.run", simulate)
    monkeypatch.setattr("amr_twin.experiments.fusion_seeds.run", simulate)
    refused(["experiment", "chapter5", "--out", tmp_path / "c5", "--samples", 4096], "experiment chapter5: ",
            "add --yes")
    refused(["experiment", "fusion", "--out", tmp_path / "f", "--seeds", "0:999"], "1000 drives", "add --yes")


def test_a_run_larger_than_the_memory_available_is_refused(tmp_path, refused, monkeypatch):
    monkeypatch.setattr("amr_twin.sim.bounds.available_mb", lambda: 1000.0)
    with monkeypatch.context() as guard:
        guard.setattr("amr_twin.sim.run.run_mission", None)  # were it not refused, it would fail at once
        refused(["run", "stop", "--duration-s", 3600, "--sensors", "--mcap", tmp_path / "r.mcap"],
                "--duration-s 3600: the run would need about 4.8 GB of memory", "1.0 GB are available")
    assert _call(["run", "stop", "--duration-s", 5, "--sensors", "--mcap", tmp_path / "r.mcap"]) == 0


def test_the_client_stops_at_the_bound_of_a_run(monkeypatch):
    from amr_twin.cli.menu import RealTimeTwin
    from amr_twin.model.config import load_config
    from amr_twin.sim.loop import Twin, TwinOptions

    monkeypatch.setattr("amr_twin.sim.bounds.MAX_RUN_S", 0.5)
    twin = Twin(load_config(), TwinOptions(world="empty", visuals=False))
    rt = RealTimeTwin(twin, rate=1000.0).start()
    try:
        rt._thread.join(timeout=30)
        assert not rt._thread.is_alive() and "bound of a run, 0.5 simulated s" in str(rt.error)
    finally:
        rt.close()
    assert 0.4 <= twin.t_s <= 0.5 + 1e-9


def test_the_command_line_starts_without_the_twin():
    """The bounds and path checks are read at start-up: they must not import numpy, MuJoCo or pydantic."""
    code = ("import sys, amr_twin.cli.main; "
            "print(sorted(m for m in ('numpy', 'mujoco', 'pydantic') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip() == "[]"


# ------------------------------------------------------------------------------------------ error paths
def test_malformed_calibration_logs_name_the_file(tmp_path, refused):
    out = tmp_path / "never.yaml"
    two = _write(tmp_path / "two.csv", "t_s,wheel,rpm,command\n0.1,left\n")
    refused(["calibrate", "--target", two, "--out", out], f"--target {two}:2: 2 field(s); every row has the header's 4")
    binary = tmp_path / "bin.csv"
    binary.write_bytes(bytes(range(256)) * 4)
    refused(["calibrate", "--target", binary, "--out", out], f"--target {binary}: not a text file")
    refused(["calibrate", "--target", tmp_path, "--out", out], f"--target {tmp_path}: is a folder")
    refused(["calibrate", "--target", "/dev/zero", "--out", out], "--target /dev/zero: not a regular file")


def _unblock(fifo: Path) -> threading.Timer:
    """Open ``fifo`` for writing in 5 s if someone reads it (a reader would wait forever otherwise)."""
    def poke():
        try:
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:  # no reader: nobody opened it, as it should be
            pass
    timer = threading.Timer(5.0, poke)
    timer.start()
    return timer


def test_unreadable_input_files_name_the_file(tmp_path, refused):
    binary = tmp_path / "bin.yaml"
    binary.write_bytes(b"\xff\xfe" * 100)
    os.mkfifo(tmp_path / "pipe.yaml")
    _unblock(tmp_path / "pipe.yaml")
    for option, path, words in (("--mission", binary, "not a text file"), ("--mission", tmp_path, "is a folder"),
                                ("--mission", tmp_path / "pipe.yaml", "not a regular file"),
                                ("--config", "/dev/zero", "not a regular file"),
                                ("--config", binary, "not a text file"),
                                ("--params", tmp_path / "pipe.yaml", "not a regular file")):
        args = ["run", option, path] if option == "--mission" else ["run", "stop", option, path]
        refused(args, str(path), words)


def _limited(args, limit_bytes: int, cwd: Path, env: dict | None = None):
    """``amr-twin args`` in a process whose files may not grow beyond ``limit_bytes`` (``ulimit -f``)."""
    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, resource.RLIM_INFINITY))

    return subprocess.run([str(AMR_TWIN), *map(str, args)], capture_output=True, text=True, timeout=300, cwd=cwd,
                          preexec_fn=limit, env=env)


def test_a_file_size_limit_is_one_line_and_leaves_nothing(tmp_path, tmp_path_factory):
    """Each writer: the CSV, the .mcap, the .rrd (Rerun's file writer thread); then chapter 5's PNG, with
    matplotlib's font cache not made yet (as on a new machine: it cannot be saved under the limit either)."""
    run = ["run", "linear", "--speed-m-s", "0.5", "--duration-s", "3", "--world", "empty"]
    for option, name in (("--csv", "r.csv"), ("--mcap", "r.mcap"), ("--record", "r.rrd")):
        res = _limited([*run, option, tmp_path / name], 20_000, tmp_path)
        assert res.returncode == 1, res.stderr
        assert res.stderr.strip() == f"error: cannot write {tmp_path / name}: File too large (the file-size " \
                                     "limit, ulimit -f, is 20000 bytes)"
        assert list(tmp_path.iterdir()) == []
    res = _limited(["experiment", "chapter5", "--out", tmp_path / "c5" / "deeper", "--runs", 1, "--duration-s", 2,
                    "--no-progress"], 20_000, tmp_path,
                   env={**os.environ, "MPLCONFIGDIR": str(tmp_path_factory.mktemp("matplotlib_config"))})
    assert res.returncode == 1 and res.stderr.count("\n") == 1 and "File too large" in res.stderr
    assert list(tmp_path.iterdir()) == []  # no empty output folder


# ---------------------------------------------------------------------------------------------- messages
@pytest.mark.parametrize("args, words", [
    (["run", "stop", "--seed", -1], ["--seed -1: must be a whole number in [0, 2^32)"]),
    (["client", "--seed", 2 ** 32], ["--seed 4294967296: must be a whole number in [0, 2^32)"]),
    (["experiment", "fusion", "--out", "{tmp}/f", "--seed", -1], ["--seed -1: must be"]),
    (["experiment", "fusion", "--out", "{tmp}/f", "--seeds", "0:1000000000000"], ["1000000000001 seeds; at most 1000"]),
    (["experiment", "chapter5", "--out", "{tmp}/c", "--samples", 2, "--seed", -1], ["--seed -1: must be"]),
    (["run", "stop", "--set", "wheel=1"], ["--set 'wheel=1': wheel is a section, not a parameter", "wheel.radius_m"]),
    (["run", "stop", "--set", "pos_m=1"], ["--set 'pos_m=1': 'pos_m' is not a parameter; did you mean",
                                            "components.imu.pos_m"]),
    (["run", "stop", "--set", "=5"], ["--set '=5': expected KEY=VALUE with a parameter's dotted key"]),
    (["run", "stop", "--set", "wheel.radius_m=true"], ["--set 'wheel.radius_m=true': wheel.radius_m takes a "
                                                        "number (m), not true or false"]),
    (["run", "stop", "--set", "wheel.radius_m=5"], ["--set 'wheel.radius_m=5': wheel.radius_m: 5 is out of range: "
                                                     "allowed [0.05, 0.3] m"]),
    (["run", "stop", "--set", "payload.xy_m=[1]"], ["--set 'payload.xy_m=[1]': payload.xy_m: [1] has 1 value(s); "
                                                     "it takes 2"]),
    (["run", "stop", "--set", "wheel.radius_m=1e400"], ["--set 'wheel.radius_m=1e400': wheel.radius_m: inf must be "
                                                         "a finite number"]),
    (["run", "stop", "--payload-kg", "1e6"], ["--payload-kg 1e+06: payload.mass_kg: 1000000.0 is out of range"]),
    (["sweep", "payload", "--out", "{tmp}/s", "--masses", "60:0:5"], ["--masses '60:0:5': STOP 0 kg is below START "
                                                                      "60 kg", "0:60:5"]),
    (["sweep", "payload", "--out", "{tmp}/s", "--masses", "0:60:0"], ["STEP 0 kg must be > 0"]),
    (["sweep", "payload", "--out", "{tmp}/s", "--masses", "0:nan:1"], ["must be finite numbers"]),
    (["sweep", "payload", "--out", "{tmp}/s", "--positions", "nan:0"], ["--positions 'nan:0': X and Y must be finite"]),
    (["sweep", "payload", "--out", "{tmp}/s", "--positions", "0.3:0"], ["leaves the deck: |X| <= 0.200 m"]),
    (["sweep", "payload", "--out", "{tmp}/s", "--commands", "linear:1e308"], ["--commands 'linear:1e308': the client "
                                                                              "refuses it"]),
    (["run", "stop", "--live", "bogus"], ["--live 'bogus': must be one of foxglove, rerun"]),
    (["run", "stop", "--live", "--host", "999.1.1.1"], ["--host 999.1.1.1: not an address"]),
    (["sweep"], ["amr-twin sweep: give a command: payload"]),
    (["experiment"], ["amr-twin experiment: give a command: chapter5, fusion, navigation, umbmark, faults"]),
    ([], ["amr-twin: give a command: model, "]),
    (["experiment", "chapter5", "--out", ""], ["'--out'", "an empty path"]),
    (["run", "stop", "--csv", ""], ["'--csv'", "an empty path"]),
    (["run", "stop", "--config", ""], ["'--config'", "an empty path"]),
])
def test_refusals_name_the_option_and_what_is_allowed(args, words, tmp_path, refused):
    refused([str(a).format(tmp=tmp_path) for a in args], *words)


def test_a_params_file_s_bad_value_names_the_file(tmp_path, refused):
    params = _write(tmp_path / "p.yaml", "wheel:\n  radius_m: 5\n")
    refused(["run", "stop", "--params", params], f"--params {params}: wheel.radius_m: 5 is out of range")
    params.write_text("wheel:\n  radius_m: true\n")
    refused(["run", "stop", "--params", params], f"--params {params}: wheel.radius_m takes a number (m)")
