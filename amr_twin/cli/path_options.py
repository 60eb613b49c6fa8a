"""Which options name what a command reads and what it writes; no output may be one of its inputs.

Every command of the app is checked before its callback runs, by the class of the app's root group
(:class:`CheckedGroup`): a command added later is checked without calling anything. The options are
known by their flag: :data:`INPUTS` (each with what its value reads: ``--world warehouse`` reads
``models/worlds/warehouse.xml``, no ``--config`` reads ``models/amr/amr.yaml``) and :data:`OUTPUTS`.
An option whose type is a path and that is in neither is taken to be written (compared with every
input); ``tests/cli/test_path_options.py`` fails until it is declared here.

Refused, in one line naming both options, exit 2, before anything is read or written
(:func:`amr_twin.recording.outputs.check_not_inputs`):

- an output that is an input: the same path once links are resolved, or the same file by another
  name (a hard link: same device and inode);
- an output folder that holds an input (the files written there could replace it);
- an empty path given to any of these options (``--out ""`` would be the current folder);
- an output another command is writing (its lock, :mod:`amr_twin.recording.output_lock`, held for as
  long as the command runs): the holder's pid is named.

A command interrupted (Ctrl-C) says so in one line, exit 130: its files are written together at the
end."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Callable, Iterator

from typer.core import TyperGroup

try:  # typer >= 0.20 carries its own copy of click
    from typer._click import exceptions as _click_errors
    from typer._click.core import ParameterSource
    from typer._click.globals import get_current_context
except ImportError:  # pragma: no cover - older typer on click
    from click import exceptions as _click_errors
    from click import get_current_context
    from click.core import ParameterSource


def _given(value) -> list[Path]:
    return [] if value is None else [Path(value)]


def _config_file(value) -> list[Path]:
    from amr_twin.model.parameter_tree import DEFAULT_CONFIG

    return [DEFAULT_CONFIG if value is None else Path(value)]


def _target_file(value) -> list[Path]:
    return [] if value in (None, "thesis") else [Path(value)]


def _world_files(value) -> list[Path]:
    """The world's file and, for a map_server map, its image (when the YAML names one)."""
    from amr_twin.model.worlds import world_files

    return [] if value is None else world_files(value)


def _mission_files(value) -> list[Path]:
    """The mission file and, for a navigation mission naming a ``map:``, that map's YAML and
    image."""
    if value is None:
        return []
    from amr_twin.model.yaml_file import read_yaml

    path = Path(value)
    try:
        name = read_yaml(path, "mission", ValueError).get("map")
    except (ValueError, AttributeError):  # unreadable: loading the mission says why
        return [path]
    if not isinstance(name, str) or not name.strip():
        return [path]
    return [path] + _world_files(str(path.parent / name))  # a relative map lies beside the mission


def _route_file(value) -> list[Path]:
    from amr_twin.experiments.fusion.experiment import route_file

    return [route_file(value)]


INPUTS: dict[str, Callable[[object], list[Path]]] = {
    "--config": _config_file,  # none given: the robot's parameter file
    "--params": _given,
    "--mission": _mission_files,  # with a navigation mission's map (YAML + image)
    "--calibration": _given,
    "--sketch": _given,  # a folder
    "--target": _target_file,  # 'thesis' or a CSV log
    "--world": _world_files,  # a name of models/worlds/, an MJCF file or a map YAML (+ its image)
    "--route": _route_file,  # a name of experiments/routes/ or a route YAML
    "--map": _world_files,  # a map_server YAML (+ its image): the navigation commands'
    "--slam-map": _world_files,
    "--odometry": _given,  # the wheel odometry's calibration (run; experiment umbmark writes them)
}
"""Options whose value names what the command reads: flag -> the files (or folders) it reads."""

OUTPUTS = (
    "--out",
    "--csv",
    "--record",
    "--mcap",
    "--report",
    "--export-urdf",
    "--export-mjcf",
    "--serial-pty",
)  # the last: a link made to the emulated board's pseudo-terminal
"""Options whose value names a file or folder the command writes."""

PATH_METAVARS = ("PATH", "FILE", "DIR")


def is_path_option(param) -> bool:
    """A command-line option whose value is a path: typer's ``Path`` annotation, or a metavar saying
    so."""
    descriptor = getattr(param, "type_descriptor", None)
    return getattr(param, "param_type_name", "") == "option" and bool(
        getattr(descriptor, "is_path", False)
        or type(getattr(param, "type", None)).__name__ == "Path"
        or (param.metavar or "").upper() in PATH_METAVARS
    )


def role(param) -> str | None:
    """``input``, ``output`` or None (not a path) of an option; an undeclared path option is an
    output."""
    flag = param.opts[0] if getattr(param, "param_type_name", "") == "option" else None
    if flag in INPUTS:
        return "input"
    if flag in OUTPUTS or is_path_option(param):
        return "output"
    return None


def _contexts(ctx) -> Iterator:
    while ctx is not None:
        yield ctx
        ctx = ctx.parent


