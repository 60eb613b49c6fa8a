"""Options shared by several commands, defined once.

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
from typer.core import TyperCommand, TyperGroup

from amr_twin.controllers.firmware import FIRMWARES

ConfigOpt = typer.Option(None, "--config", help="Parameter file (default models/amr/amr.yaml).")
ParamsOpt = typer.Option(
    None, "--params", help="Second YAML overriding values of the parameter file."
)
SetOpt = typer.Option(None, "--set", help="Override one value: key=value (repeatable).")


def firmware_option(default: str = "faithful") -> typer.models.OptionInfo:
    """``--firmware``: its choices are the firmware factory's
    (:data:`~amr_twin.controllers.firmware.FIRMWARES`)."""
    return typer.Option(
        default,
        "--firmware",
        help=f"Arduino firmware: {FIRMWARES.choices()}; default {default} "
        "(docs/firmware.md; avr: the sketch compiled with avr-gcc on an emulated ATmega2560).",
    )


def sketch_option() -> typer.models.OptionInfo:
    """``--sketch DIR``: the sketch of ``--firmware avr``."""
    return typer.Option(
        None,
        "--sketch",
        metavar="DIR",
        help="With --firmware avr: your Arduino sketch folder "
        "(DIR/DIR.ino) instead of controllers/arduino/motor_control.",
    )


def checked_firmware(firmware: str, sketch: Optional[Path], fail: Callable[[str], None]) -> str:
    """``--firmware`` and ``--sketch`` as the firmware string (``avr:DIR`` with a sketch); for avr
    the toolchain is checked and the sketch built now. A refusal is one line (``fail``)."""
    from amr_twin.controllers.firmware import check_avr, firmware_kind

    try:
        kind = firmware_kind(firmware, None if sketch is None else str(sketch))
        check_avr(kind)
    except ValueError as exc:
        fail(str(exc))
    return kind


SEED_LIMIT = 2**32
"""Seeds are whole numbers in [0, 2^32) (numpy's SeedSequence takes any non-negative one; a bound
keeps keys short)."""


def checked_seed(
    seed: Optional[int], fail: Callable[[str], None], option: str = "--seed"
) -> Optional[int]:
    """``--seed``: a whole number in [0, 2^32), or a one-line refusal (``fail``)."""
    if seed is not None and not 0 <= seed < SEED_LIMIT:
        fail(f"{option} {seed}: must be a whole number in [0, 2^32)")
    return seed


def live_option_args(args: list[str], commands=()) -> list[str]:
    """``--live`` with its value optional: ``--live`` followed by nothing, an option or one of the
    group's ``commands`` means ``--live foxglove``; any other word is its value (checked: ``--live
    bogus`` is refused naming the modes).

    (typer's parser has no options with an optional value: a bare ``--live`` is written out.)
    """
    out = list(args)
    for i, arg in enumerate(out):
        if arg == "--":
            break
        if arg == "--live" and (
            i + 1 == len(out) or out[i + 1].startswith("-") or out[i + 1] in commands
        ):
            out[i] = "--live=foxglove"
    return out


class LiveGroup(TyperGroup):
    """A command group whose ``--live`` takes an optional value (:func:`live_option_args`)."""

    def parse_args(self, ctx, args):
        return super().parse_args(ctx, live_option_args(args, self.commands))


class LiveCommand(TyperCommand):
    """A command whose ``--live`` takes an optional value (:func:`live_option_args`)."""

    def parse_args(self, ctx, args):
        return super().parse_args(ctx, live_option_args(args))


def live_options() -> dict[str, tuple[object, typer.models.OptionInfo]]:
    """``--live [foxglove|rerun]``, ``--host``, ``--port``, ``--web-port``, ``--rate``
    (amr_twin.live.session)."""
    return {
        "live": (
            Optional[str],
            typer.Option(
                None,
                "--live",
                metavar="[foxglove|rerun]",
                help="Serve the twin live "
                "while it runs, paced to --rate: foxglove (the default; Foxglove WebSocket "
                "server, the .mcap's "
                "channels, drive it with /cmd_vel) or rerun (the .rrd's streams over gRPC + a "
                "local web viewer).",
            ),
        ),
        "host": (
            str,
            typer.Option(
                "127.0.0.1",
                "--host",
                help="With --live foxglove: the address to listen on (0.0.0.0: every interface).",
            ),
        ),
        "port": (
            Optional[int],
            typer.Option(
                None,
                "--port",
                help="With --live: the server's port (foxglove 8765, "
                "rerun's gRPC 9876; 0: a free one).",
            ),
        ),
        "web_port": (
            Optional[int],
            typer.Option(
                None,
                "--web-port",
                help="With --live rerun: the web viewer's port (default 9090; 0: a free one).",
            ),
        ),
        "rate": (
            Optional[float],
            typer.Option(
                None,
                "--rate",
                help="With --live, --ros1 or --serial-pty: "
                "simulated seconds per wall second (default 1; --ros1 alone: 0, as fast as "
                "possible).",
            ),
        ),
    }


def checked_live(
    live: Optional[str],
    host: str,
    port: Optional[int],
    web_port: Optional[int],
    rate: Optional[float],
    fail: Callable[[str], None],
    default_rate: float = 1.0,
    paced: bool = False,
):
    """The :class:`~amr_twin.live.session.LiveOptions` of the live options, None without ``--live``;
    an option of ``--live`` given without it, or a bad value, is refused in one line (``fail``);
    ``paced``: ``--rate`` serves another option of the command (``--ros1``, ``--serial-pty``)."""
    import math

    from amr_twin.live.session import LiveOptions

    if live is None:
        for flag, value, unset in (
            ("--port", port, None),
            ("--web-port", web_port, None),
            ("--rate", None if paced else rate, None),
            ("--host", host, "127.0.0.1"),
        ):
            if value != unset:
                fail(f"{flag} is an option of --live: give --live (or drop {flag})")
        return None
    if rate is not None and not math.isfinite(rate):
        fail(f"--rate {rate}: must be a finite number in [0, 1000] (0: as fast as possible)")
    options = LiveOptions(
        mode=live,
        host=host,
        port=port,
        web_port=web_port,
        rate=default_rate if rate is None else rate,
    )
    try:
        options.check()
    except ValueError as exc:
        fail(str(exc))
    return options


def ros1_options() -> dict[str, tuple[object, typer.models.OptionInfo]]:
    """``--ros1``, ``--roscore``, ``--serial-pty PATH`` (amr_twin.ros1.session,
    controllers/avr_serial_port.py)."""
    return {
        "ros1": (
            bool,
            typer.Option(
                False,
                "--ros1",
                help="Join the ROS 1 graph at ROS_MASTER_URI (Debian's ROS 1) "
                "and bridge the twin both ways: /clock (use_sim_time), /tf, /odom, /scan, "
                "/imu/*, /joint_states, "
                "... out; /wheel_Command and /cmd_vel in (docs/how-to/ros1.md). As fast as "
                "possible unless --rate.",
            ),
        ),
        "roscore": (
            bool,
            typer.Option(
                False,
                "--roscore",
                help="With --ros1: start a private roscore on a free "
                "port (its URI is printed) instead of joining ROS_MASTER_URI.",
            ),
        ),
        "serial_pty": (
            Optional[str],
            typer.Option(
                None,
                "--serial-pty",
                metavar="PATH",
                help="With --firmware avr: "
                "serve the emulated Mega's serial port on a pseudo-terminal linked at PATH (as "
                "/dev/ttyACM0 "
                "on the robot) for a rosserial host, paced to real time; the board is driven "
                "from ROS, not "
                "by the run's command (give `run stop`).",
            ),
        ),
    }


def checked_ros1(
    ros1: bool,
    roscore: bool,
    serial_pty: Optional[str],
    firmware: str,
    live_given: bool,
    rate: Optional[float],
    fail: Callable[[str], None],
):
    """``(Ros1Options or None, AvrParams or None, rate)`` of the ROS 1 options, checked before the
    work: ROS 1 installed, the master answering, the pseudo-terminal's path free. ``rate`` is the
    pacing of a run that is not served live: ``--rate``, else as fast as possible (0), or real time
    (1) with ``--serial-pty``."""
    import math

    if roscore and not ros1:
        fail("--roscore is an option of --ros1: give --ros1 (or drop --roscore)")
    from amr_twin.ros1.remapping import kept

    if kept() and not ros1:
        fail(
            f"ROS argument {kept()[0]!r} is for the twin's ROS 1 node: give --ros1 (or drop the "
            f"NAME:=VALUE arguments)"
        )
    params = None
    if serial_pty is not None:
        if not firmware.startswith("avr"):
            fail(
                f"--serial-pty serves the emulated board's serial port: give --firmware avr (got "
                f"{firmware})"
            )
        from amr_twin.controllers.avr_serial_port import pty_problem
        from amr_twin.controllers.firmware import AvrParams

        problem = pty_problem(serial_pty)  # a link left dangling by a killed twin is replaced
        if problem:
            fail(f"--serial-pty {serial_pty}: {problem}")
        params = AvrParams(serial_pty=serial_pty)
        if rate is not None and not (math.isfinite(rate) and 0 < rate <= 1000):
            fail(
                f"--rate {rate}: with --serial-pty the board's serial port runs paced: give a "
                f"rate in (0, 1000]"
            )
    if not live_given and rate is not None and not (math.isfinite(rate) and 0 <= rate <= 1000):
        fail(f"--rate {rate}: must be a finite number in [0, 1000] (0: as fast as possible)")
    options = None
    if ros1:
        from amr_twin.ros1.session import Ros1Options

        options = Ros1Options(roscore=roscore, firmware_topics=serial_pty is None)
        try:
            options.check()
        except ValueError as exc:
            fail(str(exc))
    default = 1.0 if serial_pty is not None else 0.0
    return options, params, default if rate is None else rate


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
                "kinds and arguments in docs/faults.md.",
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
