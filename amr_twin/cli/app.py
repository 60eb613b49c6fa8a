"""The ``amr-twin`` typer app: a parser's usage error (an unknown option, a value that is not a
number, an option in the wrong place) is one line in the project's words, exit code 2; ROS 1
remapping arguments (``name:=value``) are kept apart for the ROS 1 node.
"""

from __future__ import annotations

import contextlib
import gc
import sys

import typer

try:  # typer >= 0.20 carries its own copy of click
    from typer._click import exceptions as _click_errors
except ImportError:  # pragma: no cover - older typer on click
    from click import exceptions as _click_errors

from amr_twin.cli.common import start_up
from amr_twin.ros1 import remapping


class App(typer.Typer):
    """The typer app, with the parser's usage errors printed as one line (exit 2)."""

    def __call__(self, *args, **kwargs):
        if "standalone_mode" in kwargs:
            return super().__call__(*args, **kwargs)
        argv = kwargs.get("args", args[0] if args else None)
        # Start-up allocates about a million objects (numpy, mujoco, pydantic, typer), which the
        # default thresholds scan over and over, and the interpreter scans them all once more at
        # exit: a 1 s run spent ~0.1 s of its 0.9 s CPU there. Rarer collections until the command's
        # parameters are loaded (amr_twin.cli.common.started), and the survivors frozen before exit
        # (files are closed, atexit handlers still run).
        start_up()
        argv, ros_args = remapping.split(sys.argv[1:] if argv is None else list(argv))
        bad = next(filter(None, map(remapping.problem, ros_args)), None)
        if bad:
            typer.echo(f"error: {bad}", err=True)
            sys.exit(2)
        remapping.keep(
            ros_args
        )  # roslaunch's __name:=, __log:=, remaps: for the ROS 1 node (amr_twin.ros1.remapping)
        kwargs["args"], args = argv, ()
        try:
            with self._only_group(argv):
                code = super().__call__(*args, standalone_mode=False, **kwargs)
        except _click_errors.UsageError as exc:
            where = exc.ctx.command_path if exc.ctx is not None else "amr-twin"
            hint = _misplaced(exc) or f" (see {where} --help)"
            typer.echo(
                f"error: {where}: "
                f"{_missing_command(exc) or _plain(' '.join(exc.format_message().split()))}{hint}",
                err=True,
            )
            sys.exit(2)
        except _click_errors.ClickException as exc:
            typer.echo(f"error: {' '.join(exc.format_message().split())}", err=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            typer.echo("aborted", err=True)
            sys.exit(130)
        finally:
            gc.freeze()
        sys.exit(code if isinstance(code, int) else 0)

    @contextlib.contextmanager
    def _only_group(self, argv: list[str]):
        """While a command of one group runs (``amr-twin run linear ...``), only that group is
        built: typer turns every registered command into click's when called (~25 ms of
        start-up for all of them, ~7 ms for ``run``). Anything else (top-level help, a
        top-level command, a name that is no group) builds them all."""
        first = argv[0] if argv else ""
        groups = [g for g in self.registered_groups if g.name == first]
        if len(groups) != 1:
            yield
            return
        saved = self.registered_commands, self.registered_groups
        self.registered_commands, self.registered_groups = [], groups
        try:
            yield
        finally:
            self.registered_commands, self.registered_groups = saved


_PARSER_WORDS = {
    "Input should be a valid integer, unable to parse string as an "
    "integer": "expects a whole number",
    "Input should be a valid integer, got a number with a fractional "
    "part": "expects a whole number",
    "Input should be a valid number, unable to parse string as a number": "expects a number",
    "Input should be a valid boolean, unable to interpret input": "expects true or false",
}
"""typer's (pydantic's) words for a value of the wrong type, and the project's."""


def _plain(message: str) -> str:
    """A usage error's message in the project's words (:data:`_PARSER_WORDS`)."""
    for theirs, ours in _PARSER_WORDS.items():
        message = message.replace(theirs, ours)
    return message


def _missing_command(exc) -> str | None:
    """For a group given no command: which it has."""
    commands = getattr(exc.ctx.command, "commands", None) if exc.ctx is not None else None
    if not commands or exc.format_message() != "Missing command.":
        return None
    return f"give a command: {', '.join(commands)}"


def _misplaced(exc) -> str | None:
    """For an option given to a group that belongs to its commands: where it goes."""
    name = getattr(exc, "option_name", None)
    if (
        "given twice" in exc.format_message()
    ):  # amr_twin.cli.path_options._once: the option is in its place
        return None
    group = getattr(exc.ctx, "command", None) if exc.ctx is not None else None
    parent = exc.ctx.parent if exc.ctx is not None else None
    if (
        name
        and parent is not None
        and any(name in p.opts for p in getattr(parent.command, "params", []))
    ):
        return (
            f": {name} is an option of {parent.command_path}; put it before {exc.ctx.info_name!r}"
        )
    commands = getattr(group, "commands", None)
    if not name or not commands:
        return None
    owners = sorted(
        cmd for cmd, c in commands.items() if any(name in p.opts for p in getattr(c, "params", []))
    )
    if not owners:
        return None
    return (
        f": {name} is an option of {' and '.join(owners)}; put it after the command, "
        f"e.g. {exc.ctx.command_path} {owners[0]} {name} ..."
    )
