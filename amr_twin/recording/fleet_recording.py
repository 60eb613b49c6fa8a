"""The recordings of a world of several robots, written together:
:func:`write_fleet_recordings` (``<stem>.mcap`` and ``<stem>.rrd`` in one folder).

``amr-twin fleet --record DIR`` writes ``DIR/fleet.{mcap,rrd}``; ``amr-twin experiment fleet
--record DIR`` one pair an episode (:func:`episode_stem`). The files:
:mod:`amr_twin.recording.fleet_mcap`, :mod:`amr_twin.recording.fleet_rrd`.
"""

from __future__ import annotations

from pathlib import Path


def write_fleet_recordings(captures, folder: Path, stem: str, cfg, events=()) -> tuple[Path, Path]:
    """Write ``folder/<stem>.mcap`` and ``folder/<stem>.rrd`` of ``captures`` (the
    :func:`~amr_twin.recording.fleet_capture.attach_fleet` captures of a run that has ended;
    ``cfg`` the robots' parameters, for their description) and the fleet manager's ``events``
    (``(t_us, dict)``: :class:`~amr_twin.recording.fleet_capture.SeenEvents`); the folder is
    made. Returns the two paths."""
    from amr_twin.model.urdf import robot_urdf
    from amr_twin.recording.fleet_mcap import write_fleet_mcap
    from amr_twin.recording.fleet_rrd import write_fleet_rrd

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return (
        write_fleet_mcap(captures, folder / f"{stem}.mcap", robot_urdf(cfg), events),
        write_fleet_rrd(captures, folder / f"{stem}.rrd", events),
    )


def episode_stem(robots: int, payload_kg: tuple[float, float], seed: int) -> str:
    """The file name (without suffix) of an episode's recordings: ``fleet_4r_0-30kg_s1``."""
    lo, hi = payload_kg
    return f"fleet_{robots}r_{lo:g}-{hi:g}kg_s{seed}"
