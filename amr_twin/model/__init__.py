"""The robot model: the parameter file, its schema and spreads, mass properties, statics, the xacro -> URDF -> MJCF build and the worlds."""
