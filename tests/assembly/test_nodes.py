"""The PC-side nodes by name: the odometry node on the nominal geometry, or on a calibration's."""

import pytest

from amr_twin import Twin, TwinOptions, load_config
from amr_twin.controllers.odometry_calibration import OdometryCalibration


@pytest.mark.parametrize("calibration", [None, OdometryCalibration(0.0505, 0.0497, 0.402)])
def test_the_odometry_node_takes_the_calibrated_geometry(calibration):
    cfg = load_config()
    twin = Twin(cfg, TwinOptions(world="empty", visuals=False, odometry_calibration=calibration))
    odometry = twin.nodes["odometry"]
    wheel = cfg.wheel
    want = (
        (wheel.radius_m, wheel.radius_m, wheel.separation_m)
        if calibration is None
        else (0.0505, 0.0497, 0.402)
    )
    got = (odometry.left_radius_m, odometry.right_radius_m, odometry.separation_m)
    assert got == pytest.approx(want, rel=1e-12)
    twin.client.angular(30.0, 0.0)
    twin.advance(1.0)
    assert odometry.yaw_rad != 0.0  # it integrates the wheels' speeds
