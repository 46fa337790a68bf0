"""The ``crane-fmu`` command: build, simulate, describe, reproduce the paper, sweep, benchmark.

A thin shell over :mod:`crane_fmu.commands`, one module per command. Every command that runs
something takes a system by name or as an SSP file. User mistakes print one line and exit with
status 2; an FMU failing during a run prints one line and exits with status 1.
"""

import argparse
import errno
import os
import sys

from crane_fmu import __version__
from crane_fmu.commands import COMMANDS
from crane_fmu.commands.common import Parser, UsageError

CANNOT_WRITE = {errno.ENOSPC, errno.EFBIG, errno.EDQUOT}  # a full disk, a file-size limit, a full quota


def parser():
    """The argument parser, built from the commands."""
    top = Parser(prog="crane-fmu", description="Build, simulate, sweep, score and benchmark the crane's FMUs.")
    top.add_argument("--version", action="version", version=f"crane-fmu {__version__}")
    sub = top.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for command in COMMANDS:
        p = sub.add_parser(command.NAME, help=command.HELP, description=getattr(command, "DESCRIPTION", None),
                           epilog=command.EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
        command.arguments(p)
        p.set_defaults(run=command.run)
    return top


def main(argv=None):
    """Run the command line; return the exit status."""
    try:
        top = parser()
        args = top.parse_args(argv)
        if args.command is None:  # bare crane-fmu: what there is to run
            top.print_help(sys.stderr)
            return 2
        return args.run(args)
    except UsageError as exc:
        print(f"crane-fmu: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: one line; a command that keeps partial results says where itself
        print("crane-fmu: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader (e.g. head) has gone: not an error
        sys.stdout = open(os.devnull, "w")
        return 0
    except OSError as exc:
        if exc.errno not in CANNOT_WRITE:
            raise
        # a full disk or a file-size limit (ulimit -f), wherever it struck; what was written before stays (a
        # sweep's or a board's journal: a re-run resumes from it)
        where = f" {exc.filename}" if exc.filename else ""
        print(f"crane-fmu: cannot write{where}: {exc.strerror} (what was written before is kept)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
