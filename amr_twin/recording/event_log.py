"""Collisions and injected faults in the recordings: a small stream of their own.

``.rrd`` (:func:`log_events`, called by :func:`amr_twin.recording.rerun_log.write_rrd`)::

    events/collisions     TextLog (WARN) at each collision's first contact
    events/faults         TextLog (WARN) at each fault's start and end
    world/collisions      Points3D, red, the first contact points so far

``.mcap`` (:func:`mcap_items`, added by :func:`amr_twin.recording.mcap_log.write_mcap`)::

    /twin/collisions  diagnostic_msgs/msg/DiagnosticArray  one status (ERROR) per collision, at its
                      first contact: name "twin/collision", message "<parts> hit <geom>", values
                      t_s, until_s, x_m, y_m, z_m, hit, robot_parts, peak_force_n, robot pose
    /twin/faults      diagnostic_msgs/msg/DiagnosticArray  one status (WARN) when a fault starts,
                      one (OK) when it clears: name "twin/fault/<kind>", values of its
                      specification

DiagnosticArray is what ``rqt_robot_monitor`` and Foxglove's diagnostics panels read.
"""

from __future__ import annotations

from amr_twin.ros.ros2_cdr import Cdr

OK, WARN, ERROR = 0, 1, 2  # diagnostic_msgs/DiagnosticStatus levels
DIAGNOSTIC_ARRAY = "diagnostic_msgs/DiagnosticArray"


def collisions_of(twin) -> list:
    """The twin's collisions so far (:class:`~amr_twin.sim.collisions.Collision`, in order)."""
    return list(twin.observables.collisions)


def faults_of(twin) -> list:
    """The twin's injected faults (:class:`~amr_twin.sim.fault_injector.FaultInjector`'s), or []."""
    injector = twin.faults
    return list(injector.faults) if injector is not None else []


def has_events(twin) -> bool:
    """Whether the run had a collision or a fault to show."""
    return bool(collisions_of(twin) or faults_of(twin))


def _diagnostic(t_ns: int, level: int, name: str, message: str, values: dict) -> bytes:
    c = Cdr()
    c.header(t_ns // 1_000_000_000, t_ns % 1_000_000_000, "world")
    c.u32(1)
    c.u8(level)
    c.string(name)
    c.string(message)
    c.string("amr")
    c.u32(len(values))
    for key, value in values.items():
        c.string(str(key))
        c.string(str(value))
    return bytes(c.b)


def statuses(twin) -> list[tuple[int, str, int, str, str, dict]]:
    """``(t_ns, topic, level, name, message, values)`` of the twin's collisions and faults, one
    DiagnosticStatus each (see the module notes); the ROS 1 bridge publishes the same on
    /diagnostics."""
    out = []
    for c in collisions_of(twin):
        values = {k: v for k, v in c.as_dict().items() if k != "robot_pose"}
        values["robot_parts"] = ",".join(c.robot_parts)
        values.update({f"robot_{k}": v for k, v in c.as_dict()["robot_pose"].items()})
        out.append(
            (
                int(round(c.t_s * 1e9)),
                "/twin/collisions",
                ERROR,
                "twin/collision",
                f"{', '.join(c.robot_parts)} hit {c.hit}",
                values,
            )
        )
    for f in faults_of(twin):
        d = f.describe()
        values = {k: v for k, v in d.items() if k != "description" and v is not None}
        for t_s, level, what in ((f.t_s, WARN, "injected"), (f.until_s, OK, "cleared")):
            if t_s is not None:
                out.append(
                    (
                        int(round(t_s * 1e9)),
                        "/twin/faults",
                        level,
                        f"twin/fault/{f.name}",
                        f"{f.text} {what}: {d['description']}",
                        values,
                    )
                )
    return out


def mcap_items(twin, order: int) -> list[tuple[int, int, str, str, bytes]]:
    """``(t_ns, order, topic, type, CDR payload)`` of the twin's collisions and faults (see the
    module notes)."""
    return [
        (t_ns, order + i, topic, DIAGNOSTIC_ARRAY, _diagnostic(t_ns, level, name, message, values))
        for i, (t_ns, topic, level, name, message, values) in enumerate(statuses(twin))
    ]


def log_events(rec, collisions: list, faults: list, root: str = "") -> None:
    """``collisions`` (:func:`collisions_of`) and ``faults`` (:func:`faults_of`) into a Rerun
    recording stream (see the module notes; a robot of a fleet's under ``<root>events`` and
    ``world/<root>collisions``, ``root`` ``amr-2/``)."""
    import numpy as np
    import rerun as rr

    from amr_twin.recording.rerun_streams import TIMELINE

    points = []
    for c in collisions:
        rec.set_time(TIMELINE, duration=float(c.t_s))
        rec.log(
            f"{root}events/collisions",
            rr.TextLog(
                f"collision: {', '.join(c.robot_parts)} hit {c.hit} at ({c.x_m:.2f}, "
                f"{c.y_m:.2f}) m, "
                f"until {c.until_s:.2f} s, peak force {c.peak_force_n:.0f} N",
                level="WARN",
            ),
        )
        points.append((c.x_m, c.y_m, c.z_m))
        rec.log(
            f"world/{root}collisions",
            rr.Points3D(np.array(points), colors=[(230, 30, 30)], radii=[0.05]),
        )
    for f in faults:
        for t_s, what in ((f.t_s, "injected"), (f.until_s, "cleared")):
            if t_s is not None:
                rec.set_time(TIMELINE, duration=float(t_s))
                rec.log(f"{root}events/faults", rr.TextLog(f"fault {f.text} {what}", level="WARN"))
