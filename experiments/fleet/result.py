"""The fleet experiment's typed results: one episode (a fleet size, a payload range, a seed) and
the sweep over them."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field


@dataclass(frozen=True)
class EpisodePoint:
    """One episode: ``robots`` vehicles on ``world`` for ``duration_s`` simulated seconds, orders
    arriving at ``jobs_per_hour`` with payloads uniform in ``payload_kg`` (kg), seed ``seed``;
    two robots' centres closer than ``near_miss_m`` are a near miss; the manager sends a vehicle
    to charge below ``charge_below`` % batteryCharge."""

    robots: int
    payload_kg: tuple[float, float]
    seed: int
    duration_s: float
    jobs_per_hour: float
    world: str = "warehouse"
    near_miss_m: float = 1.2
    charge_below: float = 20.0


@dataclass(frozen=True)
class JobRecord:
    """One order: arrival, assignment and drop finished (s; None: not reached), the robot, the
    payload (kg), and what its robot drew and drove from assignment to drop (Wh, A s, m; of the
    energy, ``driving_wh`` while it moved, the rest standing: handling, waiting, electronics)."""

    job_id: str
    payload_kg: float
    arrival_s: float
    robot: str | None = None
    assigned_s: float | None = None
    done_s: float | None = None
    failed: bool = False
    energy_wh: float | None = None
    charge_as: float | None = None
    distance_m: float | None = None
    driving_wh: float | None = None


@dataclass(frozen=True)
class RobotRecord:
    """One robot: time on orders (s) and its share, time charging (s), energy drawn (Wh), its
    collisions (the physics' monitor, as dicts) and its true track ``[t_s, x_m, y_m]``."""

    serial: str
    busy_s: float
    utilisation: float
    charging_s: float
    energy_wh: float
    collisions: list[dict]
    track: list[list[float]]


@dataclass(frozen=True)
class EpisodeResult:
    """What one episode measured: per order and per robot, with the fleet's figures."""

    point: EpisodePoint
    jobs: list[JobRecord]
    robots: list[RobotRecord]
    orders_per_hour: float
    lead_time_p50_s: float | None
    lead_time_p95_s: float | None
    energy_per_order_wh: float | None
    deadlocks: int
    collisions: int
    near_misses: list[dict]
    least_distance_m: float | None
    wall_s: float = field(default=0.0, compare=False)
    cpu_s: float = field(default=0.0, compare=False)

    def as_json(self) -> dict:
        """JSON-ready (times s, energies Wh, distances m)."""
        return asdict(self)
