"""``crane-fmu animate``: an animation of the crane from a simulate result (GIF, or MP4 with ffmpeg)."""

import shutil
import sys
import time
from pathlib import Path

from .common import UsageError, writable_file

NAME = "animate"
HELP = "an animation of the crane from a simulate result (GIF, or MP4 with ffmpeg)"
EXAMPLES = (
    "examples:\n"
    "  crane-fmu simulate --system transport --out move.csv\n"
    "  crane-fmu animate move.csv --out move.gif"
)


def arguments(p):
    p.add_argument("result", help="a CSV written by crane-fmu simulate")
    p.add_argument("--out", required=True, help="FILE.gif or FILE.mp4")
    p.add_argument("--fps", type=int, default=15,
                   help="frames per second (default 15), rounded to whole centiseconds between frames (15: 7 cs)")


def run(args):
    from crane_fmu.analysis.score_plots import animate, animation_needs
    from crane_fmu.cosim import read_result

    if Path(args.out).suffix not in (".gif", ".mp4"):
        raise UsageError(f"--out {args.out}: the animation is written as .gif or .mp4")
    if Path(args.out).suffix == ".mp4" and not shutil.which("ffmpeg"):
        raise UsageError(f"--out {args.out}: MP4 needs ffmpeg, which is not installed; write a .gif instead")
    if args.fps < 1:
        raise UsageError(f"--fps must be >= 1, got {args.fps}")
    try:
        columns = read_result(args.result)
    except (OSError, ValueError) as exc:
        raise UsageError(f"cannot read {args.result}: {exc}") from None
    needed = animation_needs(columns)
    if needed:
        raise UsageError(f"{args.result} has no crane to animate: it needs {needed}")
    writable_file(args.out, "--out")
    start = time.perf_counter()
    path = animate(columns, args.out, Path(args.result).stem, args.fps, progress=sys.stderr.isatty())
    print(f"wrote {path} ({time.perf_counter() - start:.1f} s)")
    return 0
