"""The options every kind of ``amr-twin run`` shares, defined once.

``amr-twin run`` is a group (``run linear ...``, ``run --mission FILE``) whose
options can be written before or after the command kind: ``amr-twin run
--payload-kg 150 linear --speed-m-s 0.7`` and ``amr-twin run linear --speed-m-s
0.7 --payload-kg 150`` are the same run. :func:`shared` adds the options of
:data:`RUN_OPTIONS` to the group's callback and to each kind's command from one
definition; the command receives a :class:`RunOptions` merged from both places
(a repeatable option collects both; one given twice with different values is
refused in one line).
"""

from __future__ import annotations

import copy
import functools
import inspect
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Callable, Optional

import typer

from amr_twin.cli.live_options import live_options
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt, firmware_option, sketch_option
from amr_twin.cli.ros1_options import ros1_options


@dataclass
class RunOptions:
    """The options of ``amr-twin run`` that every command kind shares (see :data:`RUN_OPTIONS`)."""

    duration_s: Optional[float] = None
    payload_kg: Optional[float] = None
    firmware: str = "faithful"
    sketch: Optional[Path] = None
    seed: int = 0
    world: str = "warehouse"
    start: Optional[str] = None
    sensors: bool = False
    fault: list[str] = field(default_factory=list)
    actor: list[str] = field(default_factory=list)
    actors_random: Optional[str] = None
    stop_on_collision: bool = False
    csv: Optional[Path] = None
    as_json: bool = False
    record: Optional[Path] = None
    mcap: Optional[Path] = None
    config: Optional[Path] = None
    params: Optional[Path] = None
    set_: list[str] = field(default_factory=list)
    odometry: Optional[Path] = None
    live: Optional[str] = None
    host: str = "127.0.0.1"
    port: Optional[int] = None
    web_port: Optional[int] = None
    rate: Optional[float] = None
    ros1: bool = False
    roscore: bool = False
    serial_pty: Optional[str] = None


def _run_option_infos(
    overrides: dict | None = None,
) -> dict[str, tuple[object, typer.models.OptionInfo]]:
    """name -> (annotation, a fresh OptionInfo) for each field of :class:`RunOptions`;
    ``overrides``: name -> ``{"default": ..., "help": ...}`` for a command that runs with other
    defaults (``run goto``)."""
    infos = {
        "duration_s": (
            Optional[float],
            typer.Option(
                None,
                "--duration-s",
                help="Simulated seconds (default 10; a "
                "mission's own), at most 3600; inf with --ros1 or --live: until Ctrl-C or "
                "SIGTERM (the outputs "
                "are written then).",
            ),
        ),
        "payload_kg": (
            Optional[float],
            typer.Option(None, "--payload-kg", help="Payload mass, kg."),
        ),
        "firmware": (str, firmware_option()),
        "sketch": (Optional[Path], sketch_option()),
        "seed": (
            int,
            typer.Option(
                0,
                "--seed",
                help="Seed of the random draws: rosserial frame loss and hall "
                "chatter of --fault, IMU and LiDAR noise of --sensors. Same seed, same run.",
            ),
        ),
        "world": (
            str,
            typer.Option(
                "warehouse",
                "--world",
                help="World: warehouse, empty (models/worlds/), an "
                "MJCF file, or a ROS map (map_server YAML + PGM, walls extruded).",
            ),
        ),
        "start": (
            Optional[str],
            typer.Option(
                None,
                "--start",
                help="Start pose X_M,Y_M,YAW_DEG (default: the "
                "world's; the warehouse's is the west end of its central aisle, facing +x).",
            ),
        ),
        "sensors": (
            bool,
            typer.Option(
                False,
                "--sensors",
                help="Run the IMU (imu/data_raw, imu/mag, 100 Hz) and "
                "the LiDAR (scan, 5.5 Hz); recorded with --record/--mcap.",
            ),
        ),
        "fault": (
            Optional[list[str]],
            typer.Option(
                None,
                "--fault",
                metavar="KIND@T[:ARGS]",
                help="Inject a fault at T s (repeatable), e.g. hall-left-dead@3, "
                "rosserial-loss@2:0.3,for=5; "
                "kinds and arguments in faults.md in docs/reference/.",
            ),
        ),
        "actor": (
            Optional[list[str]],
            typer.Option(
                None,
                "--actor",
                metavar="KIND:X1,Y1;X2,Y2[@V][+T][/loop][/stop=M]",
                help="A person or pallet_jack walking these waypoints (m, world frame) at V m/s "
                "from T s "
                "(repeatable; /loop: round again; /stop=M: halts while the robot is within M m "
                "ahead); "
                "docs/explanation/actors.md.",
            ),
        ),
        "actors_random": (
            Optional[str],
            typer.Option(
                None,
                "--actors-random",
                metavar="N[/stop=M]",
                help="N people and pallet jacks on random loops of the world's free space, drawn "
                "from --seed (at most 50).",
            ),
        ),
        "stop_on_collision": (
            bool,
            typer.Option(
                False,
                "--stop-on-collision",
                help="End the run at the first collision (exit code 4).",
            ),
        ),
        "csv": (
            Optional[Path],
            typer.Option(None, "--csv", help="Write the time series here (CSV)."),
        ),
        "as_json": (bool, typer.Option(False, "--json", help="Print one JSON object.")),
        "record": (
            Optional[Path],
            typer.Option(
                None,
                "--record",
                help="Write a Rerun recording here (.rrd; open with `rerun FILE`).",
            ),
        ),
        "mcap": (
            Optional[Path],
            typer.Option(
                None, "--mcap", help="Write the ROS 2 topics here (.mcap; Foxglove, ros2 bag)."
            ),
        ),
        "config": (Optional[Path], ConfigOpt),
        "params": (Optional[Path], ParamsOpt),
        "set_": (Optional[list[str]], SetOpt),
        "odometry": (
            Optional[Path],
            typer.Option(
                None,
                "--odometry",
                metavar="FILE",
                help="The wheel odometry "
                "node's calibration (YAML: per-wheel radii and wheelbase, as amr-twin experiment "
                "umbmark "
                "writes it) instead of the nominal geometry.",
            ),
        ),
        **live_options(),
        **ros1_options(),
    }
    for name, changes in (overrides or {}).items():
        annotation, info = (
            infos[name][0],
            copy.copy(infos[name][1]),
        )  # ConfigOpt and the like are shared
        infos[name] = (annotation, info)
        info.default = changes.get("default", info.default)
        info.help = changes.get("help", info.help)
    return infos


