"""Slamtec RPLIDAR A1 on the ``amr/laser`` site: rotating 2D scans cast in MuJoCo.

Reasons and measurements: docs/explanation/lidar.md#amr_twinsensorslidar.

Part of the physics layer (``PHYSICS_LAYER``): a sensor: casts its beams with ``mj_multiRay`` on
MjData at each laser pose."""

from __future__ import annotations

from collections import deque

import numpy as np

from amr_twin.ros.bus import Bus
from amr_twin.ros.tf_buffer import LASER_FRAME
from amr_twin.base.clock import VirtualClock
from amr_twin.model.config_sensors import LidarCfg
from amr_twin.ros.messages import Header, Time
from amr_twin.ros.sensor_messages import LaserScan

from amr_twin.sim.grid_steps import NEVER_BEFORE
from amr_twin.sensors.lidar_beams import (
    US,
    PoseSamples,
    beam_angles_rad,
    beam_directions,
    scan_timing,
)
from amr_twin.sensors.lidar_caster import BeamCaster
from amr_twin.sensors.lidar_kernels import beam_kernels

PHYSICS_LAYER = True


class Lidar:
    """RPLIDAR A1 scanning in a compiled twin on the shared clock.

    Parameters
    ----------
    physics : amr_twin.sim.physics.Physics
        The compiled twin, with a site ``<prefix>laser`` (its robot's; ``site`` names another)
    clock : VirtualClock
        Shared clock.
    bus : Bus
        Publishes ``scan``; serves ``start_motor`` and ``stop_motor``.
    cfg : LidarCfg
        ``lidar:`` section of the parameter file.
    seed : int or None
        Seed of the ``numpy.random.Generator`` drawing the range noise.
    group_us : int
        Standalone: period of the pose samples and casts, us (every multiple of
        it in absolute time).
    loop_cast_us : int
        In the twin: longest time between two casts, us.
    autostart : bool
        Start rotating (standalone) at the current clock time.
    native : bool
        Use the C helper for the beams' arithmetic when it builds
        (:mod:`amr_twin.sensors.lidar_kernels`; same bits as its Python twin);
        :attr:`engine` says which runs.
    """

    def __init__(
        self,
        physics,
        clock: VirtualClock,
        bus: Bus,
        cfg: LidarCfg,
        seed: int | None = 0,
        group_us: int = 20000,
        frame_id: str = LASER_FRAME,
        site: str | None = None,
        autostart: bool = True,
        loop_cast_us: int = 200000,
        native: bool = True,
    ):
        model, data = physics.model, physics.data
        if group_us <= 0 or loop_cast_us <= 0:
            raise ValueError(f"group_us {group_us}, loop_cast_us {loop_cast_us}: must be > 0")
        self.model, self.data, self.clock, self.bus, self.cfg = model, data, clock, bus, cfg
        self.frame_id = frame_id
        self.site_id = int(model.site(physics.prefix + "laser" if site is None else site).id)
        self.rng = np.random.default_rng(seed)
        self.n_beams, self.beam_dt_us, self.scan_us = scan_timing(cfg)
        self.angle_min, self.angle_increment, self.angles_rad = beam_angles_rad(self.n_beams)
        self.local_dirs = beam_directions(self.angles_rad)  # (n, 3) in the laser frame
        self._kernels = beam_kernels(self.n_beams, cfg, native)
        self.engine = self._kernels.engine
        """Which runs the beams' arithmetic: ``"C"`` or ``"Python (<why>)"``."""
        # negative (clockwise); float32 on the wire: the float32 next to -1/sample_rate toward 0, so
        # that stamp + i * time_increment never falls before the beam's true instant (by ~10 ns)
        self._time_increment = float(
            np.nextafter(np.float32(-self.beam_dt_us / US), np.float32(0.0))
        )
        self.group_us, self.loop_cast_us = int(group_us), int(loop_cast_us)
        self.cast_period_us = self.group_us  # pose sample period (the loop's grid in the twin)
        self.cast_every_us = self.group_us  # longest time between casts
        self._caster = BeamCaster(model, data, self.site_id, self.local_dirs, self._kernels)
        self._no_dist, self._no_hit = (
            np.full(self.n_beams, -1.0),
            np.full(self.n_beams, -1, np.int32),
        )
        self._beam_offsets_us = self.beam_dt_us * np.arange(
            self.n_beams - 1, -1, -1, dtype=np.int64
        )
        self.dist_m = np.full(self.n_beams, -1.0)
        """True distances of the rotation in progress, m (-1: no hit)."""
        self.hit_geom = np.full(self.n_beams, -1, np.int32)
        """Geom id hit by each beam of the rotation in progress (-1: none)."""
        self.beam_t_us = np.zeros(self.n_beams, np.int64)
        """Instant of each beam of the rotation in progress, us (t0 + (n - 1 - i) / sample_rate)."""
        self.last_scan: LaserScan | None = None
        self.last_beam_t_us = self.beam_t_us.copy()
        self.last_hit_geom = self.hit_geom.copy()
        self.pub = bus.advertise("scan", LaserScan)
        bus.advertise_service("start_motor", self.start_motor)
        bus.advertise_service("stop_motor", self.stop_motor)
        self.seq = 0
        self._handle = None
        self._samplers: list | None = None  # the loop's grid samplers (in the twin)
        self._grid: tuple[int, list] | None = None
        self._poses = PoseSamples(data, self.site_id, self.cast_period_us, self._after_pose, native)
        self._done: deque = deque()  # (t_us, scan, beam_t_us, hit_geom) cast, not yet published
        self.running = False
        self._new_rotation(clock.now_us)
        if autostart:
            self.start_motor()

    # -- services ------------------------------------------------------------------
    def start_motor(
        self, request=None, grid_us: int | None = None, samplers: list | None = None
    ) -> None:
        """Start rotating: the first beam of a new scan is acquired now.

        With ``grid_us`` and ``samplers`` (the simulation loop's record grid and
        its list of grid samplers, remembered for later service calls) the loop
        samples the pose; otherwise clock events every ``group_us`` do.
        """
        if grid_us is not None and samplers is not None:
            self._grid = (int(grid_us), samplers)
        if self.running:
            return
        self.running = True
        now = self.clock.now_us
        self._new_rotation(now)
        self._poses.clear()
        if self._grid is not None:  # pose samples on the multiples of the grid that are >= group_us
            grid, self._samplers = self._grid
            self.cast_period_us = -(-self.group_us // grid) * grid
            self.cast_every_us = self.loop_cast_us
            self._samplers.append(self._poses)
            self._handle = self.clock.schedule(
                self._publish_time_us(now), self._publish_next, publishes=("scan",)
            )
        else:
            self.cast_period_us = self.cast_every_us = self.group_us
            grid = self.group_us
            self._handle = self.clock.schedule(-(-now // grid) * grid, self._on_cast)
        self._poses.period_us = self.cast_period_us

    def stop_motor(self, request=None) -> None:
        """Stop rotating; the scan in progress and scans not yet published are discarded."""
        self.running = False
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None
        if self._samplers is not None:
            self._samplers.remove(self._poses)
            self._samplers = None
        self._done.clear()
        self._poses.due_us = NEVER_BEFORE  # not rotating: each sample runs the casts' bookkeeping

    # -- scanning ------------------------------------------------------------------
    def _new_rotation(self, t0_us: int) -> None:
        self.t0_us = t0_us
        self.dist_m = self._no_dist.copy()  # new arrays: the published scan keeps the last ones
        self.hit_geom = self._no_hit.copy()
        self.beam_t_us = self._beam_offsets_us + t0_us
        self._next = 0  # beams cast so far, in acquisition order (indices n - 1 down to n - _next)
        self._last_cast_us = t0_us
        self._last_beam_us = int(self.beam_t_us[0])
        self._next_cast_us = min(self._last_beam_us, t0_us + self.cast_every_us)
        self._poses.due_us = self._next_cast_us if self.running else NEVER_BEFORE

    def _on_cast(self) -> None:
        """Standalone clock event: sample the pose, cast, publish a completed rotation."""
        now = self.clock.now_us
        self._handle = self.clock.schedule(now + self.cast_period_us, self._on_cast)
        self.on_sample(now)

    def on_sample(self, t_us: int) -> None:
        """Keep the laser pose at ``t_us`` (``MjData`` is there) and cast the beams due.

        Casts when the rotation in progress is complete or ``cast_every_us``
        after the previous cast. Called by the loop on its record grid (twin) or
        by this sensor's clock events (standalone).
        """
        self._poses(t_us)  # the pose at the multiples of cast_period_us, then _after_pose if due

    def _after_pose(self, t_us: int) -> None:
        """A pose sample at ``t_us`` is kept and the casts are due (``t_us >= _next_cast_us``, or
        the motor stopped): cast the beams due, finish a complete rotation."""
        if t_us < self._next_cast_us and self.running:
            return
        cast = False
        while self.running:
            n = self.n_beams
            if self._last_beam_us <= t_us:
                self.cast(0, n - self._next)
                cast = True
                self._finish(t_us)
                self._new_rotation(self.t0_us + self.scan_us)
                self._last_cast_us = t_us
                continue
            if t_us - self._last_cast_us >= self.cast_every_us:
                due = min(n, max(0, (t_us - self.t0_us) // self.beam_dt_us + 1))  # acquired by t_us
                if due > self._next:
                    self.cast(n - due, n - self._next)
                    cast = True
                    self._next = due
                self._last_cast_us = t_us
            break
        self._next_cast_us = min(self._last_beam_us, self._last_cast_us + self.cast_every_us)
        self._poses.due_us = self._next_cast_us if self.running else NEVER_BEFORE
        if not self.running:
            self._poses.keep_last()
        elif cast:  # later beams only need the samples from the one before the first of them on
            self._poses.keep_from(int(self.beam_t_us[self.n_beams - 1 - self._next]))

    def cast(self, start: int, stop: int, at_own_instants: bool = True) -> None:
        """Cast beams ``start:stop`` (:meth:`BeamCaster.cast
        <amr_twin.sensors.lidar_caster.BeamCaster.cast>`: each at its own instant ``beam_t_us[i]``
        with ``at_own_instants``, else all from the pose now) into :attr:`dist_m` (m, -1 for no
        hit) and :attr:`hit_geom`; noise is added for the whole rotation at its end."""
        if stop - start <= 0:
            return
        geomid, dist = self.hit_geom[start:stop], self.dist_m[start:stop]
        self._caster.cast(start, stop, self.beam_t_us, self._poses, at_own_instants, geomid, dist)

    def noisy_ranges(self, dist: np.ndarray, geomid: np.ndarray) -> np.ndarray:
        """Noisy ranges (n,) float32, m, inf where invalid, of true distances ``dist`` (n,) and hit
        geoms ``geomid`` (n,), -1 for none (:func:`~amr_twin.sensors.lidar_beams.noisy_ranges` with
        this sensor's config and generator, in C when the helper is built)."""
        return self._kernels.noise(dist, geomid, self.rng.standard_normal(len(dist)))

    def _finish(self, t_us: int) -> None:
        """The rotation in progress is cast: add the noise and publish it (or queue it)."""
        self.seq += 1
        scan = LaserScan(
            header=Header(self.seq, Time.from_us(int(self.beam_t_us[0])), self.frame_id),
            angle_min=self.angle_min,
            angle_max=float(self.angles_rad[-1]),
            angle_increment=self.angle_increment,
            time_increment=self._time_increment,
            scan_time=self.scan_us / US,
            range_min=self.cfg.range_min_m,
            range_max=self.cfg.range_max_m,
            ranges=self.noisy_ranges(self.dist_m, self.hit_geom),
            intensities=np.zeros(0, np.float32),
        )
        if self._samplers is None:  # standalone: this is the clock event at t_us
            self._publish(scan, self.beam_t_us, self.hit_geom)
        else:
            self._done.append((t_us, scan, self.beam_t_us, self.hit_geom))

    def _publish_time_us(self, t0_us: int) -> int:
        """First pose sample at or after the last beam of the rotation started at ``t0_us``."""
        last = t0_us + self.scan_us - self.beam_dt_us
        return -(-last // self.cast_period_us) * self.cast_period_us

    def _publish_next(self) -> None:
        """Publishing event (twin): the rotation cast on the grid at this instant goes out."""
        now = self.clock.now_us
        if not self._done or self._done[0][0] != now:
            raise RuntimeError(f"LiDAR scan due at t_us={now} was not cast on the loop's grid")
        _t, scan, beam_t_us, hit_geom = self._done.popleft()
        t0 = beam_t_us[-1] + self.scan_us  # the next rotation starts one rotation after this one
        self._handle = self.clock.schedule(
            self._publish_time_us(t0), self._publish_next, publishes=("scan",)
        )
        self._publish(scan, beam_t_us, hit_geom)

    def _publish(self, scan: LaserScan, beam_t_us: np.ndarray, hit_geom: np.ndarray) -> None:
        self.last_scan, self.last_beam_t_us, self.last_hit_geom = scan, beam_t_us, hit_geom
        self.pub.publish(scan)

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