def paths_of(ctx) -> tuple[list[tuple[str, Path]], list[tuple[str, Path]]]:
    """``(outputs, inputs)`` of a command's context and its groups' (``run --csv F linear``):
    ``(label, path)``.

    A value given on the command line wins over a default of the same option at another level; an
    input the command reads by default is labelled ``FLAG (default)``.
    """
    values: dict[str, tuple[str, list]] = {}  # flag -> (role, [(value, is_default), ...])
    for c in _contexts(ctx):
        for param in c.command.params:
            kind = role(param)
            if kind is None or param.name not in c.params:
                continue
            source = c.get_parameter_source(param.name)
            default = source in (ParameterSource.DEFAULT, ParameterSource.DEFAULT_MAP, None)
            value = c.params[param.name]
            items = value if isinstance(value, (list, tuple)) else [value]
            values.setdefault(param.opts[0], (kind, []))[1].extend((v, default) for v in items)
    outputs, inputs = [], []
    for flag, (kind, items) in values.items():
        given = [v for v, default in items if not default]
        chosen = (
            list(dict.fromkeys(given)) if given else list(dict.fromkeys(v for v, _ in items))[:1]
        )
        label = flag if given else f"{flag} (default)"
        for value in chosen:
            if kind == "input":
                inputs += [(label, p) for p in INPUTS[flag](value)]
            elif value is not None:
                outputs.append((label, Path(value)))
    return outputs, inputs


def check_paths(ctx) -> list[tuple[str, Path]]:
    """Refuse (one line, exit 2) an output of ``ctx``'s command that is, or holds, one of its
    inputs; return the outputs."""
    from amr_twin.cli.common import fail
    from amr_twin.recording.outputs import OutputError, check_not_inputs

    outputs, inputs = paths_of(ctx)
    try:
        check_not_inputs(outputs, inputs)
    except OutputError as exc:
        fail(str(exc))
    return outputs


def _refuse_empty(param) -> None:
    """An empty value of a path option is refused while parsing (typer would read it as the current
    folder)."""
    process = param.process_value

    def process_value(ctx, value):
        if isinstance(value, str) and not value.strip():
            raise _click_errors.BadParameter(
                "an empty path: give a file or folder name", ctx=ctx, param=param
            )
        return process(ctx, value)

    param.process_value = process_value


def _checked(callback):
    """``callback`` preceded by :func:`check_paths` and run holding its outputs' locks
    (:mod:`amr_twin.recording.output_lock`); a group whose command follows leaves both to the
    command."""

    @functools.wraps(callback)
    def checked(*args, **kwargs):
        from amr_twin.cli.common import fail
        from amr_twin.recording.output_lock import OutputBusy, holding

        ctx = get_current_context()
        if getattr(ctx.command, "commands", None) and ctx.invoked_subcommand:
            return callback(*args, **kwargs)
        outputs = check_paths(ctx)
        try:
            with holding(outputs):
                return callback(*args, **kwargs)
        except OutputBusy as exc:
            fail(str(exc))
        except KeyboardInterrupt:  # typer would exit 130 without a word
            kept = (
                " (the points finished are kept in runs/: a rerun resumes from them)"
                if "sweep" in ctx.command_path
                else ""
            )
            fail(f"{ctx.command_path}: interrupted; no output written{kept}", code=130)

    checked.paths_checked = True
    return checked


def _commands(command) -> Iterator:
    yield command
    for sub in (getattr(command, "commands", None) or {}).values():
        yield from _commands(sub)


def _once(command) -> None:
    """An option of one value given twice with different values (``--live foxglove --live rerun``)
    is a usage error (exit 2) instead of the last one silently winning; a repeatable option is not
    touched."""
    make_parser = command.make_parser

    def checked_parser(ctx):
        parser = make_parser(ctx)
        for option in {
            id(o): o for o in (*parser._long_opt.values(), *parser._short_opt.values())
        }.values():
            if option.action not in ("store", "store_const"):
                continue
            process = option.process

            def once(value, state, option=option, process=process):
                new = option.const if option.action == "store_const" else value
                if option.dest in state.opts and state.opts[option.dest] != new:
                    flags = "/".join(option.obj.opts + option.obj.secondary_opts)
                    old = state.opts[option.dest]
                    raise _click_errors.BadOptionUsage(
                        flags,
                        f"{flags} given twice with different values ({old} and "
                        f"{new}): give it once",
                        ctx=ctx,
                    )
                process(value, state)

            option.process = once
        return parser

    command.make_parser = checked_parser


class CheckedGroup(TyperGroup):
    """The app's root group: each command below it checks its paths (:func:`check_paths`) before its
    callback runs, and refuses an empty path and an option given twice (:func:`_once`) while
    parsing. A group given no command fails with a usage error (``Missing command.``, one line
    naming its commands: :mod:`amr_twin.cli.main`) instead of printing its help and an empty
    error."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for command in _commands(self):
            _once(command)
            if getattr(command, "commands", None):
                command.no_args_is_help = False
            for param in command.params:
                if role(param) is not None:
                    _refuse_empty(param)
            if command.callback is not None and not getattr(
                command.callback, "paths_checked", False
            ):
                command.callback = _checked(command.callback)
