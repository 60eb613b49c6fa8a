"""Sensor noise measured from both sides against the datasheets (not against amr.yaml): a
sensor with zero or doubled noise fails, as one whose noise is too large does.

Expected figures, by hand:
- L3GD20 gyro: rate noise density 0.03 dps/sqrt(Hz) (datasheet), white over the 50 Hz
  Nyquist band of 100 Hz samples: sigma = 0.03 * sqrt(100) = 0.3 dps = 5.2 mrad/s.
- LSM303DLHC accelerometer: 220 ug/sqrt(Hz) (the LIS3DH figure amr.yaml adopts): sigma =
  2.2 mg = 0.0216 m/s^2, plus the 1 mg quantum (sigma 0.0028 m/s^2).
- RPLIDAR A1: resolution < 1 % of the distance, taken as 2 sigma: 15 mm at 3 m.
- DWM1000: 10 cm location accuracy taken as 2 sigma of a range: 5 cm.
"""

import math

import numpy as np
import pytest

from amr_twin.model.config import load_config

GYRO_SIGMA_RAD_S = math.radians(0.03) * math.sqrt(100.0)
ACCEL_SIGMA_M_S2 = math.hypot(220e-6 * 9.80665 * math.sqrt(100.0), 0.00980665 / math.sqrt(12))
LIDAR_SIGMA_AT_3_M = 0.015
UWB_SIGMA_M = 0.05


@pytest.fixture(scope="module")
def imu_at_rest():
    """Three seconds of the IMU on the settled robot (shipped parameters, three seeds)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parents[1]))
    from test_imu import Rig

    out = []
    for seed in (0, 1, 2):
        rig = Rig(seed=seed)
        rig.run(3.0)
        out.append((rig.gyro(), rig.accel()))
    return out


def test_gyro_noise_is_the_datasheets(imu_at_rest):
    for gyro, _ in imu_at_rest:
        sigma = gyro.std(axis=0)  # the bias is constant over 3 s
        assert np.all((0.8 * GYRO_SIGMA_RAD_S < sigma) & (sigma < 1.25 * GYRO_SIGMA_RAD_S)), sigma


def test_accelerometer_noise_is_the_datasheets(imu_at_rest):
    for _, accel in imu_at_rest:
        sigma = accel.std(axis=0)
        assert np.all((0.8 * ACCEL_SIGMA_M_S2 < sigma) & (sigma < 1.25 * ACCEL_SIGMA_M_S2)), sigma


def test_lidar_range_noise_is_the_datasheets():
    from amr_twin.sensors.lidar_beams import noisy_ranges

    cfg = load_config().lidar
    true = np.full(20000, 3.0)
    for seed in range(3):
        err = noisy_ranges(true, np.zeros(20000, np.int32), cfg, np.random.default_rng(seed)) - true
        assert abs(err.mean()) < 0.1 * LIDAR_SIGMA_AT_3_M
        assert 0.85 * LIDAR_SIGMA_AT_3_M < err.std() < 1.15 * LIDAR_SIGMA_AT_3_M


def test_uwb_range_noise_is_the_datasheets():
    from amr_twin.sensors.uwb_errors import corrupt_ranges

    data = load_config().uwb.model_dump()
    data.update(nlos_prob=0.0, dropout_prob=0.0)  # the line-of-sight noise alone
    cfg = type(load_config().uwb).model_validate(data)
    true = np.full(20000, 8.0)
    for seed in range(3):
        err = corrupt_ranges(true, cfg, np.random.default_rng(seed))[0] - true
        assert 0.9 * UWB_SIGMA_M < err.std() < 1.1 * UWB_SIGMA_M
