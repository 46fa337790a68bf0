"""``crane-fmu compare``: score controller FMUs on the same scenarios (the scoreboard)."""

import os
from pathlib import Path

from .common import UsageError, check_workers, dask_options, require_dask, writable_file
from .simulate import strict_option

NAME = "compare"
HELP = "score controller FMUs on the same scenarios (the scoreboard)"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu compare --out results/compare                  # every built-in controller, every scenario\n"
    "  crane-fmu compare --controller build/mine/PdSway.fmu --out results/mine   # yours beside every built-in one\n"
    "  crane-fmu compare --controller build/mine/PdSway.fmu --controller LqrController --only --out results/two\n"
    "  crane-fmu compare --quick --animate none --out results/compare   # a first look: results/compare/quick\n"
    "  crane-fmu compare --scenario S1,S6 --cases 32 --out results/some  # some scenarios, 32 paired cases\n"
    "  crane-fmu compare --check results/compare                # run 5 recorded cases again: the same figures?\n"
    "  crane-fmu compare --out results/compare --scheduler tcp://scheduler-host:8786\n"
    "Re-running the same command resumes: finished cases are skipped."
)


def arguments(p):
    p.add_argument("--controller", action="append", default=[], metavar="NAME|FILE.fmu|FILE.py",
                   help="a built-in controller's name, a controller FMU or a law file (FILE.py or FILE.py:NAME, run "
                        "without building an FMU) (repeatable); every built-in one is scored beside them unless "
                        "--only")
    p.add_argument("--only", action="store_true", help="score only the --controller ones")
    p.add_argument("--out", help="output folder: scoreboard.md, index.html, scores.parquet, plots, animations")
    dask_options(p)
    p.add_argument("--quick", action="store_true",
                   help="16 cases of the paired design (S3, S9, S10) instead of 64; a board marked QUICK, written to "
                        "OUT/quick")
    p.add_argument("--cases", type=int, metavar="N", help="cases of the paired design (default 64, --quick 16)")
    p.add_argument("--scenario", metavar="S1,S6", help="the scenarios to run (default: every one)")
    p.add_argument("--animate", default="S2", metavar="none|all|S1|S2|S7|S11-S14",
                   help="whose nominal runs to animate (default S2); drawn again only when the run changed")
    p.add_argument("--check", metavar="OUT", help="instead: run a random sample of the board in OUT (or, where OUT "
                                                  "holds none, of the quick board in OUT/quick) again and compare "
                                                  "every figure, bit for bit (exit 1 when one differs)")
    p.add_argument("--sample", type=int, default=5, metavar="N", help="with --check: how many cases (default 5)")
    strict_option(p)


def run(args):
    # one BLAS thread per process: the board's matrices are 6 x 6 to 8 x 8, and its processes fill the cores
    # (OpenBLAS's own threads, spinning beside them, doubled the time of the floors' matrix exponentials)
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, "1")
    from crane_fmu.compare import ANIMATE, check, compare

    check_workers(args)
    require_dask("compare")
    if args.check:
        try:
            differences = check(args.check, args.sample, args.workers, args.scheduler)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        for line in differences:
            print(f"differs: {line}")
        print(f"{len(differences)} case(s) differ" if differences else "every figure the same, bit for bit")
        return 1 if differences else 0
    if not args.out:
        raise UsageError("--out is required (or --check OUT)")
    choices = {"none": (), "all": ANIMATE, **{s: (s,) for s in ANIMATE}}
    if args.animate not in choices:
        raise UsageError(f"--animate {args.animate}: choose none, all, {', '.join(ANIMATE)} (the scenarios whose "
                         "runs are animated)")
    if args.only and not args.controller:
        raise UsageError("--only scores only the --controller ones: give at least one --controller")
    writable_file(Path(args.out) / ("quick" if args.quick else "") / "scoreboard.md", "--out")
    scenarios = [s.strip() for s in args.scenario.split(",")] if args.scenario else None
    try:
        compare(args.out, args.controller, args.fmu_dir, args.workers, args.scheduler, args.quick,
                progress=not args.no_progress, animate=choices[args.animate], only=args.only, scenarios=scenarios,
                cases=args.cases, strict=args.strict)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return 0
