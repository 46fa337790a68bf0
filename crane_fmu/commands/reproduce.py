"""``crane-fmu reproduce``: reproduce the paper's Figures 4, 5, 7, 8 and write REPORT.md."""

from pathlib import Path

from crane_fmu import DEFAULT_FMU_DIR

from .common import UsageError, check_workers, writable_file

NAME = "reproduce"
HELP = "reproduce the paper's Figures 4, 5, 7, 8 and write REPORT.md"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu reproduce --out results/paper\n"
    "  crane-fmu reproduce --quick --out /tmp/q"
)


def arguments(p):
    p.add_argument("--out", default="results/paper", help="output folder (default results/paper)")
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR, help="folder of the built FMUs")
    p.add_argument("--quick", action="store_true", help="fewer cases and shorter runs (every figure still)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")


def run(args):
    from crane_fmu import systems
    from crane_fmu.analysis.reproduce import reproduce

    check_workers(args)
    try:
        systems.resolve(systems.get("paper"), args.fmu_dir)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    writable_file(Path(args.out) / "REPORT.md", "--out")
    reproduce(args.out, args.fmu_dir, quick=args.quick, workers=args.workers)
    return 0
