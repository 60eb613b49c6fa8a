"""No output is an input: every command's every output option, walked from the app itself.

A command or option added later is in these lists without editing them: an output option that is
not checked, or a path option declared neither as an input nor as an output, fails here.
"""

import os
import shutil
from pathlib import Path

import pytest
import typer.main
from typer.testing import CliRunner

from amr_twin.cli.main import app
from amr_twin.cli.path_options import INPUTS, OUTPUTS, is_path_option, role

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()


def _commands(command=None, path=()):
    """(command path, click command) of every command and group with a callback."""
    command = command or typer.main.get_command(app)
    if command.callback is not None:
        yield path, command
    for name, sub in (getattr(command, "commands", None) or {}).items():
        yield from _commands(sub, (*path, name))


def _options(command):
    return [p for p in command.params if getattr(p, "param_type_name", "") == "option"]


COMMANDS = list(_commands())
OUTPUT_CASES = [
    (path, p.opts[0]) for path, c in COMMANDS for p in _options(c) if role(p) == "output"
]
INPUT_CASES = [
    (path, p.opts[0])
    for path, c in COMMANDS
    for p in _options(c)
    if role(p) == "input" and any(role(q) == "output" for q in _options(c))
]


def _required(command, skip: str, tmp_path: Path) -> list[str]:
    """Values for the command's required options other than ``skip`` (a fresh folder name)."""
    out = []
    for p in _options(command):
        if p.required and p.opts[0] != skip:
            out += [p.opts[0], str(tmp_path / f"required{p.opts[0]}")]
    return out


def _command(path):
    return dict(COMMANDS)[path]


def _listing(folder: Path) -> dict:
    return {
        p.relative_to(folder): (p.stat().st_mtime_ns, p.stat().st_size) if p.is_file() else None
        for p in sorted(folder.rglob("*"))
    }


def _refused(args, tmp_path, *names):
    before = _listing(tmp_path)
    res = runner.invoke(app, args)
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, (args, res.output)
    assert len(lines) == 1 and all(n in lines[0] for n in names), (args, res.stderr)
    assert _listing(tmp_path) == before  # nothing written, nothing touched
    return lines[0]


def test_the_walk_sees_every_command_and_its_outputs():
    paths = {" ".join(p) for p, _ in COMMANDS}
    assert {
        "model",
        "calibrate",
        "run",
        "run linear",
        "run stop",
        "experiment chapter5",
        "experiment fusion",
        "experiment faults",
        "sweep payload",
        "client",
        "bench",
    } <= paths
    assert {
        ("calibrate", "--out"),
        ("calibrate", "--report"),
        ("model", "--export-urdf"),
        ("run", "--csv"),
        ("run linear", "--mcap"),
        ("experiment chapter5", "--record"),
        ("sweep payload", "--out"),
    } <= set((" ".join(p), f) for p, f in OUTPUT_CASES)


def test_every_path_option_is_declared_an_input_or_an_output():
    undeclared = sorted(
        {
            (" ".join(path), p.opts[0])
            for path, c in COMMANDS
            for p in _options(c)
            if is_path_option(p) and p.opts[0] not in INPUTS and p.opts[0] not in OUTPUTS
        }
    )
    assert not undeclared, (
        f"declare these in amr_twin/cli/path_options.py (INPUTS or OUTPUTS): {undeclared}"
    )
    used = {p.opts[0] for _, c in COMMANDS for p in _options(c)}
    awaited = {
        "--map",
        "--slam-map",
    }  # the navigation commands' (branch nav), declared before they merge
    assert set(INPUTS) | set(OUTPUTS) <= used | awaited, "a declared option no command has"


@pytest.mark.parametrize(
    "path, flag", OUTPUT_CASES, ids=[f"{' '.join(p)} {f}" for p, f in OUTPUT_CASES]
)
def test_an_output_that_is_the_parameter_file_is_refused(path, flag, tmp_path):
    cfg = tmp_path / "c.yaml"
    shutil.copy(ROOT / "models" / "amr" / "amr.yaml", cfg)
    os.link(cfg, tmp_path / "hard.yaml")
    (tmp_path / "soft.yaml").symlink_to(cfg.name)
    extra = _required(_command(path), flag, tmp_path)
    for given in (
        cfg,
        tmp_path / "hard.yaml",
        tmp_path / "soft.yaml",
        tmp_path / "sub" / ".." / "c.yaml",
    ):
        _refused(
            [*path, flag, str(given), "--config", str(cfg), *extra],
            tmp_path,
            flag,
            "--config",
            "is the input",
        )
    _refused(
        [*path, flag, str(tmp_path), "--config", str(cfg), *extra],
        tmp_path,
        flag,
        "holds the input",
    )
    if path == ("calibrate",) and flag == "--out":  # the parameter file read by default
        default = ROOT / "models" / "amr" / "amr.yaml"
        _refused([*path, flag, str(default)], tmp_path, "--config (default)")


