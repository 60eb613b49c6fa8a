"""``amr-twin client``: the terminal menu of wheel_Command_Client (§3.2.2, fig. 3.2).

The twin runs in a background thread, paced to ``rate`` simulated seconds per
wall-clock second, while the main thread reads the menu from the terminal. The
options are the thesis' (the figure's text is not printed, so the wording is
ours): linear motion in m/s, rotation in deg/s about an ICC (REP-103: positive
ICC to the left, positive speed counter-clockwise; the thesis' menu text says
the opposite, its code and chapter 5 agree with REP-103), stop, single motor
(0 left / 1 right, sense 1 forward / -1 backward, m/s) and exit. Every speed the
firmware publishes on ``wheel0_Vel``/``wheel1_Vel`` is printed as it arrives.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import TYPE_CHECKING, Optional

import typer

if TYPE_CHECKING:
    from rich.console import Console

from amr_twin.cli.common import _config, _guard, fail
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt
from amr_twin.cli.live_options import checked_live, live_options
from amr_twin.cli.options import checked_firmware, checked_seed, firmware_option, sketch_option
from amr_twin.cli.ros1_options import checked_ros1, ros1_options
from amr_twin.cli.real_time_twin import RealTimeTwin
from amr_twin.cli.run_options import _run_option_infos

_LIVE = live_options()
_WORLD = _run_option_infos()["world"]  # as the run commands have it
_ROS1 = ros1_options()

MENU = """
[bold]wheel_Command_Client[/bold]
  1) Linear motion            (speed, m/s; negative: backward)
  2) Rotation about an ICC    (speed, deg/s; ICC distance, m, positive to the left)
  3) Stop                     (brake both wheels)
  4) Motor motion             (motor 0 left / 1 right; sense 1 / -1; speed, m/s)
  0) Exit"""


def escape(text: str) -> str:
    """``rich.markup.escape``, imported when the menu runs (rich costs ~35 ms of every command's
    start-up)."""
    from rich.markup import escape as rich_escape

    return rich_escape(text)


MAX_LINE = 1024
"""Longest line the menu reads from a file or a pipe, characters (``input()`` read /dev/zero whole:
9 GB in 48 s)."""


def read_line(console: Console, prompt: str, stdin=None) -> str:
    """One answer: from a terminal with its line editing; from a file or a pipe at most
    :data:`MAX_LINE` characters, else a one-line refusal (exit 2). EOFError at the end of the
    input."""
    import sys

    stdin = sys.stdin if stdin is None else stdin
    if stdin.isatty():
        return console.input(prompt, markup=False)
    console.print(prompt, end="", markup=False)
    line = stdin.readline(MAX_LINE + 1)
    if not line:
        raise EOFError
    if len(line) > MAX_LINE or "\0" in line:
        fail(
            f"standard input: a line of the menu is at most {MAX_LINE} characters of text (a "
            f"choice, a number)"
        )
    return line


def _ask(console: Console, prompt: str) -> Optional[float]:
    text = read_line(console, prompt).strip()
    try:
        value = float(text)
    except ValueError:
        console.print(f"[red]not a number: {escape(repr(text))}[/red]")
        return None
    if not math.isfinite(value):
        console.print(f"[red]{escape(text)}: must be a finite number[/red]")
        return None
    return value


def _choice(console: Console, rt: RealTimeTwin, choice: str) -> bool:
    """Act on one menu choice; False to exit."""
    client = rt.twin.client
    if choice == "0":
        return False
    if choice == "1":
        v = _ask(console, "linear speed [m/s]: ")
        call = None if v is None else (lambda: client.linear(v))
    elif choice == "2":
        w = _ask(console, "angular speed [deg/s]: ")
        icc = None if w is None else _ask(console, "ICC distance [m]: ")
        call = None if icc is None else (lambda: client.angular(w, icc))
    elif choice == "3":
        call = client.stop
    elif choice == "4":
        motor = _ask(console, "motor (0 left, 1 right): ")
        sense = _ask(console, "sense (1 forward, -1 backward): ") if motor in (0.0, 1.0) else None
        v = _ask(console, "speed [m/s]: ") if sense in (1.0, -1.0) else None
        if motor not in (0.0, 1.0) or sense not in (1.0, -1.0):
            console.print("[red]motor must be 0 or 1 and sense 1 or -1[/red]")
        call = None if v is None else (lambda: client.motor(int(motor), int(sense), v))
    else:
        console.print(f"[red]unknown choice {escape(repr(choice))}[/red]")
        return True
    if call is None:
        return True
    code = rt.call(call)
    if code == 0:
        r = client.last_request
        console.print(
            escape(
                f"sent wheel_Command [{r.motionL}, {r.speedL:.5f}, {r.motionR}, {r.speedR:.5f}]"
                " (code 0)"
            )
        )
    else:
        console.print(f"[red]{escape(client.last_error or '')}[/red] (code {code})")
    return True


def client(
    rate: float = typer.Option(1.0, "--rate", help="Simulated seconds per wall second."),
    firmware: str = firmware_option(),
    sketch: Optional[Path] = sketch_option(),
    payload_kg: Optional[float] = typer.Option(None, "--payload-kg", help="Payload mass, kg."),
    seed: int = typer.Option(
        0, "--seed", help="Seed of the random draws (rosserial loss and hall chatter of --fault)."
    ),
    fault: Optional[list[str]] = typer.Option(
        None,
        "--fault",
        metavar="KIND@T[:ARGS]",
        help="Inject a fault T s after the start (repeatable; faults.md in docs/reference/).",
    ),
    world: str = _WORLD[1],
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
    live: Optional[str] = _LIVE["live"][1],
    host: str = _LIVE["host"][1],
    port: Optional[int] = _LIVE["port"][1],
    web_port: Optional[int] = _LIVE["web_port"][1],
    ros1: bool = _ROS1["ros1"][1],
    roscore: bool = _ROS1["roscore"][1],
) -> None:
    """Terminal menu of wheel_Command_Client (fig. 3.2) driving the twin in real time (--live:
    served to Foxglove or Rerun as well, and driven by a Foxglove client's /cmd_vel; --ros1: on a
    ROS 1 graph)."""
    from amr_twin.sim.faults import FaultError, parse_faults
    from amr_twin.assembly.twin import Twin, TwinOptions

    if not (math.isfinite(rate) and 0 < rate <= 1000):
        fail(f"--rate {rate}: must be a finite number in (0, 1000]")
    checked_seed(seed, fail)
    firmware = checked_firmware(firmware, sketch, fail)
    live_opts = checked_live(live, host, port, web_port, None, fail, default_rate=rate)
    ros1_opts = checked_ros1(ros1, roscore, None, firmware, True, rate, fail)[0]
    try:
        faults = parse_faults(fault or [], sensors=False)
    except FaultError as exc:
        fail(str(exc))
    extra = {}
    if payload_kg is not None:
        if not math.isfinite(payload_kg):
            fail(f"--payload-kg {payload_kg}: must be a finite number")
        extra["payload.mass_kg"] = payload_kg
    cfg = _config(config, params, set_, extra)
    from rich.console import Console

    console = Console(highlight=False)
    logging.getLogger("amr_twin.controllers.wheel_command").addHandler(logging.NullHandler())
    twin = _guard(
        lambda: Twin(
            cfg,
            TwinOptions(
                firmware=firmware, seed=seed, faults=faults, world=world, start_xy_yaw=None
            ),
        )
    )

    def show(topic: str, msg, t_us: int) -> None:
        if topic in ("wheel0_Vel", "wheel1_Vel"):
            side = "left " if topic == "wheel0_Vel" else "right"
            console.print(
                f"[dim]t={t_us * 1e-6:8.3f} s[/dim]  {topic} ({side}) {msg.data:8.3f} RPM"
            )

    twin.on_message(show)
    twin.on_collision(
        lambda c: console.print(
            escape(
                f"[collision] t={c.t_s:.2f} s: {', '.join(c.robot_parts)} hit {c.hit} at "
                f"({c.x_m:.2f}, {c.y_m:.2f}) m"
            )
        )
    )
    rt = _guard(
        lambda: RealTimeTwin(
            twin, rate, live_opts, say=lambda line: console.print(escape(line)), ros1=ros1_opts
        )
    )
    rt.start()
    x, y, yaw = twin.start_xy_yaw
    hint = "; --world empty: no walls" if world != "empty" else ""
    console.print(
        escape(
            f"twin running at {rate:g}x real time, firmware {firmware}, world {world} "
            f"(start x {x:g} m, y {y:g} m, facing {math.degrees(yaw):g} deg{hint})"
        )
    )
    for f in faults:
        console.print(escape(f"fault {f.name} at {f.t_s:g} s: {f.describe()['description']}"))
    try:
        while rt.error is None:
            console.print(MENU)
            if not _choice(console, rt, read_line(console, "choice: ").strip()):
                break
    except (EOFError, KeyboardInterrupt):
        pass
    finally:
        rt.close()
    if rt.error is not None:
        fail(f"the twin stopped: {str(rt.error).splitlines()[0]}", code=3)
    console.print(f"exit at t={twin.t_s:.3f} s simulated")
