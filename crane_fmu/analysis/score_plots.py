"""The scoreboard's pictures: comparison plots and animations of the crane (matplotlib, Agg)."""

import json
import math
import shutil
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np

from crane_fmu import components

from .plots import pyplot, save
from .scoreboard import SCENARIOS, summarise

COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:gray",
           "tab:olive", "tab:cyan")


def colour(name):
    """A controller's colour, the same on every board: the registered controllers' in registration order, any
    other's from its name (a CRC-32 of it) among the colours left."""
    builtin = [c.model_identifier for c in components.registered("controller")]
    if name in builtin:
        return COLOURS[builtin.index(name) % len(COLOURS)]
    left = COLOURS[len(builtin):] or COLOURS
    return left[zlib.crc32(name.encode()) % len(left)]


def _nominal(rows, scenario):
    return [r for r in rows if r["scenario"] == scenario and r.get("signals")]


def plot_runs(rows, scenario, path, users=()):
    """Trolley position, both angles and u against time, one line per controller, for a scenario's nominal case."""
    runs = _nominal(rows, scenario)
    if not runs:
        return None
    plt = pyplot()
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 9))
    for r in sorted(runs, key=lambda r: r["controller"]):
        s, c = r["signals"], colour(r["controller"])
        label = r["controller"] + (" (yours)" if r["controller"] in users else "") + (
            "" if r["status"] == "ok" else " (failed)")
        axes[0].plot(s["time"], s["x"], color=c, lw=1.2, label=label)
        axes[1].plot(s["time"], np.degrees(s["theta1"]), color=c, lw=1.2)
        axes[2].plot(s["time"], np.degrees(s["theta2"]), color=c, lw=1.2)
        axes[3].plot(s["time"], s["u"], color=c, lw=1.2)
    for ax, label in zip(axes, ("trolley x [m]", "hook angle theta1 [deg]", "payload angle theta2 [deg]",
                                "demanded u [m/s2]")):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    finite = [v for r in runs for k in ("theta1", "theta2") for v in np.degrees(r["signals"][k])
              if math.isfinite(v)]  # both angles share one scale
    limit = min(max(abs(min(finite)), abs(max(finite)), 1.0) * 1.1, 90.0)
    axes[1].set_ylim(-limit, limit)
    axes[2].set_ylim(-limit, limit)
    axes[3].set_ylim(-3, 3)  # the drive gives at most 2 m/s2; larger demands are clipped in the picture
    axes[0].legend(fontsize=8, loc="best")
    quick = " (QUICK board: a subset of the cases)" if any(r.get("quick") for r in rows) else ""
    axes[0].set_title(f"{scenario}: {SCENARIOS[scenario].title}{quick}")
    axes[-1].set_xlabel("time [s]")
    return save(fig, path, dpi=100)


