"""``crane-fmu targets``: every controller against its targets, through the built FMUs."""

from crane_fmu import DEFAULT_FMU_DIR

from .common import UsageError, check_workers

NAME = "targets"
HELP = ("measure every controller against its targets (regulation, transport, robustness, reach, coarse steps; the "
        "crane in three dimensions' S11-S14)")
EXAMPLES = (
    "examples:\n"
    "  crane-fmu targets\n"
    "  crane-fmu targets --quick --workers 2\n"
    "  crane-fmu targets --floors     # only the floors: the least time each nominal scenario needs"
)


def arguments(p):
    p.add_argument("--fmu-dir", default=DEFAULT_FMU_DIR, help=f"folder of the built FMUs (default {DEFAULT_FMU_DIR})")
    p.add_argument("--quick", action="store_true", help="fewer cases")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: one per core)")
    p.add_argument("--floors", action="store_true",
                   help="only the floors (minimum-time linear programs; no FMUs needed)")


def run(args):
    from crane_fmu import systems
    from crane_fmu.analysis.controller_targets import run_targets

    if args.floors:
        from crane_fmu.analysis.controller_targets import report_floors
        from crane_fmu.analysis.floor import scenario_floors

        report_floors(scenario_floors())
        return 0
    check_workers(args)
    try:
        for name in ("lqr", "energy", "paper", "transport", "hoist-transport", "mpc", "mpc-transport", "lqr3d",
                     "mpc3d"):
            systems.resolve(systems.get(name), args.fmu_dir)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    run_targets(args.fmu_dir, args.quick, args.workers)
    return 0
