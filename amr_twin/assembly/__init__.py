"""The twin assembled: the loop with its sensors, firmware, nodes and estimator, the run commands and missions."""
