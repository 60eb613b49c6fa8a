"""Analysis of runs: metrics, trajectories and SE(2), TUM files, the plant calibration and its report, parameter draws for uncertainty."""
