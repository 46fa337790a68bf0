"""``crane-fmu plot``: plot one or more simulate results on shared axes (over time, or a crane in two axes seen
from above, or each cable's swing)."""

import os
from pathlib import Path

from .common import UsageError, writable_file

NAME = "plot"
HELP = "plot one or more simulate results on shared axes"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu plot results/paper.csv results/lqr.csv --out results/section5.png\n"
    "  crane-fmu plot run.csv --out run.png --title 'my run'\n"
    "  crane-fmu plot move3d.csv --view top --corridor 0,0,3,0,3,2 --corridor-width 0.6 --out top.png\n"
    "  crane-fmu plot move3d.csv --view swing --out swing.png"
)
VIEWS = ("time", "top", "swing")


def arguments(p):
    p.add_argument("results", nargs="+",
                   help="CSV or Parquet files written by crane-fmu simulate (labelled by file name), of one plant")
    p.add_argument("--out", required=True, help="the PNG to write")
    p.add_argument("--title", default="", help="a title over the plot")
    p.add_argument("--view", choices=VIEWS, default="time",
                   help="time: positions, swing angles and demands over time (default); top: the trolley's, hook's "
                        "and load's paths seen from above (a crane in two axes); swing: each cable's swing angle")
    p.add_argument("--corridor", metavar="X0,Y0,X1,Y1,...",
                   help="with --view top: a corridor's centre line through these points [m], shaded with "
                        "--corridor-width; the legend gives the load's largest distance from it")
    p.add_argument("--corridor-width", type=float, metavar="W",
                   help="the corridor's full width [m] (the load within W/2 of the centre line)")


def run(args):
    from crane_fmu.analysis.plots import plot_overlay
    from crane_fmu.analysis.spatial_plots import parse_corridor, plot_swing, plot_top, same_plant
    from crane_fmu.cosim import read_result

    if Path(args.out).suffix != ".png":
        raise UsageError(f"--out {args.out}: the plot is written as .png")
    corridor = None
    if args.corridor is not None or args.corridor_width is not None:
        if args.view != "top":
            raise UsageError(f"--corridor and --corridor-width go with --view top, not --view {args.view}")
        if args.corridor is None:
            raise UsageError("--corridor-width needs --corridor X0,Y0,X1,Y1,...")
        try:
            corridor = parse_corridor(args.corridor, args.corridor_width)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
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
        same_plant(runs)
        if args.view == "top":
            drawn = plot_top(runs, partial, args.title, corridor, args.corridor_width)
        elif args.view == "swing":
            drawn = plot_swing(runs, partial, args.title)
        else:
            drawn = plot_overlay(runs, partial, args.title)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    os.replace(partial, args.out)
    print(f"wrote {args.out}")
    for label, apart in (drawn["apart"] if args.view == "top" else {}).items():
        inside = "within" if apart <= args.corridor_width / 2 else "OUTSIDE"
        print(f"{label}: the load at most {apart:.4f} m from the corridor's centre line ({inside} "
              f"{args.corridor_width / 2:g} m)")
    return 0
