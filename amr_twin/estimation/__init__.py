"""Estimation of the robot's pose and map: the EKF and its model, dead reckoning, LiDAR odometry, the pose graph, the occupancy grid."""
