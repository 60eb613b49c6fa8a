"""Recorders and their files: CSV/JSON reports, the MCAP (ROS 2) log, the Rerun .rrd and its blueprint, output checks and atomic writes."""
