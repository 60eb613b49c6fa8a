"""The command line: one module per command group (main, run, experiment, fusion, menu), shared options and checks."""
