"""The simulation loop: MuJoCo physics, the plant (driver, motors, battery), rolling resistance, collisions, faults and the run commands."""
