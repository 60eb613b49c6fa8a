"""The twin on a real ROS 1 graph (Debian's ROS 1): the rospy bridge, the master, the rosserial host."""
