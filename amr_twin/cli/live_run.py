"""A run served live (Foxglove or Rerun) and/or on a ROS 1 graph, ended by SIGINT or SIGTERM with
its outputs written.
"""

from __future__ import annotations


import typer

from amr_twin.cli.common import fail


def run_live(twin, live, run, ros1=None, rate: float = 1.0, navigation=None):
    """``run()`` with ``twin`` served live (amr_twin.live.session) and/or on a ROS 1 graph
    (amr_twin.ros1.session), with ``navigation`` (amr_twin.ros1.navigation_setup) as move_base
    there. SIGINT (Ctrl-C) or SIGTERM (roslaunch sends both) ends the run at the twin's next event
    and the outputs are written; a second one ends it at once, without them (exit 130)."""
    import signal

    say = lambda line: typer.echo(line, err=True)  # noqa: E731
    signals: list[int] = []

    def on_signal(signum, _frame):
        if signals:
            raise KeyboardInterrupt
        signals.append(signum)
        twin.stop()

    before = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    session = ros = None
    if live is not None:
        from amr_twin.live.session import LiveSession

        session = LiveSession(twin, live, say=say)
        pacer = session.pacer
    else:
        from amr_twin.controllers.diff_drive import DiffDriveNode
        from amr_twin.live.pacer import Pacer
        from amr_twin.live.session import CMD_TIMEOUT_S

        from amr_twin.ros1.session import pacer_tick_us

        pacer = Pacer(twin, rate, pacer_tick_us(rate))
        DiffDriveNode(twin.bus, twin.clock, twin.client, cmd_timeout_s=CMD_TIMEOUT_S)
    try:
        if ros1 is not None:
            from amr_twin.ros1.session import Ros1Session

            ros = Ros1Session(twin, pacer, ros1, say=say)
            if navigation is not None:
                navigation.serve(twin, pacer, say=say)
        result = run()
        if signals:
            say(
                f"stopped by {signal.Signals(signals[0]).name} at t={twin.t_s:.2f} s simulated; "
                f"writing the outputs"
            )
        return result
    except KeyboardInterrupt:
        fail(f"interrupted at t={twin.t_s:.2f} s simulated; no output written", code=130)
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)
        (session or pacer).close()
        if ros is not None:
            ros.close()
        for name, sink in (
            ("live", session.sink if session else None),
            ("ros1", ros.bridge if ros else None),
        ):
            dropped = getattr(sink, "dropped", 0)
            if dropped:
                typer.echo(
                    f"{name}: {dropped} message(s) from clients dropped (see the warnings above)",
                    err=True,
                )
