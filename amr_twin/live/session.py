"""Watch and drive a running twin: the live session behind ``--live``.

``amr-twin run ... --live [foxglove|rerun] [--port P] [--rate R]`` and ``amr-twin client --live``:

- ``foxglove`` (the default): a Foxglove WebSocket server (:mod:`amr_twin.live.foxglove`),
  the channels of the ``.mcap`` plus ``/twin/scene``; a client drives the twin with
  ``/cmd_vel`` (Foxglove's Teleop panel) or wheel_Command requests;
- ``rerun``: the ``.rrd``'s streams and blueprint live over gRPC, with Rerun's web viewer
  served locally (:mod:`amr_twin.live.rerun_stream`).

In both the twin runs paced to ``rate`` x real time (:mod:`amr_twin.live.pacer`; 0: as fast as
possible), with the cmd_vel diff-drive node of ``controllers/diff_drive.py`` (0.5 s watchdog)
subscribed, as a ROS 2 graph of the robot would have it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

LOG = logging.getLogger(__name__)

MODES = ("foxglove", "rerun")
FOXGLOVE_PORT = 8765
RERUN_PORT = 9876
RERUN_WEB_PORT = 9090
CMD_TIMEOUT_S = 0.5
"""The diff-drive node's watchdog: wheels stopped this long after the last cmd_vel, s."""


@dataclass(frozen=True)
class LiveOptions:
    """How to serve a live twin: ``mode`` foxglove or rerun; ports (None: the mode's default; 0: a
    free port); ``rate`` simulated s per wall s (0: as fast as possible)."""

    mode: str = "foxglove"
    host: str = "127.0.0.1"
    port: int | None = None
    web_port: int | None = None
    rate: float = 1.0

    def check(self) -> None:
        """Raise ValueError (one line naming the option) on a bad value."""
        if self.mode not in MODES:
            raise ValueError(
                f"--live {self.mode!r}: must be one of {', '.join(MODES)} (a bare --live is "
                f"foxglove)"
            )
        for flag, port in (("--port", self.port), ("--web-port", self.web_port)):
            if port is not None and not 0 <= port <= 65535:
                raise ValueError(f"{flag} {port}: must be in [0, 65535] (0: a free port)")
        if not (0 <= self.rate <= 1000):
            raise ValueError(
                f"--rate {self.rate}: must be a finite number in [0, 1000] (0: as fast as possible)"
            )
        if self.web_port is not None and self.mode != "rerun":
            raise ValueError("--web-port is the Rerun web viewer's: give it with --live rerun")
        if self.mode == "rerun" and self.host != "127.0.0.1":
            raise ValueError(
                "--host is the Foxglove server's: Rerun's servers listen on every interface"
            )
        if self.mode == "foxglove":
            ports = (("--port", self.host, FOXGLOVE_PORT if self.port is None else self.port),)
        else:  # Rerun's servers listen on every interface
            ports = (
                ("--port", "0.0.0.0", RERUN_PORT if self.port is None else self.port),
                (
                    "--web-port",
                    "0.0.0.0",
                    RERUN_WEB_PORT if self.web_port is None else self.web_port,
                ),
            )
        problem = host_problem(self.host) if self.mode == "foxglove" else None
        if problem:
            raise ValueError(
                f"--host {self.host}: {problem}; give an address of this machine (127.0.0.1: this "
                "machine only, 0.0.0.0: every interface)"
            )
        for flag, host, port in ports:
            problem = port_problem(host, port) if port else None
            if problem:
                raise ValueError(
                    f"{flag} {port}: cannot listen on {host}:{port} ({problem}); "
                    "give another port, or 0 for a free one"
                )


def host_problem(host: str) -> str | None:
    """Why a server could not listen on ``host`` (None: it can): no such address, or not one of this
    machine."""
    import socket

    try:
        infos = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)
    except OSError as exc:
        return f"not an address ({exc.strerror or exc})"
    family, _type, _proto, _name, address = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as sock:
        try:
            sock.bind((address[0], 0, *address[2:]))
        except OSError as exc:
            return f"not an address of this machine ({exc.strerror or exc})"
    return None


def port_problem(host: str, port: int) -> str | None:
    """Why a server could not listen on ``host:port`` now (None: it can), e.g. a port in use."""
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except OSError as exc:
        return f"host {host!r}: {exc.strerror or exc}"
    family, _type, _proto, _name, address = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(address)
        except OSError as exc:
            return exc.strerror or str(exc)
    return None


class LiveSession:
    """Serve ``twin`` live and pace it; :meth:`close` when the run is over.

    Parameters
    ----------
    twin : Twin
        Built, not yet run.
    options : LiveOptions
    say : callable
        Where to print the addresses (one line each), e.g. stderr.
    """

    def __init__(self, twin, options: LiveOptions, say=print):
        from amr_twin.controllers.diff_drive import DiffDriveNode
        from amr_twin.live.pacer import Pacer

        options.check()
        if not twin.options.visuals:
            raise ValueError(
                "a live view draws the robot: build the twin with TwinOptions(visuals=True)"
            )
        self.twin, self.options = twin, options
        self.diff_drive = DiffDriveNode(
            twin.bus, twin.clock, twin.client, cmd_timeout_s=CMD_TIMEOUT_S
        )
        self.pacer = Pacer(twin, options.rate)
        rate = "as fast as possible" if options.rate == 0 else f"at {options.rate:g}x real time"
        if options.mode == "foxglove":
            from amr_twin.live.foxglove import FoxgloveSink

            port = FOXGLOVE_PORT if options.port is None else options.port
            self.sink = FoxgloveSink(twin, self.pacer, options.host, port)
            say(
                f"live: Foxglove WebSocket server on {self.sink.url} (the twin runs {rate}; "
                "publish geometry_msgs/msg/Twist on /cmd_vel to drive it)"
            )
        else:
            from amr_twin.live.rerun_stream import RerunSink

            self.sink = RerunSink(
                twin,
                RERUN_PORT if options.port is None else options.port,
                RERUN_WEB_PORT if options.web_port is None else options.web_port,
            )
            say(
                f"live: Rerun gRPC stream {self.sink.uri}, web viewer {self.sink.web_url} (the "
                f"twin runs {rate})"
            )
        self.pacer.sinks.append(self.sink)

    def call(self, func, timeout_s: float = 10.0):
        """Run ``func()`` in the twin's thread at the next tick (a menu choice); returns its
        result."""
        return self.pacer.call(func, timeout_s)

    def close(self) -> None:
        """Send what is left and stop serving."""
        self.pacer.close()
