"""What a board's drawing processes use, imported once by the fork server they are forked from (``crane-fmu
compare``), not by each: matplotlib's pyplot on Agg (about 0.5 CPU-s) and scipy.stats (the bootstrap's quantiles,
about 0.4 CPU-s). Without the plot extra the import fails, and the fork server goes on without it."""

from scipy import stats  # noqa: F401

from .plots import pyplot

pyplot()
