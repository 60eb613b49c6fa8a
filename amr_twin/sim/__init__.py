"""The simulation loop: MuJoCo physics, the plant (driver, motors, battery), rolling resistance, collisions, actors and faults."""
