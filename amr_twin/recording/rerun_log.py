"""Record a run to a Rerun ``.rrd`` file, headless.

Reasons and measurements: docs/reference/recordings.md#amr_twinrecordingrerun_log."""

from __future__ import annotations

from pathlib import Path

from amr_twin.base.atomic_file import write_bytes
from amr_twin.recording.rerun_navigation import _log_navigation
from amr_twin.recording.event_log import collisions_of, faults_of, has_events, log_events
from amr_twin.recording.recorder import recorder_of
from amr_twin.recording.rerun_capture import Capture, capture_of
from amr_twin.recording.rerun_streams import (
    WHEELS,
    _log_commands,
    _log_duty,
    _log_electrics,
    _log_imu,
    _log_wheel_speeds,
)
from amr_twin.recording.rerun_world import (
    _log_body_transforms,
    _log_geoms,
    _log_scan,
    _log_trajectory,
)
from amr_twin.recording.rerun_uwb import _log_uwb

TRACKED = "world/bodies/amr/base_link"
"""The 3D view's camera follows the robot's base."""


def _blueprint(has_imu: bool, has_uwb: bool = False, has_events: bool = False):
    import rerun.blueprint as rrb

    plots = [rrb.TimeSeriesView(origin=f"wheels/{w}", name=f"{w} wheel RPM") for w in WHEELS]
    plots.append(rrb.TimeSeriesView(origin="duty", name="PWM counts"))
    plots.append(rrb.TimeSeriesView(origin="electrics", name="currents A, battery V"))
    if has_imu:
        plots.append(rrb.TimeSeriesView(origin="imu", name="IMU"))
    if has_uwb:
        plots.append(rrb.TimeSeriesView(origin="uwb", name="UWB ranges, m"))
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial3DView(
                    origin="world",
                    name="twin",
                    eye_controls=rrb.EyeControls3D(tracking_entity=TRACKED),
                ),
                rrb.TextLogView(origin="commands", name="commands"),
                *(
                    [rrb.TextLogView(origin="events", name="collisions and faults")]
                    if has_events
                    else []
                ),
                row_shares=[4, 1, 1] if has_events else [4, 1],
            ),
            rrb.Vertical(*plots),
            column_shares=[3, 2],
        ),
        collapse_panels=True,
    )


ENCODE_TIMEOUT_S = 600.0
"""Longest wait for Rerun to encode what was logged, s (no file is involved: it does not fail on a
full disk)."""


def log_robot(
    rec,
    m,
    capture: Capture,
    series,
    result=None,
    prefix: str = "amr/",
    root: str = "",
    anchors: bool = True,
) -> bool:
    """One robot's streams into ``rec``: its bodies, scan, IMU, UWB, wheels, duty, electrics,
    commands, trajectory, navigation (plan, map, costmap, footprint) and events; ``prefix``: its
    names in the model (``amr-2/``), ``root``: its entities' (``amr-2/``); ``anchors``: log the
    UWB anchors if it ranged. Returns whether it ranged."""
    twin = capture.twin
    _log_body_transforms(rec, m, capture)
    _log_scan(rec, m, capture, laser=prefix + "laser", root=root)
    _log_imu(rec, capture, root)
    ranged = _log_uwb(rec, m, capture, prefix + "base_link", root, anchors)
    _log_wheel_speeds(rec, series, root)
    _log_duty(rec, series, root)
    _log_electrics(rec, series, root)
    _log_commands(rec, series, result, root)
    _log_trajectory(rec, series, root=root)
    _log_navigation(rec, capture, root)
    log_events(rec, collisions_of(twin), faults_of(twin), root)
    return ranged


def write_rrd(
    capture: Capture, series, path: Path, result=None, application_id: str = "amr_twin"
) -> Path:
    """Write the capture and ``series`` to ``path`` (.rrd), through a temporary file.

    Rerun encodes the recording into a byte stream (:meth:`RecordingStream.binary_stream`) that this
    process writes in one piece once everything is logged: a full disk or a file-size limit is an
    ``OSError`` naming ``path`` (:func:`~amr_twin.base.atomic_file.replacing`) and no half file is
    left. Rerun's own file writer (``RecordingStream.save``) writes from a thread of its own and, on
    such an error, hangs in ``save`` or ``flush``, raises "File-writer thread shut down
    prematurely", or says nothing and leaves a truncated file (rerun-sdk 0.41). The stream is read
    once: reading it in pieces gives a file whose checksums fail. The encoded bytes (about 0.09 MB
    per simulated second with the sensors) are held in memory until then, beside the capture.
    """
    import rerun as rr

    path = Path(path)
    m = capture.twin.observables.model
    rec = rr.RecordingStream(application_id)
    stream = rec.binary_stream()
    rec.send_blueprint(
        _blueprint(
            bool(capture.messages.get("imu/data_raw")),
            bool(capture.messages.get("uwb/range")),
            has_events(capture.twin),
        ),
        make_active=False,
        make_default=True,
    )
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    _log_geoms(rec, m)
    log_robot(rec, m, capture, series, result)
    rec.disconnect()
    data = stream.read(flush=True, flush_timeout_sec=ENCODE_TIMEOUT_S) or b""
    write_bytes(path, data)
    return path


def record_run(twin_or_capture, rrd_path=None, mcap_path=None, result=None) -> dict[str, Path]:
    """Write the recordings of a finished run (its twin was :func:`attach`-ed before running).

    ``result`` (a :class:`~amr_twin.recording.run.RunResult`) adds the client calls; without it
    the series is taken from the twin's recorder
    (:func:`~amr_twin.recording.recorder.attach_recorder`). Returns {"rrd": path, "mcap": path}.
    """
    capture = (
        twin_or_capture if isinstance(twin_or_capture, Capture) else capture_of(twin_or_capture)
    )
    if capture is None:
        raise ValueError("record_run: attach(twin) must be called before the twin runs")
    if result is not None:
        series = result.series
    elif (recorder := recorder_of(capture.twin)) is not None:
        series = recorder.series()
    else:
        raise ValueError(
            "record_run: pass the run's result, or attach_recorder(twin) before the twin runs"
        )
    out = {}
    if rrd_path is not None:
        out["rrd"] = write_rrd(capture, series, rrd_path, result)
    if mcap_path is not None:
        from amr_twin.recording.mcap_log import write_mcap

        out["mcap"] = write_mcap(capture, series, mcap_path)
    return out
