"""One episode of the fleet experiment: a world of N robots (one physics: they see and can hit
each other), each a VDA 5050 vehicle on an embedded broker, the project's fleet manager giving them
a seeded order stream as the orders arrive, as fast as possible and in lockstep
(:mod:`.lockstep`), measured as it runs.

:func:`fleet_session` builds the world: one :class:`~amr_twin.fleet.session.FleetSession` whose
robots start on rack-face nodes of the manager's roadmap (:mod:`.starts`). Everything else takes
its ``vehicles`` (:class:`~amr_twin.fleet.served_robot.ServedRobot`: ``serial``, ``robot``,
``transport``, ``adapter``, ``true_pose()``).
"""

from __future__ import annotations

import time

import numpy as np

from amr_twin.experiments.fleet import metrics
from amr_twin.experiments.fleet.lockstep import EPOCH, Lockstep, quiet
from amr_twin.experiments.fleet.orders import order_stream
from amr_twin.experiments.fleet.result import EpisodePoint, EpisodeResult, JobRecord, RobotRecord

SAMPLE_TICKS = 5
"""Poses (distance driven, near misses, energy series) every this many 20 ms ticks."""
MOVING_M = 0.005
"""A robot that moved this far since the last sample (0.05 m/s) was driving: the energy drawn
meanwhile counts as driving energy."""
TRACK_TICKS = 25
"""A track point every this many ticks (0.5 s)."""


def fleet_session(cfg, point: EpisodePoint, roadmap, visuals: bool = False):
    """The world of ``point.robots`` robots, amr-1..amr-N, on one embedded broker, as fast as
    possible (rate 0), stamped from :data:`~.lockstep.EPOCH`; robot i at the i-th start of
    :func:`~.starts.start_poses` about the world's start on ``roadmap`` (``visuals``: a lone
    robot drawn, for a recording)."""
    from amr_twin.experiments.fleet.starts import start_poses
    from amr_twin.fleet.session import FleetOptions, FleetSession
    from amr_twin.model.worlds import default_start

    starts = start_poses(
        roadmap,
        default_start(point.world)[:2],
        point.robots,
        cfg.chassis.length_m / 2,
        cfg.half_width_m,
    )
    options = FleetOptions(
        world=point.world, starts=starts, rate=0.0, seed=point.seed, visuals=visuals
    )
    return FleetSession(cfg, options, epoch=EPOCH)


class _Meter:
    """Per robot, at every tick: energy drawn (V I dt), charge drawn (from the state of charge),
    time charging; every :data:`SAMPLE_TICKS`: the true position, distance driven, near misses."""

    def __init__(self, vehicles: list, capacity_ah: float, near_miss_m: float):
        self.vehicles, self.capacity_as = vehicles, capacity_ah * 3600.0
        self.ticks = 0
        self.energy_j = [0.0] * len(vehicles)
        self.charging_s = [0.0] * len(vehicles)
        self.soc0 = [s.robot.observables.battery()[2] for s in vehicles]
        self.last_xy = [s.true_pose()[:2] for s in vehicles]
        self.series: list[list] = [[] for _ in vehicles]
        """Per robot: (t_s, energy_j, charge_as, distance_m, driving_j), cumulative."""
        self.driving_j = [0.0] * len(vehicles)
        self.sampled_j = [0.0] * len(vehicles)
        self.distance_m = [0.0] * len(vehicles)
        self.tracks: list[list] = [[] for _ in vehicles]
        self.near = metrics.NearMisses(near_miss_m)

    def tick(self, t_s: float, dt_s: float) -> None:
        self.ticks += 1
        sample = self.ticks % SAMPLE_TICKS == 0
        positions = {}
        for i, s in enumerate(self.vehicles):
            volt, amp, soc = s.robot.observables.battery()
            self.energy_j[i] += volt * amp * dt_s
            self.charging_s[i] += dt_s if s.adapter.handling.charging else 0.0
            if not sample:
                continue
            x, y, _yaw = s.true_pose()
            step = float(np.hypot(x - self.last_xy[i][0], y - self.last_xy[i][1]))
            self.distance_m[i] += step
            if step >= MOVING_M:
                self.driving_j[i] += self.energy_j[i] - self.sampled_j[i]
            self.sampled_j[i] = self.energy_j[i]
            self.last_xy[i] = (x, y)
            positions[s.serial] = (x, y)
            charge = (self.soc0[i] - soc) * self.capacity_as
            self.series[i].append(
                (t_s, self.energy_j[i], charge, self.distance_m[i], self.driving_j[i])
            )
            if self.ticks % TRACK_TICKS == 0:
                self.tracks[i].append([t_s, round(x, 3), round(y, 3)])
        if sample:
            self.near.update(t_s, positions)


