"""Parameter file, chapter 6 sections (uwb, ekf, lidar_odometry, mapping): values and one-line
errors."""

import numpy as np
import pytest

from amr_twin.model.config import ConfigError, load_config


def test_fusion_sections_loaded():
    cfg = load_config()
    assert cfg.uwb.rate_hz == 10.0 and cfg.uwb.anchors_xy_m.shape == (4, 2)
    assert np.array_equal(cfg.uwb.anchors_xy_m[:, 0], cfg.uwb.anchors_x_m)
    assert cfg.ekf.imu_rest_calibration_s > 0 and cfg.ekf.mahalanobis_gate > 0
    assert cfg.lidar_odometry.voxel_size_m == 0.15 and cfg.lidar_odometry.deskew is True
    assert cfg.mapping.resolution_m == 0.05


@pytest.mark.parametrize(
    "sets, field, words",
    [
        (["uwb.dropout_prob=1.5"], "uwb.dropout_prob", "[0.0, 0.9]"),
        (
            ["uwb.anchors_y_m=[1.0, 2.0]"],
            "uwb",
            "anchors_y_m: must have as many values as anchors_x_m",
        ),
        (["uwb.anchors_x_m=[1.0, 2.0]", "uwb.anchors_y_m=[1.0, 2.0]"], "uwb", "allowed [3, 16]"),
        (["uwb.anchors_x_m=[1.0, 2.0, 3000.0, 4.0]"], "uwb.anchors_x_m", "1000.0"),
        (["ekf.mahalanobis_gate=0"], "ekf.mahalanobis_gate", "out of range"),
        (["ekf.odom_w_sigma_rad_s=-0.1"], "ekf.odom_w_sigma_rad_s", "rad/s"),
        (["ekf.gyro_sigma=1"], "ekf.gyro_sigma", "is not a parameter"),
        (
            ["lidar_odometry.min_range_m=4.0", "lidar_odometry.max_range_m=3.0"],
            "lidar_odometry",
            "min_range_m: must be less than max_range_m",
        ),
        (["mapping.resolution_m=0"], "mapping.resolution_m", "[0.01, 1.0] m"),
    ],
)
def test_bad_fusion_values_give_one_line_naming_the_field(sets, field, words):
    with pytest.raises(ConfigError) as info:
        load_config(sets=sets)
    message = str(info.value)
    assert "\n" not in message
    assert (
        message.startswith("--set '") and field in message.split("': ", 1)[1]
    )  # the option that gave it, the field
    assert words in message
