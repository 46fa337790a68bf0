"""The ``crane-fmu`` commands, one module each.

A command module has ``NAME``, ``HELP``, ``EXAMPLES`` (and optionally ``DESCRIPTION``),
``arguments(parser)`` that adds its options, and ``run(args) -> exit status``; it raises
:class:`~crane_fmu.commands.common.UsageError` for a user's mistake (one line, exit 2).
Imports of what a command works with happen inside its ``run``: the parser loads every command module,
so each import at the top of one would slow every command and ``crane-fmu --help``, which takes about
0.24 s to import ``crane_fmu.cli``. Measured on the project's 2-core machine (busy), the median of 7 fresh
interpreters, ``python -c "import time; t = time.perf_counter(); import fmpy; print(time.perf_counter() - t)"``:
fmpy 0.4 s, numpy 0.3 s, pyarrow.parquet 0.4 s, scipy.io 0.9 s, scipy.stats 2.5 s, matplotlib.pyplot 1.5 s.
"""

from . import animate, bench, build, compare, export, info, linearize, plot, reproduce, serve, simulate, sweep, targets

COMMANDS = (build, simulate, export, info, linearize, reproduce, sweep, compare, targets, plot, animate, bench, serve)
