"""Record a run to a Rerun ``.rrd`` file, headless (issue 7).

Two stages, so that a recorded run costs little while it runs:

1. :class:`Capture` is attached to a :class:`~amr_twin.loop.Twin` before it runs.
   It taps the bus (keeps every published message with its time) and samples the
   world pose of each robot body as a grid sampler of the loop (default ~30 Hz on
   the recorder's 10 ms grid; no clock event, so the physics chunks, hence the
   run, are unchanged). It only reads ``data.xpos`` / ``data.xquat``.
2. After the run :func:`write_rrd` (or :func:`record_run`, which also writes the
   MCAP file of :mod:`amr_twin.mcap_log`) turns the capture plus the finished
   :class:`~amr_twin.recorder.RunSeries` into Rerun columns, one ``_log_<stream>``
   function per stream, all on the ``sim_time`` timeline.

Entities::

    world                               view coordinates (Z up)
    world/bodies/<body>                 Transform3D over time (robot bodies)
    world/bodies/<body>/geoms/<kind>    static Boxes3D / Ellipsoids3D / Cylinders3D
    world/bodies/amr/laser/scan         LaserScan points in the laser frame
    world/scan                          the same points in the world (deskewed per beam)
    world/trajectory/{true,odom}        LineStrips3D, growing at 2 Hz
    wheels/{left,right}/{reference,published,true}_rpm   Scalars
    duty/{left,right}                   analogWrite counts
    imu/{accel,gyro,mag}                Scalars (x, y, z)
    uwb/anchor_<i>/range_m              Scalars, one per received range (only with a UWB tag)
    world/uwb/anchors                   static Points3D of the anchors
    world/uwb/anchor_<i>/ray            LineStrips3D tag -> anchor at each range
    commands                            TextLog of wheel_Command and the client calls

A default blueprint (3D view + time-series plots) is sent with the recording.
"""

from __future__ import annotations

import math
import os
import weakref
from pathlib import Path

import mujoco
import numpy as np

US = 1_000_000
TIMELINE = "sim_time"
VISUAL_GROUPS = (0, 1, 4)  # world, robot visuals, payload (2 is robot collision)
WHEELS = ("left", "right")

_captures: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


