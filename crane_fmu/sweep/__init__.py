"""Parameter sweeps of the co-simulated FMUs on Dask (``crane-fmu sweep``)."""
