"""The ``crane-fmu`` commands, one module each.

A command module has ``NAME``, ``HELP``, ``EXAMPLES`` (and optionally ``DESCRIPTION``),
``arguments(parser)`` that adds its options, and ``run(args) -> exit status``; it raises
:class:`~crane_fmu.commands.common.UsageError` for a user's mistake (one line, exit 2).
Imports of the heavy parts (fmpy, numpy, matplotlib, Dask) happen inside ``run``.
"""

from . import animate, bench, build, compare, info, linearize, plot, reproduce, serve, simulate, sweep, targets

COMMANDS = (build, simulate, info, linearize, reproduce, sweep, compare, targets, plot, animate, bench, serve)
