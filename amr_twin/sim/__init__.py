"""The simulation loop: MuJoCo physics, the plant (driver, motors, battery), rolling resistance, the virtual clock, collisions, faults and the run commands."""