class Capture:
    """Bus messages and body poses of a running twin (attach before running).

    The body poses are taken by a grid sampler of the loop (``twin.samplers``,
    called on the record grid while the physics steps), not by a clock event: the
    capture adds no boundary to the physics chunks, so a recorded run is the same
    run whatever the caller's ``advance`` pattern (a sweep's 20 ms loop included).
    """

    def __init__(self, twin, body_hz: float = 30.0):
        self.twin = twin
        self.messages: dict[str, list[tuple[int, object]]] = {}
        m = twin.physics.model
        self.body_ids = np.array([b for b in range(1, m.nbody)], dtype=int)
        grid_us = twin.dt_us * twin.recorder.every
        self.period_us = max(grid_us, int(round(US / body_hz / grid_us)) * grid_us)
        self._t: list[int] = []
        self._pos: list[np.ndarray] = []
        self._quat: list[np.ndarray] = []
        twin.bus.add_tap(self._tap)
        self._sample(twin.t_phys_us)
        twin.samplers.append(self._on_grid)
        _captures[twin] = self

    def _tap(self, topic: str, msg, t_us: int) -> None:
        lst = self.messages.get(topic)
        if lst is None:
            lst = self.messages[topic] = []
        lst.append((t_us, msg))

    def _sample(self, t_us: int) -> None:
        d, ids = self.twin.physics.data, self.body_ids
        self._t.append(int(t_us))
        self._pos.append(d.xpos[ids].copy())
        self._quat.append(d.xquat[ids].copy())

    def _on_grid(self, t_us: int) -> None:
        """Grid sampler: the physics is at ``t_us``; keep the poses every ``period_us``."""
        if t_us % self.period_us == 0 and t_us > self._t[-1]:
            self._sample(t_us)

    def body_poses(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """t_s (n,), positions (n, nb, 3), quaternions w x y z (n, nb, 4)."""
        return (np.array(self._t, float) / US, np.array(self._pos).reshape(-1, len(self.body_ids), 3),
                np.array(self._quat).reshape(-1, len(self.body_ids), 4))


def attach(twin, body_hz: float = 30.0) -> Capture:
    """Start capturing ``twin`` (before it runs); returns the :class:`Capture`."""
    return _captures.get(twin) or Capture(twin, body_hz)


def capture_of(twin) -> Capture | None:
    return _captures.get(twin)


def atomic_target(path: Path) -> Path:
    """A temporary name next to ``path`` (written, then renamed by the caller)."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Delete the half-written recordings a killed writer left in ``folder``; return them.

    A writer that is interrupted normally removes its temporary file itself; one
    killed outright (SIGKILL, a crashed worker) leaves ``.<name>.rrd.<pid>.tmp`` or
    ``.<name>.mcap.<pid>.tmp`` behind. Only those of processes no longer running
    are deleted, so a concurrent writer's file is left alone.
    """
    removed = []
    for tmp in Path(folder).glob(".*.tmp"):
        stem, _, pid = tmp.name[:-len(".tmp")].rpartition(".")
        if stem.endswith((".rrd", ".mcap")) and pid.isdigit() and not _alive(int(pid)):
            tmp.unlink(missing_ok=True)
            removed.append(tmp)
    return removed


def recording_folder(folder: Path) -> Path:
    """``folder`` made absolute (worker processes may run elsewhere), created, stale temporaries removed."""
    folder = Path(folder).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(folder)
    return folder


TRACKED = "world/bodies/amr/base_link"
"""The 3D view's camera follows the robot's base."""


# -- geoms -----------------------------------------------------------------------
def body_entity(m: mujoco.MjModel, b: int) -> str:
    name = m.body(b).name or f"body{b}"
    return "world/bodies/" + ("world" if b == 0 else name)


def _rgba(m: mujoco.MjModel, g: int) -> np.ndarray:
    mat = m.geom_matid[g]
    rgba = m.mat_rgba[mat] if mat >= 0 else m.geom_rgba[g]
    return (np.clip(rgba, 0, 1) * 255).astype(np.uint8)


def _log_geoms(rec, m: mujoco.MjModel) -> None:
    """Each body's visual geoms, once, static, in the body frame."""
    import rerun as rr

    T = mujoco.mjtGeom
    for b in range(m.nbody):
        kinds: dict[str, list] = {"boxes": [], "ellipsoids": [], "cylinders": []}
        for g in range(m.body_geomadr[b], m.body_geomadr[b] + m.body_geomnum[b]):
            if m.geom_group[g] not in VISUAL_GROUPS or m.geom_rgba[g][3] == 0:
                continue
            typ, size = int(m.geom_type[g]), m.geom_size[g]
            pos, q = m.geom_pos[g], m.geom_quat[g]
            xyzw = [q[1], q[2], q[3], q[0]]
            if typ == T.mjGEOM_BOX:
                kinds["boxes"].append((pos, xyzw, 2 * size, _rgba(m, g)))
            elif typ == T.mjGEOM_PLANE:
                half = [s if s > 0 else 15.0 for s in size[:2]]
                kinds["boxes"].append((pos - [0, 0, 0.001], xyzw, [2 * half[0], 2 * half[1], 0.002],
                                       _rgba(m, g)))
            elif typ == T.mjGEOM_SPHERE:
                kinds["ellipsoids"].append((pos, xyzw, [size[0]] * 3, _rgba(m, g)))
            elif typ == T.mjGEOM_ELLIPSOID:
                kinds["ellipsoids"].append((pos, xyzw, size[:3], _rgba(m, g)))
            elif typ in (int(T.mjGEOM_CYLINDER), int(T.mjGEOM_CAPSULE)):
                kinds["cylinders"].append((pos, xyzw, (size[0], 2 * size[1]), _rgba(m, g)))
        base = body_entity(m, b) + "/geoms/"
        for kind, items in kinds.items():
            if not items:
                continue
            centers = np.array([i[0] for i in items])
            quats = np.array([i[1] for i in items])
            colors = np.array([i[3] for i in items])
            if kind == "boxes":
                arch = rr.Boxes3D(centers=centers, quaternions=quats, sizes=np.array([i[2] for i in items]),
                                  colors=colors, fill_mode="solid")
            elif kind == "ellipsoids":
                arch = rr.Ellipsoids3D(centers=centers, quaternions=quats,
                                       half_sizes=np.array([i[2] for i in items]), colors=colors,
                                       fill_mode="solid")
            else:
                rl = np.array([i[2] for i in items])
                arch = rr.Cylinders3D(centers=centers, quaternions=quats, radii=rl[:, 0], lengths=rl[:, 1],
                                      colors=colors, fill_mode="solid")
            rec.log(base + kind, arch, static=True)


# -- streams -----------------------------------------------------------------------
def _time(t_s) -> list:
    import rerun as rr

    return [rr.TimeColumn(TIMELINE, duration=np.asarray(t_s, float))]


def _scalars(rec, path: str, t_s, values) -> None:
    import rerun as rr

    values = np.asarray(values, float)
    if len(values):
        rec.send_columns(path, indexes=_time(t_s), columns=rr.Scalars.columns(scalars=values))


def _log_body_transforms(rec, m, capture: Capture) -> None:
    import rerun as rr

    t, pos, quat = capture.body_poses()
    for j, b in enumerate(capture.body_ids):
        q = quat[:, j]
        rec.send_columns(body_entity(m, b), indexes=_time(t),
                         columns=rr.Transform3D.columns(translation=pos[:, j],
                                                        quaternion=q[:, [1, 2, 3, 0]]))


def reference_rpm(series) -> np.ndarray:
    """Signed reference (motion x speed) of each wheel at ``series.t_s``, held; (n, 2), 0 before."""
    cmd_t = np.array([c[0] for c in series.commands], float)
    cmd = np.array([c[1] for c in series.commands], float).reshape(-1, 4)
    idx = np.searchsorted(cmd_t, series.t_s, side="right") - 1
    ref = np.column_stack([cmd[:, 0] * cmd[:, 1], cmd[:, 2] * cmd[:, 3]]) if len(cmd) else np.zeros((1, 2))
    return np.where((idx >= 0)[:, None], ref[np.clip(idx, 0, None)], 0.0)


def _log_wheel_speeds(rec, series) -> None:
    ref = reference_rpm(series)
    for w, name in enumerate(WHEELS):
        _scalars(rec, f"wheels/{name}/reference_rpm", series.t_s, ref[:, w])
        pub = series.published[w]
        _scalars(rec, f"wheels/{name}/published_rpm", pub[:, 0], pub[:, 1])
        _scalars(rec, f"wheels/{name}/true_rpm", series.t_s, series.true_rpm[:, w])


def _log_duty(rec, series) -> None:
    for w, name in enumerate(WHEELS):
        _scalars(rec, f"duty/{name}", series.t_s, series.pwm_counts[:, w])


def _log_commands(rec, series, result=None) -> None:
    import rerun as rr

    for t_s, command in (result.commands if result is not None else []):
        rec.set_time(TIMELINE, duration=float(t_s))
        rec.log("commands", rr.TextLog(f"client {command.describe()}", level="INFO"))
    for t_s, data in series.commands:
        rec.set_time(TIMELINE, duration=float(t_s))
        rec.log("commands", rr.TextLog("wheel_Command [" + ", ".join(f"{v:g}" for v in data) + "]",
                                       level="INFO"))


def _log_trajectory(rec, series, rate_hz: float = 2.0) -> None:
    """True (world) and odometry (odom frame put on the start pose) paths, growing."""
    import rerun as rr

    true_xy = series.pose[:, :2]
    x0, y0, yaw0 = series.pose[0]
    c, s = math.cos(yaw0), math.sin(yaw0)
    odom = series.odom
    odom_xy = np.column_stack([x0 + c * odom[:, 1] - s * odom[:, 2], y0 + s * odom[:, 1] + c * odom[:, 2]])
    end = float(series.t_s[-1]) if len(series.t_s) else 0.0
    for t in np.append(np.arange(0.0, end, 1.0 / rate_hz), end):
        rec.set_time(TIMELINE, duration=float(t))
        for name, tt, xy, color in (("true", series.t_s, true_xy, (40, 160, 40)),
                                    ("odom", odom[:, 0], odom_xy, (220, 60, 60))):
            n = int(np.searchsorted(tt, t, side="right"))
            if n >= 2:
                pts = np.vstack([xy[:n:5], xy[n - 1:n]])
                pts = np.column_stack([pts, np.full(len(pts), 0.01)])
                rec.log(f"world/trajectory/{name}", rr.LineStrips3D([pts], colors=[color], radii=[0.01]))


def _body_pose_at(capture: Capture, m, body: str, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position (n, 3), m, and yaw (n,), rad, of ``body`` at ``t_s``, interpolated from the body samples."""
    j = int(np.nonzero(capture.body_ids == mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body))[0][0])
    t, pos, quat = capture.body_poses()
    q = quat[:, j]
    yaw = np.unwrap(np.arctan2(2 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]), 1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2)))
    p = np.column_stack([np.interp(t_s, t, pos[:, j, k]) for k in range(3)])
    return p, np.interp(t_s, t, yaw)


def _laser_pose_at(capture: Capture, m, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Laser position (n, 3) and yaw (n,) at ``t_s``, interpolated from the body samples."""
    return _body_pose_at(capture, m, "amr/laser", t_s)


def _log_scan(rec, m, capture: Capture) -> None:
    import rerun as rr

    scans = capture.messages.get("scan", [])
    if not scans:
        return
    for _t_us, msg in scans:
        r = np.asarray(msg.ranges, float)
        ang = msg.angle_min + msg.angle_increment * np.arange(len(r))
        ok = np.isfinite(r)
        r = np.where(ok, r, 0.0)  # no return: inf; dropped below, kept out of the products
        local = np.column_stack([r * np.cos(ang), r * np.sin(ang), np.zeros_like(r)])[ok]
        t_beam = msg.header.stamp.to_sec() + msg.time_increment * np.arange(len(r))[ok]
        p, yaw = _laser_pose_at(capture, m, t_beam)
        c, s = np.cos(yaw), np.sin(yaw)
        world = np.column_stack([p[:, 0] + c * local[:, 0] - s * local[:, 1],
                                 p[:, 1] + s * local[:, 0] + c * local[:, 1], p[:, 2]])
        rec.set_time(TIMELINE, duration=msg.header.stamp.to_sec() + msg.scan_time)
        rec.log("world/bodies/amr/laser/scan", rr.Points3D(local, colors=[(250, 200, 40)], radii=[0.01]))
        rec.log("world/scan", rr.Points3D(world, colors=[(40, 120, 250)], radii=[0.015]))


def _log_imu(rec, capture: Capture) -> None:
    imu = capture.messages.get("imu/data_raw", [])
    if imu:
        t = [msg.header.stamp.to_sec() for _, msg in imu]
        _scalars(rec, "imu/accel", t, [(m.linear_acceleration.x, m.linear_acceleration.y,
                                        m.linear_acceleration.z) for _, m in imu])
        _scalars(rec, "imu/gyro", t, [(m.angular_velocity.x, m.angular_velocity.y,
                                       m.angular_velocity.z) for _, m in imu])
    mag = capture.messages.get("imu/mag", [])
    if mag:
        t = [msg.header.stamp.to_sec() for _, msg in mag]
        _scalars(rec, "imu/mag", t, [(m.magnetic_field.x, m.magnetic_field.y, m.magnetic_field.z)
                                     for _, m in mag])


def uwb_geometry(twin) -> tuple[np.ndarray, np.ndarray]:
    """Anchor positions (K, 3) in the world and the tag position (3,) in ``base_link``, m.

    From the twin's ``UwbSensor`` (``twin.uwb``) when it has one, else from ``twin.cfg.uwb``.
    """
    sensor = getattr(twin, "uwb", None)
    if sensor is not None:
        return np.asarray(sensor.anchors_xyz_m, float), np.asarray(sensor.tag_pos_m, float)
    u = twin.cfg.uwb
    anchors = np.column_stack([np.asarray(u.anchors_xy_m, float), np.full(len(u.anchors_x_m), u.anchor_z_m)])
    return anchors, np.asarray(u.tag_pos_m, float)


def uwb_ranges(capture: Capture) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """The captured ``uwb/range`` messages per anchor: ``{i: (stamp t_s (n,), range_m (n,))}``."""
    from .sensors.uwb import anchor_index

    per: dict[int, tuple[list, list]] = {}
    for _t_us, msg in capture.messages.get("uwb/range", []):
        t, r = per.setdefault(anchor_index(msg.header.frame_id), ([], []))
        t.append(msg.header.stamp.to_sec())
        r.append(float(msg.range))
    return {i: (np.array(t), np.array(r)) for i, (t, r) in sorted(per.items())}


def _log_uwb(rec, m, capture: Capture) -> None:
    """Ranges per anchor as scalars, the anchors, and a line from the tag to each anchor ranged.

    The tag's world position at a range's stamp uses the base's interpolated
    position and yaw (the base's small tilt is left out of the line).
    """
    import rerun as rr

    ranges = uwb_ranges(capture)
    if not ranges:
        return
    anchors, tag = uwb_geometry(capture.twin)
    rec.log("world/uwb/anchors", rr.Points3D(anchors, radii=[0.08], colors=[(200, 60, 200)],
                                             labels=[f"anchor_{i}" for i in range(len(anchors))]), static=True)
    for i, (t_s, range_m) in ranges.items():
        _scalars(rec, f"uwb/anchor_{i}/range_m", t_s, range_m)
        if i >= len(anchors):
            continue
        p, yaw = _body_pose_at(capture, m, "amr/base_link", t_s)
        c, s = np.cos(yaw), np.sin(yaw)
        tag_w = np.column_stack([p[:, 0] + c * tag[0] - s * tag[1], p[:, 1] + s * tag[0] + c * tag[1],
                                 p[:, 2] + tag[2]])
        strips = np.stack([tag_w, np.broadcast_to(anchors[i], tag_w.shape)], axis=1)  # (n, 2, 3)
        rec.send_columns(f"world/uwb/anchor_{i}/ray", indexes=_time(t_s),
                         columns=rr.LineStrips3D.columns(strips=strips))
        rec.log(f"world/uwb/anchor_{i}/ray", rr.LineStrips3D.from_fields(colors=[(200, 60, 200)], radii=[0.005]),
                static=True)


def _blueprint(has_imu: bool, has_uwb: bool = False):
    import rerun.blueprint as rrb

    plots = [rrb.TimeSeriesView(origin=f"wheels/{w}", name=f"{w} wheel RPM") for w in WHEELS]
    plots.append(rrb.TimeSeriesView(origin="duty", name="PWM counts"))
    if has_imu:
        plots.append(rrb.TimeSeriesView(origin="imu", name="IMU"))
    if has_uwb:
        plots.append(rrb.TimeSeriesView(origin="uwb", name="UWB ranges, m"))
    return rrb.Blueprint(
        rrb.Horizontal(rrb.Vertical(rrb.Spatial3DView(origin="world", name="twin",
                                                      eye_controls=rrb.EyeControls3D(tracking_entity=TRACKED)),
                                    rrb.TextLogView(origin="commands", name="commands"), row_shares=[4, 1]),
                       rrb.Vertical(*plots), column_shares=[3, 2]),
        collapse_panels=True)


def write_rrd(capture: Capture, series, path: Path, result=None, application_id: str = "amr_twin") -> Path:
    """Write the capture and ``series`` to ``path`` (.rrd), through a temporary file."""
    import rerun as rr

    path = Path(path)
    tmp = atomic_target(path)
    m = capture.twin.physics.model
    rec = rr.RecordingStream(application_id)
    try:
        rec.save(tmp, default_blueprint=_blueprint(bool(capture.messages.get("imu/data_raw")),
                                                   bool(capture.messages.get("uwb/range"))))
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        _log_geoms(rec, m)
        _log_body_transforms(rec, m, capture)
        _log_scan(rec, m, capture)
        _log_imu(rec, capture)
        _log_uwb(rec, m, capture)
        _log_wheel_speeds(rec, series)
        _log_duty(rec, series)
        _log_commands(rec, series, result)
        _log_trajectory(rec, series)
        rec.flush()
        rec.disconnect()
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def record_run(twin_or_capture, rrd_path=None, mcap_path=None, result=None) -> dict[str, Path]:
    """Write the recordings of a finished run (its twin was :func:`attach`-ed before running).

    ``result`` (a :class:`~amr_twin.run.RunResult`) adds the client calls; without it
    the series is taken from the twin's recorder. Returns {"rrd": path, "mcap": path}.
    """
    capture = twin_or_capture if isinstance(twin_or_capture, Capture) else capture_of(twin_or_capture)
    if capture is None:
        raise ValueError("record_run: attach(twin) must be called before the twin runs")
    series = result.series if result is not None else capture.twin.recorder.series()
    out = {}
    if rrd_path is not None:
        out["rrd"] = write_rrd(capture, series, rrd_path, result)
    if mcap_path is not None:
        from .mcap_log import write_mcap

        out["mcap"] = write_mcap(capture, series, mcap_path)
    return out
