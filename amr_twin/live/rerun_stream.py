"""The twin live in Rerun: ``amr-twin run ... --live rerun``.

The Rerun recording of :mod:`amr_twin.recording.rerun_log`, streamed as the twin runs: a gRPC server
(``rerun+http://127.0.0.1:PORT/proxy``; it keeps what was sent for late viewers) and Rerun's
web viewer served locally on ``WEB_PORT`` and connected to it; the native viewer connects
with ``rerun rerun+http://127.0.0.1:PORT/proxy``. Same application id, entity paths,
``sim_time`` timeline and default blueprint as the ``.rrd``
(:func:`amr_twin.recording.rerun_log._blueprint`; its time panel follows the newest data, and a
viewer that connects late gets the newest data first), the streams logged by the same
``_log_<stream>`` functions (:mod:`amr_twin.recording.rerun_world`,
:mod:`amr_twin.recording.rerun_streams`, :mod:`amr_twin.recording.event_log`), each flush handing
them what the simulated clock has passed since the last one. Two differences with the file:

- ``world/trajectory/{true,odom}`` grow every 0.5 s from poses at 10 Hz (the file: 2 Hz
  from the 100 Hz series) and keep the last :data:`TRAIL_POINTS` points;
- the collisions and faults panel is in the layout from the start when faults are
  injected, and added when a first collision happens.

Rerun's servers listen on all interfaces (its own choice; the SDK has no bind option).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np


FLUSH_US = 100_000
"""The stream is fed every 0.1 s of simulated time (each flush is one Rerun chunk per entity: the
per-chunk cost of the SDK and of the viewer, not the data, sets the price)."""
TRAIL_POINTS = 3000
"""Points kept in each live trajectory line (5 min at 10 Hz)."""
TRAIL_PERIOD_US = 100_000
TRAIL_LOG_US = 500_000
POSE_KEEP_S = 1.0
"""Body poses kept after they are sent: a LiDAR rotation's beams are placed on them (s)."""
TOPICS = ("scan", "imu/data_raw", "imu/mag", "wheel0_Vel", "wheel1_Vel", "wheel_Command", "odom")


class _Window:
    """What the ``.rrd`` writers read of a :class:`~amr_twin.recording.rerun_capture.Capture`, over
    a span of time."""

    def __init__(self, twin, body_ids, t_s, pos, quat, messages):
        self.twin, self.body_ids, self.messages = twin, body_ids, messages
        self._poses = (
            np.asarray(t_s, float),
            np.asarray(pos).reshape(len(t_s), len(body_ids), 3),
            np.asarray(quat).reshape(len(t_s), len(body_ids), 4),
        )

    def body_poses(self):
        return self._poses


