"""``reset_simulation`` (the graph's ``~reset_simulation``) starts the robot's estimators afresh:
the wheel odometry forgets its wheel samples and commands, and the navigation stack's EKF is told
the robot is at its start pose. In-process: the service only calls
:meth:`amr_twin.assembly.twin.Twin.reset_simulation` at the pacer's tick."""

import math

import pytest

from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.assembly.command import Command

SPEED_M_S = 0.3
DRIVE_S = 5.0


@pytest.mark.parametrize("reset_at_s", [4.7, 6.1, 8.0])
def test_odometry_after_reset_simulation_follows_the_drive_that_follows(reset_at_s):
    """Driven, reset mid-revolution, driven 5 s again from rest: odom's x within 0.3 m of the
    distance driven (a wheel's revolution is 0.79 m; the old samples made it 2.2 to 4.7 m for 1.32 m
    driven)."""
    twin = Twin(load_config(), TwinOptions(world="empty"))
    Command("linear", speed_m_s=SPEED_M_S).send(twin)
    twin.advance(reset_at_s)
    twin.reset_simulation()
    assert math.hypot(twin.nodes["odometry"].x_m, twin.nodes["odometry"].y_m) < 1e-9
    twin.advance(0.5)
    Command("linear", speed_m_s=SPEED_M_S).send(twin)
    twin.advance(DRIVE_S)
    true_x = twin.observables.loop_sensors()[4] - twin.start_xy_yaw[0]
    assert true_x > 1.0, true_x
    assert abs(twin.nodes["odometry"].x_m - true_x) < 0.3, (twin.nodes["odometry"].x_m, true_x)


def test_ekf_after_reset_simulation_is_at_the_start_pose():
    """The navigation stack's EKF (odometry, gyro, UWB) had the robot 1.5 m on; reset, it has it at
    the start within 2 cm at once (UWB alone would take seconds to pull it back)."""
    from amr_twin.navigation.stack import true_map
    from amr_twin.ros1.navigation_setup import RunNavigation

    cfg = load_config()
    twin = Twin(cfg, TwinOptions(world="aisles", sensors=("imu", "lidar")))
    RunNavigation(cfg, true_map(cfg, "aisles")).attach(twin)
    twin.advance(2.0)
    Command("linear", speed_m_s=SPEED_M_S).send(twin)
    twin.advance(6.0)
    x0, y0, _ = twin.start_xy_yaw
    assert math.hypot(twin.ekf.state[0] - x0, twin.ekf.state[1] - y0) > 1.0
    twin.reset_simulation()
    twin.advance(0.2)
    assert math.hypot(twin.ekf.state[0] - x0, twin.ekf.state[1] - y0) < 0.02, twin.ekf.state
