"""``--live rerun``, the Rerun recording streamed while the twin runs, read back.

The stream is read by Rerun's own viewer binary (``rerun URI --save FILE``: it connects to the
gRPC server as any viewer does and writes what it receives), then compared with the ``.rrd``
that :func:`amr_twin.recording.rerun_log.record_run` writes for the same run: same entities, same
rows, same values, same default blueprint. ``rerun rrd verify`` checks the streamed file (the
viewer's ``--save`` of a stream writes no footer, the optional index of a finished file: checked
without it)."""

import signal
import subprocess
import sys
import time
import urllib.request
import warnings
from pathlib import Path

import numpy as np
import pytest

from amr_twin.model.config import load_config
from amr_twin.sim.faults import parse_faults
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.recording.rerun_capture import attach
from amr_twin.recording.rerun_log import record_run
from amr_twin.assembly.command import Command
from amr_twin.recording.run import run_mission

RERUN = str(Path(sys.executable).with_name("rerun"))
STEPS = [
    (0.0, Command("linear", speed_m_s=0.5)),
    (1.5, Command("angular", speed_deg_s=-60.0, icc_m=-1.0)),
]
DURATION_S = 3.0


def _reader(path):
    from rerun.chunk import RrdReader

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a streamed file has no footer: read by a whole-file scan
        return RrdReader(str(path))


def _columns(path) -> dict[str, dict[str, list]]:
    """entity -> component column -> values in sim_time order, from the recording store."""
    rows: dict[str, list] = {}
    for chunk in _reader(path).stream().to_chunks():
        batch = chunk.to_record_batch()
        names = [n for n in batch.schema.names if ":" in n or n == "sim_time"]
        columns = [
            batch.column(n).cast("int64") if n == "sim_time" else batch.column(n) for n in names
        ]
        rows.setdefault(chunk.entity_path, []).extend(zip(*(c.to_pylist() for c in columns)))
        rows.setdefault("_names" + chunk.entity_path, names)
    out = {}
    for entity, values in rows.items():
        if entity.startswith("_names"):
            continue
        names = rows["_names" + entity]
        if "sim_time" in names:
            k = names.index("sim_time")
            values = sorted(values, key=lambda v: v[k])
        out[entity] = {n: [v[i] for v in values] for i, n in enumerate(names)}
    return out


def _views(path) -> list[tuple]:
    """The default blueprint's views: (class, name, origin), sorted."""
    reader = _reader(path)
    views = []
    for chunk in reader.stream(store=reader.blueprints()[-1]).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:class_identifier" in batch.schema.names:
            views += [
                tuple(v[0] for v in row)
                for row in zip(
                    *(
                        batch.column(f"ViewBlueprint:{c}").to_pylist()
                        for c in ("class_identifier", "display_name", "space_origin")
                    )
                )
            ]
    return sorted(views)


@pytest.fixture(scope="module")
def streamed(tmp_path_factory):
    """A 3 s run with IMU, LiDAR and a fault, streamed live (unpaced) and recorded to a file."""
    from amr_twin.live.session import LiveOptions, LiveSession

    folder = tmp_path_factory.mktemp("live_rerun")
    cfg = load_config()
    options = TwinOptions(
        world="warehouse",
        start_xy_yaw=None,
        sensors=("imu", "lidar"),
        faults=tuple(parse_faults(["imu-stuck@1:for=1"], duration_s=DURATION_S, sensors=True)),
    )
    twin = Twin(cfg, options)
    attach(twin)
    session = LiveSession(
        twin, LiveOptions(mode="rerun", port=0, web_port=0, rate=0.0), say=lambda _line: None
    )
    result = run_mission(cfg, STEPS, DURATION_S, options, twin=twin)
    session.close()
    record_run(twin, rrd_path=folder / "file.rrd", result=result)
    with urllib.request.urlopen(
        session.sink.web_url, timeout=10
    ) as page:  # the web viewer is served
        assert page.status == 200 and b"<html" in page.read(4096).lower()
    live = folder / "live.rrd"
    viewer = subprocess.Popen(
        [RERUN, session.sink.uri, "--save", str(live), "--bind", "127.0.0.1", "--port", "auto"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    expected = int(round(DURATION_S * 100)) + 1
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            time.sleep(0.5)
            try:
                if (
                    len(_columns(live).get("/wheels/left/true_rpm", {}).get("sim_time", []))
                    >= expected
                ):
                    break
            except Exception:  # noqa: BLE001 - the file is still being written
                continue
        time.sleep(0.5)
    finally:
        viewer.send_signal(signal.SIGINT)
        try:
            viewer.wait(timeout=20)
        except subprocess.TimeoutExpired:
            viewer.kill()
            viewer.wait()
    return folder / "file.rrd", live, session


def test_the_stream_is_the_recording(streamed):
    file, live, _session = streamed
    a, b = _columns(file), _columns(live)
    # the file also logs the client calls; its trajectories grow at 2 Hz from the 100 Hz series
    different = {"/commands", "/world/trajectory/true", "/world/trajectory/odom"}
    different |= {e for e in set(a) if e.startswith("/world/trajectory/")}  # the file's 10 s blocks
    assert set(a) - different == set(b) - different
    for entity in set(a) - different:
        assert a[entity].keys() == b[entity].keys(), entity
        for name in a[entity]:
            assert len(a[entity][name]) == len(b[entity][name]), (entity, name)
    for entity, name in (
        ("/wheels/left/true_rpm", "Scalars:scalars"),
        ("/wheels/right/published_rpm", "Scalars:scalars"),
        ("/duty/right", "Scalars:scalars"),
        ("/imu/gyro", "Scalars:scalars"),
        ("/world/bodies/amr/base_link", "Transform3D:translation"),
        ("/world/bodies/amr/wheel_left_link", "Transform3D:quaternion"),
    ):
        assert np.array_equal(np.array(a[entity][name], float), np.array(b[entity][name], float)), (
            entity
        )
    scans_a, scans_b = (
        a["/world/scan"]["Points3D:positions"],
        b["/world/scan"]["Points3D:positions"],
    )
    assert len(scans_a) >= 15 and all(
        np.allclose(x, y, atol=1e-6) for x, y in zip(scans_a, scans_b)
    )
    assert "/events/faults" in b and any(
        "imu-stuck" in str(v) for v in b["/events/faults"]["TextLog:text"]
    )
    trail = np.array(
        b["/world/trajectory/true"]["LineStrips3D:strips"][-1][0]
    )  # the last line logged
    end = np.array(a["/world/bodies/amr/base_link"]["Transform3D:translation"][-1]).reshape(-1)
    assert np.allclose(trail[-1, :2], end[:2], atol=0.06)  # the live path ends where the robot is


def test_same_default_blueprint_as_the_file(streamed):
    file, live, _session = streamed
    views = _views(live)
    assert views == _views(file)
    assert ("3D", "twin", "world") in views and ("TimeSeries", "IMU", "imu") in views


def test_the_streamed_file_verifies(streamed):
    """A saved stream has no footer (the optional index of a finished file): checked without it."""
    _file, live, _session = streamed
    result = subprocess.run(
        [RERUN, "rrd", "verify", "--check-footers", "false", str(live)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr[-2000:]
