"""``amr-twin fleet``: N robots of one world as VDA 5050 2.0 vehicles on an MQTT broker
(docs/how-to/fleet.md).

Every option is checked before the model is built; bad input is one line, exit 2. Without
``--vda5050`` an embedded broker (amqtt) serves on a free port of 127.0.0.1, printed at start. The
run ends after ``--duration-s`` simulated seconds, or at Ctrl-C (then the vehicle says OFFLINE and
disconnects); ``--json`` prints what it did as one JSON object. ``--manager`` runs the project's
fleet manager (:mod:`amr_twin.fleet_manager`) on the same broker with ``--jobs`` seeded jobs; then
without ``--duration-s`` the run ends when they are done. ``--record DIR`` writes ``DIR/fleet.mcap``
and ``DIR/fleet.rrd`` of every robot at the end (:mod:`amr_twin.recording.fleet_mcap`,
:mod:`amr_twin.recording.fleet_rrd`); ``--live`` serves every robot on Foxglove
(:mod:`amr_twin.live.fleet_foxglove`).
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Optional

import typer

from amr_twin.cli.common import _config, _guard, _start_pose, fail
from amr_twin.cli.live_options import checked_live
from amr_twin.cli.options import ConfigOpt, ParamsOpt, SetOpt
from amr_twin.model.robot_starts import MAX_ROBOTS


def _starts(text: Optional[str], robots: int) -> list:
    """``X_M,Y_M,YAW_DEG[;...]`` as one (x_m, y_m, yaw_rad) a robot; None: the world's own start
    (one robot only)."""
    if not 1 <= robots <= MAX_ROBOTS:
        fail(f"--robots {robots}: must be in 1..{MAX_ROBOTS}")
    if text is None:
        if robots > 1:
            fail(f"--starts: needed with --robots {robots} (X_M,Y_M,YAW_DEG a robot, ';' between)")
        return [None]
    out = [
        _start_pose(part, "--starts", " for each robot (';' between robots)")
        for part in text.split(";")
    ]
    if len(out) != robots:
        fail(f"--starts {text!r}: {len(out)} poses for --robots {robots}: give one a robot")
    return out


def _check_overlap(poses: list, cfg) -> None:
    """Exit 2 (one line) when two robots' footprints at their starts overlap."""
    from amr_twin.model.robot_starts import overlapping_starts

    if len(poses) < 2:
        return
    pair = overlapping_starts(poses, cfg.chassis.length_m / 2, cfg.half_width_m)
    if pair is not None:
        i, j = pair
        fail(
            f"--starts: robots amr-{i + 1} and amr-{j + 1} overlap at their starts "
            f"({cfg.chassis.length_m:g} x {2 * cfg.half_width_m:g} m each)"
        )


RECORDINGS = ("fleet.mcap", "fleet.rrd")
"""The files ``--record DIR`` writes in DIR."""


def _outputs(record: Optional[Path], live, host, port, rate) -> object:
    """Check ``--record`` (a folder, its two files writable) and the live options (Foxglove only,
    ``--rate`` the fleet's own); returns the live options or None. Exit 2 (one line) on a bad
    one."""
    from amr_twin.recording.outputs import OutputError, check_folder, check_outputs

    if record is not None:
        try:
            check_folder("--record", record)
            check_outputs(files={f"--record ({n})": record / n for n in RECORDINGS})
        except OutputError as exc:
            fail(str(exc))
    options = checked_live(live, host, port, None, rate, fail, paced=True)
    if options is not None and options.mode != "foxglove":
        fail(f"--live {options.mode}: a fleet is served live on Foxglove only (--live foxglove)")
    return options


PLACE_LIMIT_S = 30.0
"""Simulated seconds the manager's jobs wait for every vehicle to be placed on the roadmap."""


