"""``--live [foxglove|rerun]`` and its options (``--host``, ``--port``, ``--web-port``, ``--rate``):
their typer options, the optional value of ``--live`` and their check (amr_twin.live.session).
"""

from __future__ import annotations

from typing import Callable, Optional

import typer
from typer.core import TyperCommand, TyperGroup


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
