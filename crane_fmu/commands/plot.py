"""``crane-fmu plot``: plot one or more simulate results on shared axes."""

import os
from pathlib import Path

from .common import UsageError, writable_file

NAME = "plot"
HELP = "plot one or more simulate results on shared axes"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu plot results/paper.csv results/lqr.csv --out results/section5.png\n"
    "  crane-fmu plot run.csv --out run.png --title 'my run'"
)


def arguments(p):
    p.add_argument("results", nargs="+",
                   help="CSV or Parquet files written by crane-fmu simulate (labelled by file name)")
    p.add_argument("--out", required=True, help="the PNG to write")
    p.add_argument("--title", default="", help="a title over the plot")


def run(args):
    from crane_fmu.analysis.plots import plot_overlay
    from crane_fmu.cosim import read_result

    if Path(args.out).suffix != ".png":
        raise UsageError(f"--out {args.out}: the plot is written as .png")
    runs = {}
    for path in args.results:
        try:
            runs[Path(path).stem] = read_result(path)
        except (OSError, ValueError) as exc:
            raise UsageError(f"cannot read {path}: {exc}") from None
    writable_file(args.out, "--out")
    partial = str(Path(args.out).with_name(f".{Path(args.out).stem}.partial.png"))
    Path(partial).parent.mkdir(parents=True, exist_ok=True)
    try:
        plot_overlay(runs, partial, args.title)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    os.replace(partial, args.out)
    print(f"wrote {args.out}")
    return 0