def _start_manager(session, cfg, world, interface, jobs, seed, charge_below, limit_s):
    """The project's fleet manager for the session's vehicles; its seeded jobs queued once every
    vehicle is placed on the roadmap (or after ``limit_s`` simulated s): a job routed before then
    could lead through a node where a robot not yet placed stands."""
    from amr_twin.fleet_manager.dispatcher import ManagerOptions
    from amr_twin.fleet_manager.jobs import job_stream
    from amr_twin.fleet_manager.manager import start_manager

    x, y, _yaw = session.vehicles[0].true_pose()
    master = start_manager(
        cfg,
        world,
        session.url,
        list(session.serials),
        interface,
        0,
        seed,
        ManagerOptions(charge_below=charge_below),
        start_xy=(x, y),
    )
    t_end = session.world.t_s + limit_s
    while session.world.t_s < t_end:
        placed = {e["vehicle"] for e in master.summary()["events"] if e["event"] == "placed"}
        if placed >= set(session.serials):
            break
        session.run(0.1)
        time.sleep(0.005)  # the broker's and the manager's threads
    dispatcher = master.dispatcher
    exclude = set(dispatcher.options.charging_nodes)
    master.submit(
        job_stream(dispatcher.roadmap, 4 if jobs is None else jobs, seed, exclude=exclude)
    )
    typer.echo(f"fleet manager on {session.url}: {master.jobs_left()} jobs", err=True)
    return master


