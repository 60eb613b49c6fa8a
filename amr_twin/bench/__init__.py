"""Benchmarks: the loop, sensors and recordings against bare MuJoCo physics, and the user-facing suites (bench --suites)."""