def _input_file(flag: str, tmp_path: Path) -> Path:
    """A file (a folder for --sketch) the input option ``flag`` accepts."""
    sources = {
        "--world": ROOT / "models" / "worlds" / "empty.xml",
        "--route": ROOT / "experiments" / "routes" / "warehouse_60m.yaml",
        "--sketch": ROOT / "controllers" / "arduino" / "motor_control",
    }
    source = sources.get(flag, ROOT / "models" / "amr" / "amr.yaml")
    target = tmp_path / f"input{source.suffix}"
    (shutil.copytree if source.is_dir() else shutil.copy)(source, target)
    return target


@pytest.mark.parametrize(
    "path, flag", INPUT_CASES, ids=[f"{' '.join(p)} {f}" for p, f in INPUT_CASES]
)
def test_every_input_is_protected_from_every_output(path, flag, tmp_path):
    given = _input_file(flag, tmp_path)
    command = _command(path)
    for out in [p.opts[0] for p in _options(command) if role(p) == "output"]:
        extra = _required(command, out, tmp_path)
        _refused([*path, flag, str(given), out, str(given), *extra], tmp_path, flag, out)


def test_an_option_given_to_the_group_is_compared_with_the_command_s(tmp_path):
    cfg = tmp_path / "c.yaml"
    shutil.copy(ROOT / "models" / "amr" / "amr.yaml", cfg)
    _refused(
        ["run", "--config", str(cfg), "stop", "--csv", str(cfg)], tmp_path, "--csv", "--config"
    )
    _refused(
        ["run", "--csv", str(cfg), "linear", "--config", str(cfg)], tmp_path, "--csv", "--config"
    )
    mission = tmp_path / "m.yaml"
    mission.write_text("duration_s: 1\nsteps:\n  - {t_s: 0, stop: {}}\n")
    _refused(
        ["run", "--mission", str(mission), "--mcap", str(mission)], tmp_path, "--mcap", "--mission"
    )
    # a map world's image is read too
    (tmp_path / "room.pgm").write_bytes(b"P5 2 2 255\n" + bytes(4))
    (tmp_path / "room.yaml").write_text("image: room.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    _refused(
        [
            "run",
            "stop",
            "--world",
            str(tmp_path / "room.yaml"),
            "--csv",
            str(tmp_path / "room.pgm"),
        ],
        tmp_path,
        "--csv",
        "--world",
    )
    # so is a navigation mission's map (beside the mission), YAML and image (both were overwritten,
    # exit 0)
    goals = tmp_path / "goals.yaml"
    goals.write_text("goals:\n  - [1.0, 0.5]\nmap: room.yaml\n")
    for victim in ("room.yaml", "room.pgm"):
        _refused(
            ["run", "--mission", str(goals), "--world", "empty", "--csv", str(tmp_path / victim)],
            tmp_path,
            "--csv",
            "--mission",
            victim,
        )


def test_a_given_input_is_not_confused_with_the_default(tmp_path):
    """``--config`` given before the kind: the default parameter file is not an input of the run."""
    cfg = tmp_path / "c.yaml"
    shutil.copy(ROOT / "models" / "amr" / "amr.yaml", cfg)
    from amr_twin.cli.path_options import paths_of

    with typer.main.get_command(app).make_context(
        "amr-twin", ["run", "--config", str(cfg), "stop"]
    ) as ctx:
        group = ctx.command.commands["run"]
        with group.make_context("run", ["--config", str(cfg), "stop"], parent=ctx) as run_ctx:
            with group.commands["stop"].make_context(
                "stop", ["--csv", "x.csv"], parent=run_ctx
            ) as leaf:
                outputs, inputs = paths_of(leaf)
    assert outputs == [("--csv", Path("x.csv"))]
    assert ("--config", cfg) in inputs and not any(
        label.endswith("(default)") and "config" in label for label, _ in inputs
    )