def fleet(
    robots: int = typer.Option(1, "--robots", help="How many robots, 1 to 20 (amr-1 ... amr-N)."),
    world: str = typer.Option(
        "aisles", "--world", help="The world (its name is the VDA 5050 mapId)."
    ),
    starts: Optional[str] = typer.Option(
        None,
        "--starts",
        help="X_M,Y_M,YAW_DEG of each robot, ';' between robots (default: the world's start).",
    ),
    vda5050: Optional[str] = typer.Option(
        None,
        "--vda5050",
        help="The broker, mqtt://HOST:PORT (default: an "
        "embedded broker on a free port of 127.0.0.1).",
    ),
    interface: str = typer.Option("uagv", "--interface", help="The topics' interfaceName."),
    duration_s: Optional[float] = typer.Option(
        None, "--duration-s", help="Simulated seconds to run (default: until Ctrl-C)."
    ),
    rate: float = typer.Option(
        1.0, "--rate", help="Simulated seconds per wall second (0: as fast as possible)."
    ),
    as_json: bool = typer.Option(
        False, "--json", help="Print what the run did as one JSON object."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the sensors' noise and of the jobs."),
    manager: bool = typer.Option(
        False,
        "--manager",
        help="Run the project's fleet manager on the same broker too (docs/how-to/fleet.md).",
    ),
    jobs: Optional[int] = typer.Option(
        None, "--jobs", help="With --manager: seeded transport jobs queued at the start (4)."
    ),
    charge_below: float = typer.Option(
        20.0, "--charge-below", help="With --manager: send to charge below this batteryCharge, %."
    ),
    shared_poses: bool = typer.Option(
        True,
        "--shared-poses/--no-shared-poses",
        help="Robots share their pose estimates: each keeps the others as obstacles, not as "
        "people to give way to (docs/how-to/fleet.md).",
    ),
    record: Optional[Path] = typer.Option(
        None,
        "--record",
        help="Write fleet.mcap and fleet.rrd of every robot into this folder "
        "(docs/reference/recordings.md).",
    ),
    live: Optional[str] = typer.Option(
        None,
        "--live",
        metavar="[foxglove]",
        help="Serve every robot live on a Foxglove WebSocket server (read-only).",
    ),
    host: str = typer.Option("127.0.0.1", "--host", help="With --live: the address to listen on."),
    port: Optional[int] = typer.Option(
        None, "--port", help="With --live: the server's port (8765; 0: a free one)."
    ),
    config: Optional[Path] = ConfigOpt,
    params: Optional[Path] = ParamsOpt,
    set_: Optional[list[str]] = SetOpt,
) -> None:
    """Serve N robots of one world as VDA 5050 2.0 vehicles amr-1 ... amr-N (manufacturer
    amr-twin) on an MQTT broker."""
    from amr_twin.fleet.protocol import check_name
    from amr_twin.fleet.transport import broker_address

    poses = _starts(starts, robots)
    for check in (
        lambda: check_name("--interface", interface),
        lambda: vda5050 is not None and broker_address(vda5050),
    ):
        try:
            check()
        except ValueError as exc:
            fail(str(exc))
    if not (math.isfinite(rate) and 0 <= rate <= 1000):
        fail(f"--rate {rate:g}: must be a finite number in [0, 1000] (0: as fast as possible)")
    if duration_s is not None and not (math.isfinite(duration_s) and 0 < duration_s <= 86400):
        fail(f"--duration-s {duration_s:g}: must be in (0, 86400] s")
    if jobs is not None and not manager:
        fail(f"--jobs {jobs}: only with --manager")
    if jobs is not None and not 0 <= jobs <= 10000:
        fail(f"--jobs {jobs}: must be in [0, 10000]")
    if not (math.isfinite(charge_below) and 0 <= charge_below < 80):
        fail(f"--charge-below {charge_below:g}: must be in [0, 80) % (charged up to 80 %)")
    live_options = _outputs(record, live, host, port, rate)
    cfg = _config(config, params, set_)
    _check_overlap(poses, cfg)

    def work() -> dict:
        from amr_twin.fleet.session import FleetOptions, FleetSession
        from amr_twin.fleet.protocol import topic

        session = FleetSession(
            cfg,
            FleetOptions(
                world=world,
                starts=tuple(poses),
                url=vda5050,
                interface=interface,
                rate=rate,
                seed=seed,
                shared_poses=shared_poses,
                visuals=record is not None or live_options is not None,
            ),
        )
        captures = None
        if record is not None:
            from amr_twin.recording.fleet_capture import attach_fleet

            captures = attach_fleet(session.world, names=session.serials)
        if live_options is not None:
            from amr_twin.live.fleet_foxglove import FleetFoxgloveSink
            from amr_twin.live.session import FOXGLOVE_PORT
            from amr_twin.model.urdf import robot_urdf

            sink = FleetFoxgloveSink(
                session.world,
                session.pacer,
                robot_urdf(cfg),
                live_options.host,
                FOXGLOVE_PORT if live_options.port is None else live_options.port,
                names=session.serials,
            )
            session.pacer.sinks.append(sink)
            typer.echo(f"live: Foxglove WebSocket server on {sink.url}", err=True)
        for serial in session.serials:
            typer.echo(
                f"vehicle {serial} on {session.url}: "
                f"{topic(interface, serial, '{order,instantActions,state,...}')}",
                err=True,
            )
        master = seen = None
        try:
            if manager:
                limit_s = PLACE_LIMIT_S if duration_s is None else min(PLACE_LIMIT_S, duration_s)
                master = _start_manager(
                    session, cfg, world, interface, jobs, seed, charge_below, limit_s
                )
                if captures is not None:
                    from amr_twin.recording.fleet_capture import SeenEvents

                    seen = SeenEvents(master.dispatcher.events)
                    seen.flush(session.world.clock.now_us)  # placed before the jobs
                    session.pacer.sinks.append(seen)
            left = math.inf if duration_s is None else duration_s - session.world.t_s
            while left > 1e-9 and not (master and duration_s is None and not master.jobs_left()):
                step = min(1.0, left)
                session.run(step)
                left -= step
        except KeyboardInterrupt:
            typer.echo("stopped", err=True)
        finally:
            out = session.summary()
            if master is not None:
                out["manager"] = master.summary()
                master.close()
            session.close()
            if captures is not None:
                from amr_twin.recording.fleet_recording import write_fleet_recordings

                events = seen.stamped if seen is not None else ()
                paths = write_fleet_recordings(captures, record, "fleet", cfg, events)
                typer.echo(f"recorded {len(captures)} robots: {paths[0]}, {paths[1]}", err=True)
        return out

    out = _guard(work)
    if as_json:
        typer.echo(json.dumps(out))
