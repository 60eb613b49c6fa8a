"""An episode's measures assembled for made-up fleets of 2-4 vehicles (no physics): per robot
energy, charging, time on orders, per order energy and distance, near misses between robots."""

from types import SimpleNamespace

import pytest

from amr_twin.experiments.fleet.episode import SAMPLE_TICKS, _Meter, _result
from amr_twin.experiments.fleet.orders import Order
from amr_twin.experiments.fleet.result import EpisodePoint
from amr_twin.fleet_manager.jobs import Job


class _Vehicle:
    """A vehicle at ``y_m`` driving along x at ``speed`` m/s, drawing ``amps`` at 40 V."""

    def __init__(self, serial, y_m, speed, amps, charging=False):
        self.serial, self.y_m, self.speed, self.t_s = serial, y_m, speed, 0.0
        battery = SimpleNamespace(battery=lambda: (40.0, amps, 1.0 - amps * self.t_s / 72000))
        self.robot = SimpleNamespace(
            observables=SimpleNamespace(battery=battery.battery, collisions=[])
        )
        self.adapter = SimpleNamespace(handling=SimpleNamespace(charging=charging))

    def true_pose(self):
        return (self.speed * self.t_s, self.y_m, 0.0)


def _run(vehicles, seconds):
    meter = _Meter(vehicles, 20.0, 1.2)
    for k in range(1, int(round(seconds / 0.02)) + 1):
        for v in vehicles:
            v.t_s = k * 0.02
        meter.tick(k * 0.02, 0.02)
    return meter


@pytest.mark.parametrize("n", [2, 3, 4])
def test_per_robot_measures_of_a_made_up_fleet(n):
    vehicles = [_Vehicle(f"amr-{i + 1}", 3.0 * i, 0.5, 1.0 + i) for i in range(n)]
    vehicles[-1].adapter.handling.charging = True
    vehicles[1].y_m = 1.0  # amr-2 drives 1 m beside amr-1: a near miss all along
    meter = _run(vehicles, 20.0)
    orders = [Order(Job(f"job-{i + 1}", "n1", "n2", 10.0 * i), 1.0) for i in range(n)]
    events = [
        e
        for i in range(n)
        for e in (
            {
                "t_s": 2.0,
                "event": "assigned",
                "vehicle": f"amr-{i + 1}",
                "task": "job",
                "job": f"job-{i + 1}",
            },
            {
                "t_s": 12.0 + i,
                "event": "done",
                "vehicle": f"amr-{i + 1}",
                "task": "job",
                "job": f"job-{i + 1}",
            },
        )
    ]
    detour = {"t_s": 6.0, "event": "assigned", "vehicle": "amr-1", "task": "job", "job": "job-1"}
    events.insert(1, detour)  # a new way round a deadlock: the order still began at 2 s
    point = EpisodePoint(n, (0.0, 30.0), 0, 20.0, 300.0)
    r = _result(point, orders, {"events": events, "deadlocks": []}, vehicles, meter, 0.0, 0.0)
    assert [x.serial for x in r.robots] == [f"amr-{i + 1}" for i in range(n)]
    assert [x.utilisation for x in r.robots] == [(10 + i) / 20 for i in range(n)]
    assert [x.charging_s for x in r.robots] == pytest.approx([0.0] * (n - 1) + [20.0])
    assert [x.energy_wh for x in r.robots] == pytest.approx(
        [40 * (1 + i) * 20 / 3600 for i in range(n)], abs=1e-4
    )
    for i, job in enumerate(r.jobs):
        assert job.robot == f"amr-{i + 1}" and job.done_s - job.arrival_s == 11.0 + i
        assert job.energy_wh == pytest.approx(40 * (1 + i) * (10 + i) / 3600, abs=1e-4)
        assert job.charge_as == pytest.approx((1 + i) * (10 + i), rel=1e-3)
        assert job.distance_m == pytest.approx(0.5 * (10 + i)) and job.driving_wh == pytest.approx(
            job.energy_wh
        )
    assert r.orders_per_hour == n * 180.0 and r.lead_time_p50_s == pytest.approx(11.0 + (n - 1) / 2)
    assert [e["robots"] for e in r.near_misses] == [["amr-1", "amr-2"]]
    assert r.near_misses[0]["least_m"] == 1.0 and r.least_distance_m == 1.0
    assert len(r.robots[0].track) == 20 / 0.5 and SAMPLE_TICKS == 5
