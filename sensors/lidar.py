"""Slamtec RPLIDAR A1 on the ``amr/laser`` site: rotating 2D scans cast in MuJoCo.

One rotation takes ``n = round(sample_rate / scan_rate)`` samples, one every
``1 / sample_rate`` s (2000 Hz at 5.5 Hz: 364 beams, 1 deg apart, 182 ms per scan;
RPLIDAR A1M8 datasheet v2.x). Beam ``i`` points at ``angle_min + i * increment``
in the ``laser`` frame (REP-103, counter-clockwise from x, ``angle_min = -pi``) and
is acquired at ``t0 + i / sample_rate``. Beams are cast in groups: a clock event
at every multiple of ``group_us`` (default 20 ms, 40 beams at 2000 Hz; on the
same instants as other periodic events, which makes it nearly free in the loop)
casts the beams acquired since the previous event with one ``mujoco.mj_multiRay``
call, each beam from
the laser pose at its own instant (the site pose now, moved back along the
site's velocity: first order over at most ``group_us``), so that a scan taken
while the robot moves is distorted as a real one. The beam instants are kept in
:attr:`Lidar.beam_t_us` and :attr:`Lidar.last_beam_t_us` (for deskew).

Rays see geom groups 0 (world) and 4 (payload) only, never the robot's own
wheels, casters or frame (groups 1, 2). The cutoff is large and ranges are
clamped here (``mj_multiRay`` culls by bounding volume, stack-notes.md). Range
noise is Gaussian with sigma ``max(floor, frac * r)``, then quantised to the
1/4 mm of the A1 protocol. No hit, or a range outside ``[range_min, range_max]``,
is ``inf`` as ``rplidar_ros`` publishes it.

When a rotation is complete, a ``sensor_msgs/LaserScan`` goes out on ``scan``
at the next cast event (at most ``group_us`` after its last beam; frame
``laser``, stamp = first beam, as ``rplidar_ros``). ``start_motor`` / ``stop_motor`` services
start and stop the rotation (the motor spin-up time is not modelled).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amr_twin.bus import LASER_FRAME, Bus
from amr_twin.clock import VirtualClock
from amr_twin.config import LidarCfg
from amr_twin.messages import Header, LaserScan, Time

US = 1_000_000
SEEN_GROUPS = (0, 4)
"""Geom groups a beam can hit: world and payload (build.py)."""
CUTOFF_M = 1e6
"""Culling distance passed to ``mj_multiRay``: effectively none."""


class Lidar:
    """RPLIDAR A1 scanning in a compiled twin on the shared clock.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The compiled twin, with a site ``amr/laser``.
    clock : VirtualClock
        Shared clock; one event per beam group and one per rotation.
    bus : Bus
        Publishes ``scan``; serves ``start_motor`` and ``stop_motor``.
    cfg : LidarCfg
        ``lidar:`` section of the parameter file.
    seed : int or None
        Seed of the ``numpy.random.Generator`` drawing the range noise.
    group_us : int
        Period of the casts, us: every multiple of it in absolute time (so that the
        clock events coincide with the IMU's and the firmware's), one
        ``mj_multiRay`` call casts the beams acquired since the previous one.
    autostart : bool
        Start rotating at the current clock time.
    """

    def __init__(self, model, data, clock: VirtualClock, bus: Bus, cfg: LidarCfg, seed: int | None = 0,
                 group_us: int = 20000, frame_id: str = LASER_FRAME, site: str = "amr/laser",
                 autostart: bool = True):
        self.model, self.data, self.clock, self.bus, self.cfg = model, data, clock, bus, cfg
        self.frame_id = frame_id
        self.site_id = int(model.site(site).id)
        self.rng = np.random.default_rng(seed)
        self.n_beams = int(round(cfg.sample_rate_hz / cfg.scan_rate_hz))
        self.beam_dt_us = US // cfg.sample_rate_hz
        self.scan_us = self.n_beams * self.beam_dt_us
        self.angle_increment = 2 * math.pi / self.n_beams
        self.angle_min = -math.pi
        self.angles_rad = self.angle_min + self.angle_increment * np.arange(self.n_beams)
        self.local_dirs = np.stack([np.cos(self.angles_rad), np.sin(self.angles_rad),
                                    np.zeros(self.n_beams)], axis=1)  # (n, 3) in the laser frame
        self.cast_period_us = int(group_us)
        per = max(1, self.cast_period_us // self.beam_dt_us)
        self.groups = [(i, min(i + per, self.n_beams)) for i in range(0, self.n_beams, per)]
        """Beam ranges of about ``group_us`` each (the typical casts of one rotation)."""
        self.geomgroup = np.zeros(6, np.uint8)
        self.geomgroup[list(SEEN_GROUPS)] = 1
        self.dist_m = np.full(self.n_beams, -1.0)
        """True distances of the rotation in progress, m (-1: no hit)."""
        self._vel = np.zeros(6)
        self._normal = np.zeros(3 * self.n_beams)
        self.hit_geom = np.full(self.n_beams, -1, np.int32)
        """Geom id hit by each beam of the rotation in progress (-1: none)."""
        self.beam_t_us = np.zeros(self.n_beams, np.int64)
        """Instant of each beam of the rotation in progress, us (t0 + i / sample_rate)."""
        self.last_scan: LaserScan | None = None
        self.last_beam_t_us = self.beam_t_us.copy()
        self.last_hit_geom = self.hit_geom.copy()
        self.pub = bus.advertise("scan", LaserScan)
        bus.advertise_service("start_motor", self.start_motor)
        bus.advertise_service("stop_motor", self.stop_motor)
        self.seq = 0
        self._handle = None
        self.running = False
        self._new_rotation(clock.now_us)
        if autostart:
            self.start_motor()

    # -- services ------------------------------------------------------------------
    def start_motor(self, request=None) -> None:
        """Start rotating: the first beam of a new scan is acquired now."""
        if not self.running:
            self.running = True
            self._new_rotation(self.clock.now_us)
            grid = self.cast_period_us
            self._handle = self.clock.schedule(-(-self.clock.now_us // grid) * grid, self._on_cast)

    def stop_motor(self, request=None) -> None:
        """Stop rotating; the scan in progress is discarded."""
        self.running = False
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    # -- scanning ------------------------------------------------------------------
    def _new_rotation(self, t0_us: int) -> None:
        self.t0_us = t0_us
        self.dist_m = np.full(self.n_beams, -1.0)
        self.hit_geom = np.full(self.n_beams, -1, np.int32)
        self.beam_t_us = t0_us + self.beam_dt_us * np.arange(self.n_beams, dtype=np.int64)
        self._next = 0  # first beam not cast yet

    def _on_cast(self) -> None:
        """Cast every beam acquired since the last cast; publish each completed rotation."""
        now = self.clock.now_us
        self._handle = self.clock.schedule(now + self.cast_period_us, self._on_cast)
        while True:
            stop = int(np.searchsorted(self.beam_t_us, now, side="right"))
            if stop > self._next:
                self.cast(self._next, stop)
                self._next = stop
            if self._next < self.n_beams:
                return
            self._publish()
            self._new_rotation(self.t0_us + self.scan_us)

    def cast(self, start: int, stop: int, at_own_instants: bool = True) -> None:
        """Cast beams ``start:stop`` with one ``mj_multiRay`` call.

        With ``at_own_instants`` each beam is cast from the laser pose at its own
        instant ``beam_t_us[i]`` (at or before now): the current site pose moved back
        along the site's velocity (first order in ``w * dt``: rotation of the
        direction about ``w``; translation of the origin, applied exactly for the
        plane of the surface hit through its normal). Otherwise all from the pose now.
        Stores the true distances (m, -1 for no hit) in :attr:`dist_m` and the hit
        geoms in :attr:`hit_geom`; noise is added for the whole rotation at its end.
        """
        m, d, s, k = self.model, self.data, self.site_id, stop - start
        rot = d.site_xmat[s].reshape(3, 3)
        local = self.local_dirs[start:stop]
        if at_own_instants:
            vel = self._vel
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, s, vel, 0)
            w = vel[:3]
            skew = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
            dt_s = (self.beam_t_us[start:stop] - self.clock.now_us) * 1e-6  # (k,) <= 0
            # u(t) = (I + dt [w]x) R u_local: the direction rotated back about w by w dt
            u = local @ rot.T + dt_s[:, None] * (local @ (skew @ rot).T)
            u /= np.sqrt((u * u).sum(axis=1))[:, None]
        else:
            u = local @ rot.T
        normal = self._normal[:3 * k]
        geomid, dist = self.hit_geom[start:stop], self.dist_m[start:stop]
        mujoco.mj_multiRay(m, d, d.site_xpos[s], u.ravel(), self.geomgroup, 1, -1,
                           geomid, dist, normal, k, CUTOFF_M)
        if at_own_instants:
            # origin moved by v dt: exact for the plane of the surface hit, n.(h - p) = r n.u
            n = normal.reshape(k, 3)
            nu = (n * u).sum(axis=1)
            ok = (geomid >= 0) & (np.abs(nu) > 1e-3)
            dist -= np.where(ok, dt_s * (n @ vel[3:]) / np.where(ok, nu, 1.0), 0.0)

    def noisy_ranges(self, dist: np.ndarray, geomid: np.ndarray) -> np.ndarray:
        """Range noise, 1/4 mm quantisation and validity of true distances.

        Parameters
        ----------
        dist : ndarray, shape (n,)
            True distances, m (any value where ``geomid < 0``).
        geomid : ndarray, shape (n,), int
            Geom hit by each beam, -1 for none.

        Returns
        -------
        ndarray, shape (n,), float32
            Ranges, m; inf where nothing was hit or out of ``[range_min, range_max]``.
        """
        cfg = self.cfg
        sigma = np.maximum(cfg.range_noise_floor_m, cfg.range_noise_frac * dist)
        r = dist + sigma * self.rng.standard_normal(len(dist))
        if cfg.range_resolution_m > 0:
            r = np.round(r / cfg.range_resolution_m) * cfg.range_resolution_m
        valid = (geomid >= 0) & (r >= cfg.range_min_m) & (r <= cfg.range_max_m)
        return np.where(valid, r, np.inf).astype(np.float32)

    def _publish(self) -> None:
        self.seq += 1
        self.last_scan = LaserScan(
            header=Header(self.seq, Time.from_us(self.t0_us), self.frame_id),
            angle_min=self.angle_min, angle_max=float(self.angles_rad[-1]),
            angle_increment=self.angle_increment, time_increment=self.beam_dt_us / US,
            scan_time=self.scan_us / US, range_min=self.cfg.range_min_m, range_max=self.cfg.range_max_m,
            ranges=self.noisy_ranges(self.dist_m, self.hit_geom), intensities=np.zeros(0, np.float32))
        self.last_beam_t_us, self.last_hit_geom = self.beam_t_us, self.hit_geom
        self.pub.publish(self.last_scan)

    def scan_now(self) -> np.ndarray:
        """Cast a whole rotation in one call from the current pose (no clock, no publish).

        Overwrites the rotation in progress; used by tests and benchmarks.

        Returns
        -------
        ndarray, shape (n_beams,), float32
            Noisy ranges, m, inf where invalid.
        """
        self.cast(0, self.n_beams, at_own_instants=False)
        return self.noisy_ranges(self.dist_m, self.hit_geom)