def run_episode(cfg, point: EpisodePoint, record=None) -> EpisodeResult:
    """Run ``point`` (module docstring) and measure it. Orders that arrive before the manager has
    placed every vehicle on its roadmap wait until it has (their lead time counts from arrival).
    ``record``: a folder for the episode's ``.mcap`` and ``.rrd``
    (:mod:`amr_twin.recording.fleet_recording`), None: none."""
    from amr_twin.fleet.protocol import INTERFACE
    from amr_twin.fleet_manager.dispatcher import ManagerOptions
    from amr_twin.fleet_manager.manager import start_manager
    from amr_twin.fleet_manager.roadmap import world_roadmap
    from amr_twin.model.worlds import default_start

    wall0, cpu0 = time.perf_counter(), time.process_time()
    session = fleet_session(cfg, point, world_roadmap(cfg, point.world), record is not None)
    captures = None
    if record is not None:
        from amr_twin.recording.fleet_capture import attach_fleet

        captures = attach_fleet(session.world, names=session.serials)
    vehicles = session.vehicles
    manager = None
    try:
        manager = start_manager(
            cfg,
            point.world,
            session.url,
            [v.serial for v in vehicles],
            INTERFACE,
            0,
            point.seed,
            ManagerOptions(charge_below=point.charge_below),
            start_xy=default_start(point.world)[:2],
        )
        orders = order_stream(
            manager.dispatcher.roadmap,
            point.payload_kg,
            point.jobs_per_hour,
            point.duration_s,
            point.seed,
            exclude=set(manager.dispatcher.options.charging_nodes),
        )
        meter = _Meter(vehicles, cfg.battery.capacity_ah, point.near_miss_m)
        due = list(orders)
        tick_s = session.pacer.tick_us * 1e-6
        placed = manager.dispatcher.vehicles, []

        def on_tick(t_s: float) -> None:
            meter.tick(t_s, tick_s)
            if not placed[1]:
                known = placed[0]
                if not all(v.serial in known and known[v.serial].node for v in vehicles):
                    return
                placed[1].append(t_s)
            arrived = []
            while due and due[0].arrival_s <= t_s:
                arrived.append(due.pop(0).job)
            if arrived:
                manager.submit(arrived)

        quiet(vehicles, manager)
        lockstep = Lockstep(vehicles, manager, on_tick)
        session.pacer.sinks.append(lockstep)
        session.run(point.duration_s)
        summary = manager.summary()
    finally:
        if manager is not None:
            manager.close()
        session.close()
    if captures is not None:
        from amr_twin.recording.fleet_recording import episode_stem, write_fleet_recordings

        stem = episode_stem(point.robots, point.payload_kg, point.seed)
        write_fleet_recordings(captures, record, stem, cfg)
    return _result(point, orders, summary, vehicles, meter, wall0, cpu0)


def _result(point, orders, summary, vehicles, meter, wall0, cpu0) -> EpisodeResult:
    events, end = summary["events"], point.duration_s
    serials = [s.serial for s in vehicles]
    series = {s: np.array(meter.series[i]).reshape(-1, 5) for i, s in enumerate(serials)}
    seen: dict[str, dict] = {o.job.job_id: {} for o in orders}
    for e in events:
        job = e.get("job")
        if job in seen and e["event"] == "assigned" and "assigned_s" not in seen[job]:
            seen[job].update(robot=e["vehicle"], assigned_s=e["t_s"])  # not a later detour
        elif job in seen and e["event"] in ("done", "failed"):
            seen[job].update(done_s=e["t_s"], failed=e["event"] == "failed")
    jobs = []
    for o in orders:
        rec = seen[o.job.job_id]
        done = rec.get("done_s") if not rec.get("failed") else None
        drawn = {}
        if done is not None and len(series[rec["robot"]]):
            arr = series[rec["robot"]]
            a = rec["assigned_s"]
            drawn = dict(
                energy_wh=round(metrics.energy_between(arr[:, 0], arr[:, 1], a, done) / 3600, 4),
                charge_as=round(metrics.energy_between(arr[:, 0], arr[:, 2], a, done), 3),
                distance_m=round(metrics.energy_between(arr[:, 0], arr[:, 3], a, done), 3),
                driving_wh=round(metrics.energy_between(arr[:, 0], arr[:, 4], a, done) / 3600, 4),
            )
        jobs.append(JobRecord(o.job.job_id, o.job.payload_kg, o.arrival_s, **{**rec, **drawn}))
    done_jobs = [j for j in jobs if j.done_s is not None and not j.failed]
    robots = []
    for i, s in enumerate(vehicles):
        spans = metrics.busy_intervals(events, s.serial, end)
        busy = sum(b - a for a, b in spans)
        robots.append(
            RobotRecord(
                s.serial,
                round(busy, 3),
                round(metrics.utilisation(spans, end), 4),
                round(meter.charging_s[i], 3),
                round(meter.energy_j[i] / 3600, 4),
                [c.as_dict() for c in s.robot.observables.collisions],
                meter.tracks[i],
            )
        )
    p50, p95 = metrics.percentiles([j.done_s - j.arrival_s for j in done_jobs])
    energy = metrics.percentiles([j.energy_wh for j in done_jobs], (50,))[0]
    return EpisodeResult(
        point,
        jobs,
        robots,
        round(len(done_jobs) * 3600.0 / end, 3),
        None if p50 is None else round(p50, 3),
        None if p95 is None else round(p95, 3),
        None if energy is None else round(energy, 4),
        len(summary["deadlocks"]),
        sum(len(r.collisions) for r in robots),
        [{**e, "least_m": round(e["least_m"], 3)} for e in meter.near.episodes],
        None if meter.near.least_m is None else round(meter.near.least_m, 3),
        round(time.perf_counter() - wall0, 3),
        round(time.process_time() - cpu0, 3),
    )
