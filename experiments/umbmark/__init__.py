"""UMBmark: squares driven both ways, and the odometry calibration from them."""
