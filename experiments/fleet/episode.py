"""One episode of the fleet experiment: the fleet's vehicles on an embedded broker, the project's
fleet manager giving them a seeded order stream as the orders arrive, as fast as possible and in
lockstep (:mod:`.lockstep`), measured as it runs.

:func:`fleet_sessions` is the one place that builds the vehicles: today one twin (one physics,
:class:`~amr_twin.fleet.session.FleetSession`); the world of N robots in one physics plugs in
there. Everything else takes a list of sessions (``serial``, ``twin``, ``transport``, ``pacer``,
``adapter``, ``true_pose()``).
"""

from __future__ import annotations

import time

import numpy as np

from amr_twin.experiments.fleet import metrics
from amr_twin.experiments.fleet.lockstep import EPOCH, Lockstep, quiet
from amr_twin.experiments.fleet.orders import order_stream
from amr_twin.experiments.fleet.result import EpisodePoint, EpisodeResult, JobRecord, RobotRecord

ROBOTS_TODAY = 1
"""The fleet sizes :func:`fleet_sessions` builds today: 1 (one twin, one physics)."""
SAMPLE_TICKS = 5
"""Poses (distance driven, near misses, energy series) every this many 20 ms ticks."""
MOVING_M = 0.005
"""A robot that moved this far since the last sample (0.05 m/s) was driving: the energy drawn
meanwhile counts as driving energy."""
TRACK_TICKS = 25
"""A track point every this many ticks (0.5 s)."""


def supported(robots: int) -> None:
    """ValueError (one line) if :func:`fleet_sessions` cannot build ``robots`` vehicles yet."""
    if robots > ROBOTS_TODAY:
        raise ValueError(
            f"--robots {robots}: this build runs one robot a physics; the world of N robots plugs "
            "in at experiments/fleet/episode.py fleet_sessions()"
        )


def fleet_sessions(cfg, point: EpisodePoint) -> list:
    """The fleet's vehicles, amr-1..amr-N, on one embedded broker, as fast as possible (rate 0),
    stamped from :data:`~.lockstep.EPOCH`: the seam where the N-robot world plugs in. Each has
    ``serial``, ``url``, ``twin`` (its battery, collisions), ``transport``, ``pacer``, ``adapter``,
    ``true_pose()``, ``close()``; they share one clock, advanced by the first one's ``run``."""
    from amr_twin.fleet.session import FleetOptions, FleetSession

    supported(point.robots)
    options = FleetOptions(world=point.world, rate=0.0, seed=point.seed)
    return [FleetSession(cfg, options, serial="amr-1", epoch=EPOCH)]


class _Meter:
    """Per robot, at every tick: energy drawn (V I dt), charge drawn (from the state of charge),
    time charging; every :data:`SAMPLE_TICKS`: the true position, distance driven, near misses."""

    def __init__(self, sessions: list, capacity_ah: float, near_miss_m: float):
        self.sessions, self.capacity_as = sessions, capacity_ah * 3600.0
        self.ticks = 0
        self.energy_j = [0.0] * len(sessions)
        self.charging_s = [0.0] * len(sessions)
        self.soc0 = [s.twin.observables.battery()[2] for s in sessions]
        self.last_xy = [s.true_pose()[:2] for s in sessions]
        self.series: list[list] = [[] for _ in sessions]
        """Per robot: (t_s, energy_j, charge_as, distance_m, driving_j), cumulative."""
        self.driving_j = [0.0] * len(sessions)
        self.sampled_j = [0.0] * len(sessions)
        self.distance_m = [0.0] * len(sessions)
        self.tracks: list[list] = [[] for _ in sessions]
        self.near = metrics.NearMisses(near_miss_m)

    def tick(self, t_s: float, dt_s: float) -> None:
        self.ticks += 1
        sample = self.ticks % SAMPLE_TICKS == 0
        positions = {}
        for i, s in enumerate(self.sessions):
            volt, amp, soc = s.twin.observables.battery()
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


def run_episode(cfg, point: EpisodePoint) -> EpisodeResult:
    """Run ``point`` (module docstring) and measure it."""
    from amr_twin.fleet.protocol import INTERFACE
    from amr_twin.fleet_manager.dispatcher import ManagerOptions
    from amr_twin.fleet_manager.manager import start_manager

    wall0, cpu0 = time.perf_counter(), time.process_time()
    sessions = fleet_sessions(cfg, point)
    manager = None
    try:
        x, y, _yaw = sessions[0].true_pose()
        manager = start_manager(
            cfg,
            point.world,
            sessions[0].url,
            [s.serial for s in sessions],
            INTERFACE,
            0,
            point.seed,
            ManagerOptions(charge_below=point.charge_below),
            start_xy=(x, y),
        )
        orders = order_stream(
            manager.dispatcher.roadmap,
            point.payload_kg,
            point.jobs_per_hour,
            point.duration_s,
            point.seed,
            exclude=set(manager.dispatcher.options.charging_nodes),
        )
        meter = _Meter(sessions, cfg.battery.capacity_ah, point.near_miss_m)
        due = list(orders)
        tick_s = sessions[0].pacer.tick_us * 1e-6

        def on_tick(t_s: float) -> None:
            meter.tick(t_s, tick_s)
            arrived = []
            while due and due[0].arrival_s <= t_s:
                arrived.append(due.pop(0).job)
            if arrived:
                manager.submit(arrived)

        quiet(sessions, manager)
        lockstep = Lockstep(sessions, manager, on_tick)
        for pacer in {id(s.pacer): s.pacer for s in sessions}.values():
            pacer.sinks.append(lockstep)
        sessions[0].run(point.duration_s)
        summary = manager.summary()
    finally:
        if manager is not None:
            manager.close()
        for s in sessions:
            s.close()
    return _result(point, orders, summary, sessions, meter, wall0, cpu0)


def _result(point, orders, summary, sessions, meter, wall0, cpu0) -> EpisodeResult:
    events, end = summary["events"], point.duration_s
    serials = [s.serial for s in sessions]
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
    for i, s in enumerate(sessions):
        spans = metrics.busy_intervals(events, s.serial, end)
        busy = sum(b - a for a, b in spans)
        robots.append(
            RobotRecord(
                s.serial,
                round(busy, 3),
                round(metrics.utilisation(spans, end), 4),
                round(meter.charging_s[i], 3),
                round(meter.energy_j[i] / 3600, 4),
                [c.as_dict() for c in s.twin.observables.collisions],
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
