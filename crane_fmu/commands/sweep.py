"""``crane-fmu sweep``: run a parameter study of the FMUs on Dask."""

from dataclasses import replace
from pathlib import Path

from .common import UsageError, check_workers, dask_options, require_dask, writable_file
from .simulate import strict_option

NAME = "sweep"
HELP = "run a parameter study of the FMUs on Dask"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu sweep study.toml --out results/study --workers 2\n"
    "  crane-fmu sweep builtin:region-of-attraction --out results/roa\n"
    "  crane-fmu sweep builtin:theta2-gain-sensitivity --out results/gains --csv\n"
    "  crane-fmu sweep study.toml --out results/study --scheduler tcp://scheduler-host:8786\n"
    "  crane-fmu sweep gains.toml --use controller=build/mine/PdSway.fmu --out results/mine   # your controller\n"
    "Re-running the same command resumes: finished cases are skipped."
)


def arguments(p):
    p.add_argument("study", help="study file (TOML, or YAML with PyYAML) or builtin:NAME")
    p.add_argument("--out", required=True, help="output folder: results.parquet, cases.jsonl, plot.png")
    dask_options(p)
    p.add_argument("--csv", action="store_true", help="also write results.csv")
    strict_option(p)
    p.add_argument("--use", action="append", default=[], metavar="INSTANCE=FILE.fmu",
                   help="run this FMU (or law file, FILE.py) as the instance in every case, over the study's "
                        "[use] table (repeatable): a study of your own controller")


def run(args):
    from crane_fmu.sweep import spec
    from crane_fmu.sweep.runner import run_study

    check_workers(args)
    require_dask("sweep")
    try:
        study = spec.load(args.study)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if args.use:
        use = dict(study.use)
        for item in args.use:
            instance, sep, path = item.partition("=")
            if not sep or not instance or not path:
                raise UsageError(f"--use {item!r}: expected INSTANCE=FILE.fmu, e.g. controller=mine.fmu")
            use[instance] = path
        study = replace(study, use=use)
    writable_file(Path(args.out) / "results.parquet", "--out")
    try:
        summary = run_study(study, args.out, args.fmu_dir, args.workers, args.scheduler, args.csv,
                            progress=not args.no_progress, strict=args.strict)
    except (ValueError, FileNotFoundError) as exc:
        raise UsageError(str(exc)) from None
    print(f"{summary['cases']} cases: {summary['ran']} run now, {summary['skipped']} already done, "
          f"{summary['not_ok']} not ok; results in {Path(args.out) / 'results.parquet'}")
    return 0
