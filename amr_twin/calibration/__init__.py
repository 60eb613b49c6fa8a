"""The plant's calibration against the thesis and logs, its report, and the parameters' spreads drawn from it."""
