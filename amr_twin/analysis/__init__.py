"""Analysis of runs: metrics, trajectories and SE(2), TUM files."""
