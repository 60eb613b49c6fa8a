"""Recorders and their files: CSV/JSON reports, the MCAP (ROS 2) log, the Rerun .rrd and its blueprint, the collisions and faults stream, output checks."""