RUN_OPTIONS = tuple(f.name for f in fields(RunOptions))


def _given(ctx: typer.Context | None, name: str) -> bool:
    """Was option ``name`` written on the command line (or the environment) of ``ctx``'s command?"""
    if ctx is None:
        return False
    source = ctx.get_parameter_source(name)
    return source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP")


def merge(ctx: typer.Context, values: dict, fail: Callable[[str], None]) -> RunOptions:
    """:class:`RunOptions` from a command's own values and those given to its group before it."""
    parent = (
        ctx.parent
        if ctx.parent is not None and ctx.parent.params.keys() >= set(RUN_OPTIONS)
        else None
    )
    infos = _run_option_infos()
    out = {}
    for name in RUN_OPTIONS:
        mine, theirs = values[name], parent.params[name] if parent is not None else None
        if name in ("fault", "set_", "actor"):
            out[name] = list(theirs or []) + list(mine or [])
            continue
        here, before = _given(ctx, name), _given(parent, name)
        if here and before and mine != theirs:
            flag = infos[name][1].param_decls[0]
            fail(
                f"{flag} given before and after {ctx.info_name!r} with different values "
                f"({theirs} and {mine}); "
                "give it once"
            )
        out[name] = mine if here or not before else theirs
    return RunOptions(**out)


def shared(fail: Callable[[str], None], overrides: dict | None = None):
    """Decorator: add the :data:`RUN_OPTIONS` to a command; it receives ``opts: RunOptions`` first.
    ``overrides``: the command's own defaults and help texts (:func:`_run_option_infos`)."""

    def decorate(func):
        signature = inspect.signature(func, eval_str=True)
        own = [p for name, p in signature.parameters.items() if name != "opts"]
        extra = [
            inspect.Parameter(
                name, inspect.Parameter.KEYWORD_ONLY, default=info, annotation=annotation
            )
            for name, (annotation, info) in _run_option_infos(overrides).items()
        ]

        has_ctx = "ctx" in signature.parameters
        if not has_ctx:
            extra.append(
                inspect.Parameter("ctx", inspect.Parameter.KEYWORD_ONLY, annotation=typer.Context)
            )

        @functools.wraps(func)
        def command(**kwargs):
            values = {name: kwargs.pop(name) for name in RUN_OPTIONS}
            ctx = kwargs["ctx"] if has_ctx else kwargs.pop("ctx")
            return func(merge(ctx, values, fail), **kwargs)

        params = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in own] + extra
        command.__signature__ = signature.replace(parameters=params)
        command.__annotations__ = {p.name: p.annotation for p in params}
        del command.__wrapped__
        return command

    return decorate
