"""Open-loop driving through the plant: straightness, turning in place, robustness."""

import math

import numpy as np
import pytest

from amr_twin.build import build
from amr_twin.config import load_config
from amr_twin.physics import DivergenceError, Physics
from amr_twin.pins import HIGH, LOW, DriverPins
from amr_twin.plant import Plant

# the shipped right motor differs from the left (calibrated, §5.1.3); make them identical
IDENTICAL = [f"motor_right.{key}={value}" for key, value in load_config().motor_left.model_dump().items()]


def _robot(sets=(), payload_kg=0.0):
    cfg = load_config(sets=[*sets, f"payload.mass_kg={payload_kg}"])
    physics = Physics(build(cfg, world="empty").model)
    physics.settle(0.5)
    return cfg, physics, Plant(cfg, physics)


def test_equal_duty_drives_straight():
    """10 s at equal duty, identical motors: lateral drift under 1 cm."""
    _, physics, plant = _robot(IDENTICAL)
    start = physics.pose()
    plant.apply((DriverPins(20, HIGH, LOW, HIGH), DriverPins(20, HIGH, LOW, HIGH)))
    physics.step(10_000)
    physics.check()
    end = physics.pose()
    dx, dy = end.x_m - start.x_m, end.y_m - start.y_m
    heading = start.yaw_rad
    lateral = -math.sin(heading) * dx + math.cos(heading) * dy
    along = math.cos(heading) * dx + math.sin(heading) * dy
    assert along > 5.0  # it did drive (about 0.7 m/s)
    assert abs(lateral) < 0.01


def test_spin_in_place_matches_wheel_kinematics():
    """Opposite duty: yaw rate within 2 % of (v_r - v_l) / L from the wheel speeds."""
    cfg, physics, plant = _robot(IDENTICAL)
    plant.apply((DriverPins(20, LOW, LOW, HIGH), DriverPins(20, HIGH, LOW, HIGH)))
    physics.step(3000)  # spin up
    rates, expected = [], []
    r, L = cfg.wheel.radius_m, cfg.wheel.separation_m
    for _ in range(200):
        physics.step(10)
        w = physics.wheel_speeds_rad_s()
        expected.append((w[1] - w[0]) * r / L)
        rates.append(physics.base_velocity()[5])
    physics.check()
    assert np.mean(expected) > 1.0  # really turning (rad/s)
    assert np.mean(rates) == pytest.approx(np.mean(expected), rel=0.02)


@pytest.mark.parametrize("payload_kg", [0.0, 50.0])
def test_random_duty_brake_coast_is_stable(payload_kg):
    """60 s of random duty, direction, brake and coast: no warning, no NaN."""
    _, physics, plant = _robot(payload_kg=payload_kg)
    rng = np.random.default_rng(7)
    for _ in range(120):  # a new command every 0.5 s
        pins = []
        for _w in range(2):
            kind = rng.choice(["drive", "drive", "brake", "coast"])
            pins.append(DriverPins(int(rng.integers(0, 256)), int(rng.integers(0, 2)),
                                   HIGH if kind == "brake" else LOW, LOW if kind == "coast" else HIGH))
        plant.apply(tuple(pins))
        physics.step(500)
        physics.check()  # raises DivergenceError on NaN or any MuJoCo warning
    assert physics.base_tilt_rad() < math.radians(30)
    assert math.isfinite(plant.battery.soc)


def test_brake_holds_and_coast_rolls():
    _, physics, plant = _robot()
    drive = DriverPins(40, HIGH, LOW, HIGH)
    plant.apply((drive, drive))
    physics.step(2000)
    plant.apply((DriverPins(0, HIGH, HIGH, HIGH), DriverPins(0, HIGH, LOW, LOW)))  # left brake, right coast
    tilt = 0.0
    for _ in range(30):
        physics.step(10)
        tilt = max(tilt, physics.base_tilt_rad())
    w = physics.wheel_speeds_rad_s()
    assert abs(w[0]) < 0.05 * abs(w[1])
    assert tilt < math.radians(3.0)  # a hard one-wheel stop does not pitch the chassis over


def test_estop_cuts_both_motors():
    _, physics, plant = _robot()
    drive = (DriverPins(60, HIGH, LOW, HIGH), DriverPins(60, HIGH, LOW, HIGH))
    plant.apply(drive)
    physics.step(1500)
    plant.set_estop(True, drive)
    assert plant.mode == ["coast", "coast"]
    assert plant.motor_currents_a() == [0.0, 0.0]


def test_divergence_is_reported_with_sim_time():
    _, physics, _ = _robot()
    physics.data.qvel[0] = float("nan")
    with pytest.raises(DivergenceError, match=r"t = \d+\.\d+ s"):
        physics.check()


def test_a_mujoco_warning_is_reported_by_name():
    import mujoco

    _, physics, _ = _robot()
    physics.check()  # a settled robot: no warning
    physics.data.warning[int(mujoco.mjtWarning.mjWARN_BADQACC)].number = 1
    with pytest.raises(DivergenceError, match="mjWARN_BADQACC"):
        physics.check()
