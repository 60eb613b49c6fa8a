"""The ROS side: the in-process bus, ROS messages, rosserial frames, the ROS 2 schemas and CDR encoders, the published ROS state."""
