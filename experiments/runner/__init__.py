"""Running many independent simulations: local process pool, Dask cluster, atomic files."""
