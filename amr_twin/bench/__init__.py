"""Benchmarks: every figure against one bare-physics floor, and the suites (bench --suites)."""