def plot_summary(rows, path, users=()):
    """Per scenario, each controller's ranking figure (worst case) as a bar, in rank order, with the target.

    A controller that never reached the figure within the run, or failed, gets a hatched bar to the top of
    the axis with the word on it: never the shortest bar. A figure far beyond the target (over four times
    it) is drawn to the top of the axis with its value written on it.
    """
    from matplotlib.lines import Line2D  # optional: the plot extra
    from matplotlib.patches import Patch


    plt = pyplot()
    scenarios = [s for s in SCENARIOS if summarise(rows, s)]
    fig, axes = plt.subplots(1, len(scenarios), figsize=(2.3 * len(scenarios), 4.4), squeeze=False,
                             layout="constrained")
    for ax, sid in zip(axes[0], scenarios):
        lines = summarise(rows, sid)
        key = SCENARIOS[sid].rank_by
        unit = "deg" if key.endswith("_deg") else "s"
        limit = next((t.limit for t in SCENARIOS[sid].targets if t.metric == key), None)
        finite = [line[key] for line in lines if line[key] is not None and not line["failed"]]
        shown = [v for v in finite if limit is None or v <= 4 * limit]
        top = 1.25 * max(shown + ([limit] if limit is not None else []) + [1e-3])
        for i, line in enumerate(lines):
            value, edge = None if line["failed"] else line[key], colour(line["controller"])
            if value is None:
                ax.bar(i, top, color="white", edgecolor=edge, hatch="///", lw=1.2)
            ax.bar(i, min(value, top), color=edge) if value is not None else None
            word = "failed" if line["failed"] else "never" if value is None else (
                f"{value:.3g} {unit}" if value > top else None)
            if word:
                ax.text(i, top / 2, word, ha="center", va="center", rotation=90, fontsize=9,
                        bbox={"facecolor": "white", "edgecolor": "none", "pad": 1})
        if limit is not None:
            ax.axhline(limit, color="k", ls="--", lw=0.9)
        ax.set_ylim(0, top)
        ax.set_xticks(range(len(lines)), [str(i + 1) for i in range(len(lines))], fontsize=8)
        ax.set_xlabel("rank", fontsize=8)
        target = "" if limit is None else f"\ntarget <= {limit:g} {unit}"
        ax.set_title(f"{sid}: {key.removesuffix('_s').removesuffix('_deg')} [{unit}]{target}", fontsize=9)
        ax.tick_params(axis="y", labelsize=8)
    names = sorted({r["controller"] for r in rows})
    handles = [Patch(color=colour(n), label=n + (" (yours)" if n in users else "")) for n in names]
    handles += [Patch(facecolor="white", edgecolor="k", hatch="///", label="never within the run, or failed"),
                Line2D([], [], color="k", ls="--", lw=0.9, label="target (value under each title)")]
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 4), fontsize=8, frameon=False)
    quick = any(r.get("quick") for r in rows)
    fig.suptitle(("QUICK board (a subset of the cases): " if quick else "")
                 + "each scenario's ranking figure, worst case, in rank order; lower is better", fontsize=10)
    fig.savefig(path, dpi=100)  # laid out by the constrained layout
    plt.close(fig)
    return path


def plot_all(rows, out_dir, users=()):
    """The S1, S2 and S7 runs and the summary, as PNGs in ``out_dir``; return their paths."""
    paths = [plot_runs(rows, s, Path(out_dir) / f"{s}.png", users) for s in ("S1", "S2", "S7")]
    return [p for p in paths if p] + [plot_summary(rows, Path(out_dir) / "summary.png", users)]


def animate(signals, path, title="", fps=15, progress=False):
    """An animation of the crane: rail, trolley, both cables, hook and payload, with the time.

    ``signals`` holds ``time`` and the plant's ``x``, ``x1``, ``y1``, ``x2``, ``y2`` (any
    instance prefix). Written as GIF (pillow), or MP4 when the path ends in .mp4 (needs ffmpeg).

    Parameters
    ----------
    fps : int
        Frames per second of the motion, as near as whole centiseconds allow (GIF delays are whole
        centiseconds: 15 gives a frame every 7 cs, 14.3 a second). Each frame shows the last recorded
        sample at or before its time, so the animation runs in real time from any output interval,
        uniform or not (fmpy's 32 ms, the master's 1 ms).
    progress : bool
        Show ``frame k/n`` on stderr as frames are drawn.

    Notes
    -----
    The axes, the rail and the labels are drawn once; each frame restores that background and draws
    only the moving parts (matplotlib's blitting), then the frames are written in one go. Drawing
    every frame whole, as ``FuncAnimation.save`` does (twice per frame), took 56 s for a 20 s run at
    25 frames per second, two thirds of it laying out tick labels.
    """
    plt = pyplot()

    def column(name):
        return np.asarray(next(v for k, v in signals.items() if k == name or k.endswith("." + name)))

    t, x, x1, y1, x2, y2 = (column(n) for n in ("time", "x", "x1", "y1", "x2", "y2"))
    delay = frame_delay(fps)
    count = int(math.floor((t[-1] - t[0]) / delay + 1e-9)) + 1
    frames = np.searchsorted(t, t[0] + delay * np.arange(count) + 1e-9, side="right") - 1
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=80)
    span = [min(x.min(), x2.min()) - 0.6, max(x.max(), x2.max()) + 0.6]
    ax.set_xlim(*span)
    ax.set_ylim(min(y2.min(), -1.0) - 0.3, 0.35)
    ax.set_aspect("equal")
    ax.plot(span, [0.05, 0.05], color="0.3", lw=3)  # the rail
    ax.set_xlabel("x [m]")
    ax.set_title(title, fontsize=10)
    trolley = plt.Rectangle((x[0] - 0.15, 0.0), 0.3, 0.1, color="0.35", animated=True)
    ax.add_patch(trolley)
    (cables,) = ax.plot([], [], color="k", lw=1.5, animated=True)
    (hook,) = ax.plot([], [], "o", color="tab:blue", ms=7, animated=True)
    (payload,) = ax.plot([], [], "s", color="tab:orange", ms=13, animated=True)
    (trail,) = ax.plot([], [], color="tab:orange", lw=0.6, alpha=0.5, animated=True)
    clock = ax.text(0.02, 0.95, "", transform=ax.transAxes, va="top", fontsize=9, animated=True)
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    images = []
    for n, i in enumerate(frames):
        trolley.set_x(x[i] - 0.15)
        cables.set_data([x[i], x1[i], x2[i]], [0.0, y1[i], y2[i]])
        hook.set_data([x1[i]], [y1[i]])
        payload.set_data([x2[i]], [y2[i]])
        first = np.searchsorted(t, t[i] - 2.0)  # the payload's path over the last 2 s
        trail.set_data(x2[first:i + 1], y2[first:i + 1])
        clock.set_text(f"t = {t[i]:5.2f} s   hook {math.degrees(math.atan2(x1[i] - x[i], -y1[i])):+5.1f} deg")
        fig.canvas.restore_region(background)
        for artist in (trail, cables, trolley, hook, payload, clock):
            ax.draw_artist(artist)
        images.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
        if progress and ((n + 1) % 10 == 0 or n + 1 == len(frames)):
            sys.stderr.write(f"\rframe {n + 1}/{len(frames)}" + ("\n" if n + 1 == len(frames) else ""))
            sys.stderr.flush()
    plt.close(fig)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    if path.suffix == ".mp4":
        _write_mp4(images, partial, 1.0 / delay)
    else:
        _write_gif(images, partial, round(100 * delay))
    partial.replace(path)
    return path


