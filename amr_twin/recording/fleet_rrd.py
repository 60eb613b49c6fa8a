"""Record a world of several robots to one Rerun ``.rrd`` file, headless.

The streams of :mod:`amr_twin.recording.rerun_log`, each robot's under its name: its bodies at
``world/bodies/amr-1/...`` (the model's names), its scans at ``world/amr-1/scan``, its true and
odometry tracks at ``world/amr-1/trajectory/{true,odom}``, its plan and costmap at
``world/amr-1/navigation/...``, its plots at ``amr-1/{wheels,duty,electrics,imu,uwb}/...``, its
collisions at ``amr-1/events/collisions``; the world's geoms once; the fleet manager's events
at ``fleet_manager/events``. Reasons:
docs/reference/recordings.md#amr_twinrecordingfleet_rrd.
"""

from __future__ import annotations

from pathlib import Path

from amr_twin.base.atomic_file import write_bytes
from amr_twin.recording.rerun_log import ENCODE_TIMEOUT_S, log_robot
from amr_twin.recording.rerun_streams import TIMELINE
from amr_twin.recording.rerun_world import _log_geoms


def _blueprint(names: list[str]):
    """The world in 3D beside each robot's currents and battery."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial3DView(origin="world", name="fleet"),
                rrb.TextLogView(
                    name="events",
                    contents=["fleet_manager/**", *(f"{n}/events/**" for n in names)],
                ),
                row_shares=[4, 1],
            ),
            rrb.Vertical(
                *(rrb.TimeSeriesView(origin=f"{n}/electrics", name=f"{n} A, V") for n in names)
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=True,
    )


def write_fleet_rrd(robots, path: Path, events=(), application_id: str = "amr_twin") -> Path:
    """Write every robot of ``robots`` (the
    :func:`~amr_twin.recording.fleet_capture.attach_fleet` captures, in order) and the manager's
    ``events`` (``(t_us, dict)``) to ``path`` (.rrd) in one piece, as
    :func:`~amr_twin.recording.rerun_log.write_rrd` does (module notes)."""
    import rerun as rr

    path = Path(path)
    m = robots[0].view.observables.model
    rec = rr.RecordingStream(application_id)
    stream = rec.binary_stream()
    rec.send_blueprint(
        _blueprint([r.view.name for r in robots]), make_active=False, make_default=True
    )
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    _log_geoms(rec, m)
    anchors = True  # the UWB anchors once, with the first robot that ranged
    for r in robots:
        series = r.recorder.series()
        ranged = log_robot(
            rec, m, r.capture, series, None, r.view.prefix, r.view.name + "/", anchors
        )
        anchors = anchors and not ranged
    for t_us, event in events:
        rec.set_time(TIMELINE, duration=t_us * 1e-6)
        text = " ".join(f"{k}={v}" for k, v in event.items() if k != "t_s")
        rec.log("fleet_manager/events", rr.TextLog(text, level="INFO"))
    rec.disconnect()
    data = stream.read(flush=True, flush_timeout_sec=ENCODE_TIMEOUT_S) or b""
    write_bytes(path, data)
    return path
