"""Open-loop driving through the plant: straightness, turning in place, robustness."""

import math

import numpy as np
import pytest

from amr_twin.model.build import build
from amr_twin.model.config import load_config
from amr_twin.sim.physics import DivergenceError, Physics
from amr_twin.base.pins import HIGH, LOW, DriverPins
from amr_twin.sim.plant import Plant

# the shipped right motor differs from the left (calibrated, §5.1.3); make them identical
IDENTICAL = [
    f"motor_right.{key}={value}" for key, value in load_config().motor_left.model_dump().items()
] + [f"driver_right.gain={load_config().driver_left.gain}"]


def plant_of(cfg, physics) -> Plant:
    """The plant of ``cfg``'s drivers, motors and battery on ``physics``."""
    return Plant(
        physics,
        cfg.driver,
        (cfg.driver_left, cfg.driver_right),
        (cfg.motor_left, cfg.motor_right),
        cfg.battery,
    )


def _robot(sets=(), payload_kg=0.0):
    cfg = load_config(sets=[*sets, f"payload.mass_kg={payload_kg}"])
    physics = Physics(build(cfg, world="empty").model)
    physics.settle(0.5)
    return cfg, physics, plant_of(cfg, physics)


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
    """60 s of random duty, direction, brake and coast: no warning, no NaN. (With 50 kg the
    robot may go over: full duty on one wheel spins it about the other at 6 rad/s, 8 m/s^2
    at its centre of mass, more than the 6 m/s^2 its wheel track holds; that is physics.)"""
    _, physics, plant = _robot(payload_kg=payload_kg)
    rng = np.random.default_rng(7)
    for _ in range(120):  # a new command every 0.5 s
        pins = []
        for _w in range(2):
            kind = rng.choice(["drive", "drive", "brake", "coast"])
            pins.append(
                DriverPins(
                    int(rng.integers(0, 256)),
                    int(rng.integers(0, 2)),
                    HIGH if kind == "brake" else LOW,
                    LOW if kind == "coast" else HIGH,
                )
            )
        plant.apply(tuple(pins))
        physics.step(500)
        physics.check()  # raises DivergenceError on NaN or any MuJoCo warning
    assert math.isfinite(plant.battery.soc)


def test_brake_is_the_shorted_motor():
    """BRAKE shorts the phases: torque -Kt Ke / R * omega (no driver current limit below
    ~230 RPM), on a free wheel of the work station (fig. 5.1); coasting has no torque."""
    cfg = load_config()
    physics = Physics(build(cfg, world="stand").model)
    plant = plant_of(cfg, physics)
    plant.apply((DriverPins(25, HIGH, LOW, HIGH), DriverPins(25, HIGH, LOW, HIGH)))
    physics.step(1500)
    w0 = physics.wheel_speeds_rad_s().copy()
    assert (
        10.0 < w0.min() and w0.max() < 20.0
    )  # spinning (rad/s), the short-circuit current under 40 A
    plant.apply(
        (DriverPins(0, HIGH, HIGH, HIGH), DriverPins(0, HIGH, LOW, LOW))
    )  # left brake, right coast
    w = physics.wheel_speeds_rad_s().copy()
    physics.step(1)  # the actuator torque of this step is computed from the speeds before it
    torque = physics.data.actuator_force
    m = cfg.motor_left
    assert torque[0] == pytest.approx(-(m.ke_v_s_rad**2) / m.resistance_ohm * w[0], rel=0.01)
    assert torque[1] == 0.0
    w = physics.wheel_speeds_rad_s()
    assert plant.motor_currents_a()[0] == pytest.approx(
        -m.ke_v_s_rad * w[0] / m.resistance_ohm, rel=1e-9
    )
    physics.step(100)
    w = physics.wheel_speeds_rad_s()
    assert (
        w[0] < 0.05 * w0[0]
    )  # the shorted motor stops its free wheel (time constant J R / Ke^2 ~ 20 ms)
    assert w[1] > 0.6 * w0[1]  # the coasting one runs on, slowed by its own friction only


def test_hard_stop_keeps_every_support_on_the_floor():
    """The end of the fusion route: 0.41 m/s, then both wheels braked. The
    shorted motors decelerate the robot at about 1 m/s^2: no wheel or caster lifts."""
    cfg, physics, plant = _robot()
    drive = DriverPins(7, HIGH, LOW, HIGH)  # about 0.4 m/s
    plant.apply((drive, drive))
    physics.step(4000)
    v0 = physics.base_velocity()[0]
    assert 0.25 < v0 < 0.7
    brake = DriverPins(0, HIGH, HIGH, HIGH)
    plant.apply((brake, brake))
    lowest, tilt = np.inf, 0.0
    for _ in range(1000):
        physics.step(1)
        lowest = min(lowest, physics.support.normal_forces_n().min())
        tilt = max(tilt, physics.base_tilt_rad())
    # the shorted motors' torque fades with the speed: an exponential stop, time constant
    # (m + 2 J / r^2) / ((Ke_l^2 + Ke_r^2) / (R r^2)) (about 0.37 s; friction helps a little)
    r, j = cfg.wheel.radius_m, physics.model.body("amr/wheel_left_link").inertia[1]
    ke2_over_r = sum(m.ke_v_s_rad**2 / m.resistance_ohm for m in (cfg.motor_left, cfg.motor_right))
    tau = (physics.robot_mass_kg() + 2 * j / r**2) * r**2 / ke2_over_r
    assert (
        0.5 * math.exp(-1.0 / tau) * v0
        < abs(physics.base_velocity()[0])
        < 1.1 * math.exp(-1.0 / tau) * v0
    )
    assert lowest > 5.0
    assert tilt < math.radians(0.5)


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
