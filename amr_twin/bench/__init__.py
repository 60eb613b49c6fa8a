"""Benchmarks: every figure against one bare-physics floor (``amr-twin bench``), and the
user-facing suites (``bench --suites``)."""