def frame_delay(fps):
    """Seconds between frames for ``fps``: whole centiseconds (as GIF stores them), at least 2 (browsers
    show shorter delays as 10)."""
    return max(2, round(100 / fps)) / 100


def _write_gif(images, path, delay_cs):
    """A GIF of RGB frames, each shown ``delay_cs`` centiseconds."""
    from PIL import Image  # Pillow comes with matplotlib: the plot extra

    sample = np.concatenate([images[0], images[len(images) // 2], images[-1]])  # every colour that moves
    palette = Image.fromarray(sample).quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    frames = [Image.fromarray(a).quantize(palette=palette, dither=Image.Dither.NONE) for a in images]
    frames[0].save(path, format="GIF", save_all=True, append_images=frames[1:], duration=10 * delay_cs, loop=0)


def _write_mp4(images, path, fps):
    """An MP4 (H.264) of RGB frames through ffmpeg."""
    height, width = images[0].shape[:2]
    command = ["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s",
               f"{width}x{height}", "-r", f"{fps:.6g}", "-i", "-", "-pix_fmt", "yuv420p", "-vf",
               "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4", str(path)]
    subprocess.run(command, input=b"".join(a.tobytes() for a in images), check=True)


def animate_all(rows, scenario, out_dir, fps=15):
    """A GIF (and an MP4 where ffmpeg is available) of each controller's nominal run of a scenario.

    An animation is drawn again only when its run changed: ``.drawn.json`` in ``out_dir`` keeps the
    case id each file was drawn from. Returns the paths drawn now.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    ledger = out_dir / ".drawn.json"
    drawn = json.loads(ledger.read_text()) if ledger.exists() else {}
    paths = []
    for r in sorted(_nominal(rows, scenario), key=lambda r: r["controller"]):
        if "x2" not in r["signals"]:
            continue
        title = f"{scenario}, {r['controller']}" + ("" if r["status"] == "ok" else " (failed)")
        key = f"{r['case_id']} {fps} fps"
        for suffix in (".gif", ".mp4") if shutil.which("ffmpeg") else (".gif",):
            path = out_dir / f"{scenario}_{r['controller']}{suffix}"
            if drawn.get(path.name) == key and path.exists():
                continue
            paths.append(animate(r["signals"], path, title, fps=fps))
            drawn[path.name] = key
            partial = ledger.with_suffix(".partial")
            partial.write_text(json.dumps(drawn, indent=1, sort_keys=True))
            partial.replace(ledger)
    return paths