class RerunSink:
    """Stream ``twin`` to a Rerun gRPC server and a local web viewer; fed by ``pacer`` (its
    :meth:`flush`).

    Parameters
    ----------
    twin : Twin
        The twin (built, not yet run); a bus tap and grid samplers are attached to it.
    grpc_port, web_port : int
        Ports of the gRPC server and of the web viewer (free ones chosen when 0).
    web_viewer : bool
        Serve the web viewer (the tests read the gRPC stream only).
    """

    def __init__(self, twin, grpc_port: int = 9876, web_port: int = 9090, web_viewer: bool = True):
        import rerun as rr

        from amr_twin.recording.rerun_log import _blueprint
        from amr_twin.recording.rerun_world import _log_geoms

        self.twin, self.rr = twin, rr
        m = twin.observables.model
        self.body_ids = np.arange(1, m.nbody)
        self._xpos, self._xquat = (
            twin.observables.named.data.xpos,
            twin.observables.named.data.xquat,
        )
        grid_us = twin.grid_us
        self.period_us = max(
            grid_us, int(round(1e6 / 30.0 / grid_us)) * grid_us
        )  # as rerun_capture.Capture's
        self._blueprint = _blueprint
        self._has_imu = "imu" in twin.sensors
        self._has_uwb = "uwb" in twin.sensors
        self._has_events = twin.faults is not None
        self.grpc_port = grpc_port or _free_port()
        self.web_port = web_port or _free_port()
        self.rec = rr.RecordingStream("amr_twin")
        self.uri = self.rec.serve_grpc(
            grpc_port=self.grpc_port, default_blueprint=self._layout(), newest_first=True
        )
        self.web_url = None
        if web_viewer:
            rr.serve_web_viewer(web_port=self.web_port, open_browser=False, connect_to=self.uri)
            from urllib.parse import quote

            self.web_url = f"http://127.0.0.1:{self.web_port}/?url={quote(self.uri, safe='')}"
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        _log_geoms(self.rec, m)
        if twin.faults is not None:
            from amr_twin.recording.event_log import faults_of, log_events

            log_events(self.rec, [], faults_of(twin))
        self._poses: list[
            tuple[int, np.ndarray, np.ndarray]
        ] = []  # t_us, xpos (nb, 3), xquat (nb, 4)
        self._sent_pose_us = -1
        from amr_twin.live.rows import LiveRows

        self._rows = LiveRows(twin)
        self._messages: dict[str, list] = {}
        self._scans: list = []  # scans waiting for the poses that place their beams
        self._commands: list[tuple[float, list[float]]] = []
        self._trail: dict[str, list] = {"true": [], "odom": []}
        self._trail_t = {"true": -TRAIL_PERIOD_US, "odom": -TRAIL_PERIOD_US}
        self._start = None
        self._next_trail_us = 0
        self._collisions_sent = 0
        self._next_flush_us = 0
        self._last_t_us = twin.clock.now_us
        twin.on_message(self._tap)
        twin.on_grid(self._on_grid)
        self._on_grid(twin.t_phys_us)

    def _layout(self):
        """The file's blueprint, its time panel following the newest data (a live view, not a
        replay)."""
        import rerun.blueprint as rrb

        layout = self._blueprint(self._has_imu, self._has_uwb, self._has_events)
        layout.time_panel = rrb.TimePanel(
            timeline="sim_time", play_state="following", state="collapsed"
        )
        return layout

    # -- the twin's side ------------------------------------------------------------------
    def _tap(self, topic: str, msg, t_us: int) -> None:
        if topic in TOPICS:
            self._messages.setdefault(topic, []).append((t_us, msg))

    def _on_grid(self, t_us: int) -> None:
        if t_us % self.period_us == 0:
            self._poses.append(
                (t_us, self._xpos[self.body_ids].copy(), self._xquat[self.body_ids].copy())
            )

    def flush(self, t_us: int) -> None:
        """Log everything up to ``t_us`` (simulated) to the stream, every :data:`FLUSH_US`."""
        self._last_t_us = t_us
        if t_us >= self._next_flush_us:
            self._next_flush_us = (t_us // FLUSH_US + 1) * FLUSH_US
            self._flush(t_us)

    def _flush(self, t_us: int) -> None:
        from amr_twin.recording.event_log import log_events
        from amr_twin.recording.rerun_streams import (
            _log_commands,
            _log_duty,
            _log_electrics,
            _log_imu,
            _log_wheel_speeds,
        )
        from amr_twin.recording.rerun_world import _log_body_transforms, _log_scan
        from amr_twin.sensors.lidar_beams import scan_end_time_s

        rec, m = self.rec, self.twin.observables.model
        poses = [p for p in self._poses if p[0] <= t_us]
        new_poses = [p for p in poses if p[0] > self._sent_pose_us]
        messages = {k: [it for it in v if it[0] <= t_us] for k, v in self._messages.items()}
        self._messages = {k: [it for it in v if it[0] > t_us] for k, v in self._messages.items()}
        if new_poses:
            _log_body_transforms(rec, m, self._window(new_poses, {}))
            self._sent_pose_us = new_poses[-1][0]
        self._scans += messages.pop("scan", [])
        if self._scans and self._poses:
            # a scan's beams are placed on the poses around them: wait for a pose at or after its
            # last beam (the physics runs ahead of the clock, so there usually is one)
            last_pose_s = self._poses[-1][0] * 1e-6
            ready = [it for it in self._scans if scan_end_time_s(it[1]) <= last_pose_s]
            self._scans = [it for it in self._scans if scan_end_time_s(it[1]) > last_pose_s]
            if ready:
                _log_scan(rec, m, self._window(self._poses, {"scan": ready}))
        keep_from = t_us - int(POSE_KEEP_S * 1e6)
        self._poses = [p for p in self._poses if p[0] >= keep_from]
        _log_imu(rec, self._window([], messages))
        rows = self._rows.take(t_us)
        new_commands = [
            (t * 1e-6, [float(v) for v in msg.data]) for t, msg in messages.get("wheel_Command", [])
        ]
        self._commands += new_commands
        if rows is not None:
            series = self._series(rows, messages)
            _log_wheel_speeds(rec, series)
            _log_duty(rec, series)
            _log_electrics(rec, series)
            self._trajectory(series, messages.get("odom", []), t_us)
        if new_commands:
            _log_commands(rec, SimpleNamespace(commands=new_commands))
        collisions = self.twin.observables.collisions
        if len(collisions) > self._collisions_sent:
            if not self._has_events:
                self._has_events = True
                rec.send_blueprint(self._layout(), make_active=False, make_default=True)
            log_events(rec, list(collisions[self._collisions_sent :]), [])
            self._collisions_sent = len(collisions)

    def _window(self, poses, messages) -> _Window:
        t = [p[0] * 1e-6 for p in poses]
        return _Window(
            self.twin, self.body_ids, t, [p[1] for p in poses], [p[2] for p in poses], messages
        )

    def _series(self, rows, messages) -> SimpleNamespace:
        """The rows as the series the ``.rrd`` writers read, with the wheel speeds published
        meanwhile and every command so far (the references are held from them)."""
        published = {
            w: np.array(
                [(t * 1e-6, msg.data) for t, msg in messages.get(f"wheel{w}_Vel", [])], float
            ).reshape(-1, 2)
            for w in (0, 1)
        }
        return SimpleNamespace(**vars(rows), published=published, commands=self._commands)

    def _trajectory(self, series, odom, t_us: int) -> None:
        rr = self.rr
        if self._start is None:
            self._start = series.pose[0]
        x0, y0, yaw0 = self._start
        c, s = math.cos(yaw0), math.sin(yaw0)
        for i, t in enumerate(series.t_s):
            self._add_point("true", int(round(t * 1e6)), series.pose[i, :2])
        for t_u, msg in odom:
            p = msg.pose.pose.position
            self._add_point("odom", t_u, (x0 + c * p.x - s * p.y, y0 + s * p.x + c * p.y))
        if t_us < self._next_trail_us:
            return
        self._next_trail_us = (t_us // TRAIL_LOG_US + 1) * TRAIL_LOG_US
        self.rec.set_time("sim_time", duration=t_us * 1e-6)
        for name, color in (("true", (40, 160, 40)), ("odom", (220, 60, 60))):
            trail = self._trail[name] = self._trail[name][-TRAIL_POINTS:]
            if len(trail) >= 2:
                pts = np.column_stack([np.array(trail), np.full(len(trail), 0.01)])
                self.rec.log(
                    f"world/trajectory/{name}", rr.LineStrips3D([pts], colors=[color], radii=[0.01])
                )

    def _add_point(self, name: str, t_us: int, xy) -> None:
        if t_us - self._trail_t[name] >= TRAIL_PERIOD_US:
            self._trail_t[name] = t_us
            self._trail[name].append((float(xy[0]), float(xy[1])))

    def close(self) -> None:
        """Log what is left and flush the stream; the gRPC server stops with the recording stream
        (the process' end)."""
        self._flush(self._last_t_us)
        self.rec.flush()


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]
