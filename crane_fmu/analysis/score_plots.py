"""The scoreboard's pictures: comparison plots and animations of the crane (matplotlib, Agg)."""

import functools
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

import numpy as np

from crane_fmu import components

from .glyph_text import GlyphText
from .metrics import find_crane
from .plots import pyplot
from .ranking import board_statistics, not_applicable, summarise
from .scenarios import paired, scenarios

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


HATCHES = ("", "..", "oo", "++", "--", "||", "**", "OO", "\\\\", "xx")  # with the colour: never colour alone;
NEVER = {"color": "white", "edgecolor": "0.3", "hatch": "///"}  # never or failed: white, hatched like no controller
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "<", ">")


def style(name, names):
    """``(colour, hatch, marker)`` of a controller: its colour (:func:`colour`) and, by its place among
    ``names`` (sorted), a hatch and a marker, so that no two controllers differ by colour alone."""
    i = sorted(names).index(name)
    return colour(name), HATCHES[i % len(HATCHES)], MARKERS[i % len(MARKERS)]


def _nominal(rows, scenario):
    return [r for r in rows if r["scenario"] == scenario and r.get("signals")]


def _label(name, users):
    return name + (" (yours)" if name in users else "")


def plot_runs(rows, scenario, path, users=()):
    """A scenario's nominal run of every controller, as a grid: a column per controller (by name, the same
    place on every board), a row per signal (trolley x, both angles, demanded u) on shared axes; each
    panel draws its controller on top, the others faint grey beneath, so no curve hides another."""
    runs = sorted(_nominal(rows, scenario), key=lambda r: r["controller"])
    if not runs:
        return None
    plt = pyplot()
    names = [r["controller"] for r in runs]
    crane = find_crane(runs[0]["signals"])[1].crane
    swing = list(crane.swing)
    signals = tuple((a.position, f"trolley {a.position} [m]", 1.0) for a in crane.axes) + tuple(
        (name, f"{name} [deg]", 180 / math.pi) for name in swing) + tuple(
        (name, f"demanded {name} [m/s2]", 1.0) for name in crane.demands)
    width, height = 2.6 * len(runs) + 1.2, 7.5
    fig, axes = plt.subplots(len(signals), len(runs), sharex=True, sharey="row", squeeze=False,
                             figsize=(width, height))
    # a fixed layout, in inches (constrained layout took half of the picture's time to find about the same):
    # the labels' room left, below and above, the gaps between the panels
    fig.subplots_adjust(left=0.6 / width, right=1 - 0.05 / width, bottom=0.4 / height, top=1 - 0.46 / height,
                        wspace=0.13 / ((width - 0.65 - 0.13 * (len(runs) - 1)) / len(runs)),
                        hspace=0.15 / ((height - 0.86 - 0.15 * (len(signals) - 1)) / len(signals)))
    for j, r in enumerate(runs):
        c, _, marker = style(r["controller"], names)
        mine = r["controller"] in users
        for i, (key, ylabel, scale) in enumerate(signals):
            ax = axes[i][j]
            for other in runs:
                if other is not r:
                    ax.plot(other["signals"]["time"], np.asarray(other["signals"][key]) * scale, color="0.8", lw=0.8)
            t = np.asarray(r["signals"]["time"])
            ax.plot(t, np.asarray(r["signals"][key]) * scale, color=c, lw=2.2 if mine else 1.4, marker=marker,
                    markevery=max(1, len(t) // 8), ms=4)
            ax.grid(True, alpha=0.3)
            if j == 0:
                ax.set_ylabel(ylabel, fontsize=8)
            ax.tick_params(labelsize=7)
        title = _label(r["controller"], users) + ("" if r["status"] == "ok" else " (failed)")
        axes[0][j].set_title(title, fontsize=9, fontweight="bold" if mine else "normal", color=c)
        axes[-1][j].set_xlabel("time [s]", fontsize=8)
    finite = [v for r in runs for k in swing for v in np.degrees(r["signals"][k]) if math.isfinite(v)]
    limit = min(max(abs(min(finite)), abs(max(finite)), 1.0) * 1.1, 90.0)  # the angles share one scale
    first = len(crane.axes)
    for row in range(first, first + len(swing)):
        axes[row][0].set_ylim(-limit, limit)
    for row in range(first + len(swing), len(signals)):
        axes[row][0].set_ylim(-3, 3)  # the drive gives at most 2 m/s2; larger demands are clipped in the picture
    quick = " (QUICK board)" if any(r.get("quick") for r in rows) else ""
    fig.suptitle(f"{scenario}: {scenarios()[scenario].title}{quick}", fontsize=10, y=1 - 0.04 / height)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _ranking_figure(line, key, described=None):
    """``(bar, low, high, p90)`` of a line's ranking figure (None where never), or None when it failed: the worst
    case, or with the paired design's ``described`` figures the median, its interval and the 90th percentile."""
    if line["failed"]:
        return None
    if described is None:
        return (line[key], None, None, None)
    d = described[key]
    return tuple(v if math.isfinite(v) else None for v in (d.median, d.median_low, d.median_high, d.p90))


def plot_summary(rows, path, users=(), stats=None):
    """Per scenario a panel of each controller's ranking figure: a row per controller, by name, in the same place
    in every panel (its rank written beside it), colour and hatch its own, yours in bold; saved to ``path``.

    The bar is the worst case; on the paired design the median, with its 95 % interval as an error bar and the
    90th percentile as a marker. *never* and *failed* are hatched bars to the edge with the word; a figure far
    beyond the target or the best bar (over eight times it) runs to the edge with its value written on it, a 90th
    percentile that far as a marker at the edge pointing out, with its value.
    """
    fig = summary_figure(rows, users, stats)
    fig.savefig(path, dpi=100)
    pyplot().close(fig)
    return path


def summary_figure(rows, users=(), stats=None):
    """The figure of :func:`plot_summary`; every bar, error bar and marker within its panel's axes."""
    from matplotlib.lines import Line2D  # optional: the plot extra
    from matplotlib.patches import Patch

    plt = pyplot()
    stats = board_statistics(rows) if stats is None else stats
    shown = [s for s in scenarios() if summarise(rows, s) or not_applicable(rows, s)]
    names = sorted({r["controller"] for r in rows})
    columns = min(4, len(shown))
    grid = math.ceil(len(shown) / columns)
    width, height = 3.6 * columns, 0.45 * len(names) * grid + 1.6 * grid + 1.2
    fig, axes = plt.subplots(grid, columns, figsize=(width, height), squeeze=False)
    _summary_layout(fig, [_label(n, users) for n in names], [n in users for n in names], columns, grid)
    for ax in axes.flat[len(shown):]:
        ax.set_visible(False)
    for ax, sid in zip(axes.flat, shown):
        lines = {line["controller"]: line for line in summarise(rows, sid)}
        key = scenarios()[sid].rank_by
        unit = "deg" if key.endswith("_deg") else "s"
        limit = next((t.limit for t in scenarios()[sid].targets if t.metric == key), None)
        on_design = sid in stats
        figures = {n: _ranking_figure(line, key, stats[sid]["describe"][n] if on_design else None)
                   for n, line in lines.items()}
        finite = [v for f in figures.values() if f for v in f if v is not None]
        bars = [f[0] for f in figures.values() if f and f[0] is not None]
        scale = max([limit or 0.0] + ([min(bars)] if bars else []))  # a far larger figure runs off the panel
        top = 1.15 * max([v for v in finite if not scale or v <= 8 * scale] + [limit or 0.0, 1e-3])
        edge = top / 1.15 * 1.1  # where a figure beyond the panel is marked, inside it
        for y, name in enumerate(names):
            c, hatch, marker = style(name, names)
            if name not in lines:
                ax.text(0.02 * top, y, "n/a" if name in not_applicable(rows, sid) else "", va="center", fontsize=8,
                        color="0.4")
                continue
            f = figures[name]
            if f is None or f[0] is None:
                ax.barh(y, top, lw=1.2, **NEVER)
                ax.text(top / 2, y, "failed" if lines[name]["failed"] else "never", ha="center", va="center",
                        fontsize=8, bbox={"facecolor": "white", "edgecolor": "none", "pad": 1})
            else:
                ax.barh(y, min(f[0], top), color=c, hatch=hatch, edgecolor="0.15", lw=2.0 if name in users else 0.5)
                if f[0] > top:  # its 90th percentile, as far, with it
                    p90 = f", p90 {f[3]:.3g}" if f[3] is not None and f[3] > top else ""
                    ax.text(top / 2, y, f"{f[0]:.3g} {unit}{p90}", ha="center", va="center", fontsize=8,
                            bbox={"facecolor": "white", "edgecolor": "none", "pad": 1})
                if f[1] is not None or f[2] is not None:
                    low, high = f[1] if f[1] is not None else 0.0, min(f[2] if f[2] is not None else top, top)
                    ax.errorbar(min(f[0], top), y, xerr=[[max(0.0, min(f[0], top) - low)], [max(0.0, high - min(
                        f[0], top))]], fmt="none", ecolor="k", capsize=3, lw=1)
                if f[3] is not None and f[3] <= top:
                    ax.plot(f[3], y, marker=marker, color="k", ms=5, ls="none")
                elif f[3] is not None and f[0] <= top:  # far beyond: at the edge, pointing out, with its value
                    ax.plot(edge, y, marker=">", color="k", ms=5, ls="none")
                    ax.annotate(f"p90 {f[3]:.3g} {unit}", (edge, y), xytext=(-6, 0), textcoords="offset points",
                                ha="right", va="center", fontsize=7,
                                bbox={"facecolor": "white", "edgecolor": "none", "pad": 1})
            ax.text(1.0, y, f"  {lines[name]['rank']}{'=' if lines[name]['tie'] else ''}", va="center", fontsize=8,
                    transform=ax.get_yaxis_transform(), clip_on=False)
        if limit is not None:
            ax.axvline(limit, color="k", ls="--", lw=0.9)
        ax.set_xlim(0, top)
        ax.set_ylim(len(names) - 0.5, -0.5)
        ax.set_yticks(range(len(names)), [_label(n, users) for n in names], fontsize=8)
        for tick, name in zip(ax.get_yticklabels(), names):
            tick.set_fontweight("bold" if name in users else "normal")
        what = "median, 95 % interval, p90" if on_design else "worst case"
        target = "" if limit is None else f"; target <= {limit:g}"
        ax.set_title(f"{sid}: {key} [{unit}]\n{what}{target}", fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
    handles = [Patch(facecolor=style(n, names)[0], hatch=style(n, names)[1], edgecolor="0.15",
                     lw=2.0 if n in users else 0.5, label=_label(n, users)) for n in names]
    handles += [Patch(facecolor=NEVER["color"], edgecolor=NEVER["edgecolor"], hatch=NEVER["hatch"],
                      label="never within the run, or failed"),
                Line2D([], [], color="k", ls="--", lw=0.9, label="target"),
                Line2D([], [], color="k", marker="|", ls="none", label="95 % interval of the median (paired)"),
                Line2D([], [], color="k", marker="o", ls="none", ms=4, label="90th percentile (paired; marker "
                       "per controller)")]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 4), fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 0.02 / height))
    fig.suptitle(summary_title(rows, shown), fontsize=10, y=1 - 0.04 / height)
    return fig


def _summary_layout(fig, labels, bold, columns, grid):
    """The summary's panels placed in inches (constrained layout took a third of the picture's time): each column's
    controller names (measured) left of its panel, its ranks right of it, each row's two-line title above, its tick
    labels below, the legend (rows of four) at the bottom, the title at the top."""
    from matplotlib.font_manager import FontProperties

    width, height = fig.get_size_inches()
    renderer = fig.canvas.get_renderer()
    names = max(renderer.get_text_width_height_descent(label, FontProperties(size=8, weight="bold" if b else "normal"),
                                                       ismath=False)[0] for label, b in zip(labels, bold)) / fig.dpi
    left, right = names + 0.12, 0.35  # the names, the ticks' room; the rank ("  5=")
    above, below = 0.42, 0.28  # a panel's title of two lines; its tick labels
    legend = 0.2 * math.ceil((len(labels) + 4) / 4) + 0.1
    panel_width = width / columns - left - right
    panel_height = (height - 0.3 - legend - grid * (above + below)) / grid
    fig.subplots_adjust(left=left / width, right=1 - right / width, top=1 - (0.3 + above) / height,
                        bottom=(legend + below) / height, wspace=(left + right) / panel_width,
                        hspace=(above + below) / panel_height)


def summary_title(rows, shown):
    """The summary's title; it names the scenarios of ``shown`` on the paired design, where there are any."""
    on_design = [s for s in paired() if s in shown]
    return (("QUICK board: " if any(r.get("quick") for r in rows) else "") + "each scenario's ranking figure; lower "
            "is better; the rank right of each bar (= a tie)"
            + (f"; {', '.join(on_design)} on the paired design" if on_design else ""))


def plot_all(rows, out_dir, users=(), stats=None, store=None):
    """The S1, S2 and S7 runs and the summary, as PNGs in ``out_dir``; return their paths.

    A picture drawn before on this machine from the same cases is copied from ``store`` (see :func:`kept`): a case's
    id is the hash of everything its run is made of, and the summary's statistics are a function of the rows.
    """
    paths = [plot_scenario(rows, s, out_dir, users, store) for s in RUN_PICTURES]
    return [p for p in paths if p] + [plot_board_summary(rows, out_dir, users, stats, store)]


def plot_scenario(rows, scenario, out_dir, users=(), store=None):
    """The picture of a scenario's nominal runs (:func:`plot_runs`) as ``out_dir/<scenario>.png``, from the rows of
    that scenario alone (the board's others change nothing of it), so that a board draws it as soon as they are in;
    its path, or None where the scenario has no nominal run. Copied from ``store`` where drawn before (:func:`kept`)."""
    quick, users = any(r.get("quick") for r in rows), sorted(users)
    runs = sorted(_nominal(rows, scenario), key=lambda r: r["controller"])
    if not runs:
        return None
    made_of = [scenario, users, quick, [[r["case_id"], r["status"]] for r in runs]]
    return kept(Path(out_dir) / f"{scenario}.png", made_of, lambda path: plot_runs(rows, scenario, path, users), store)


def plot_board_summary(rows, out_dir, users=(), stats=None, store=None):
    """The summary (:func:`plot_summary`) of all the board's rows as ``out_dir/summary.png``; its path. Copied from
    ``store`` where drawn before (:func:`kept`)."""
    quick, users = any(r.get("quick") for r in rows), sorted(users)
    cases = sorted([str(r.get(k)) for k in ("case_id", "controller", "scenario", "case", "status", "error")]
                   for r in rows)
    return kept(Path(out_dir) / "summary.png", ["summary", users, quick, cases],
                lambda path: plot_summary(rows, path, users, stats), store)


STORE = "crane_fmu_pictures"  # in the temporary folder: pictures by what they were drawn from


def kept(path, made_of, draw, store=None):
    """``draw(path)``, or a copy of the file it wrote before on this machine from the same ``made_of``; return
    ``path``.

    ``made_of`` (JSON) names everything the picture is drawn from: case ids, each the hash of everything its run is
    made of. With this package's sources and matplotlib's and Pillow's versions, it is the file's name in ``store``
    (default: the temporary folder's ``crane_fmu_pictures``): an edit of the code draws every picture again.
    """
    name = hashlib.sha256(json.dumps([_drawn_by(), made_of]).encode())
    stored = Path(store or Path(tempfile.gettempdir()) / STORE) / f"{name.hexdigest()[:32]}{path.suffix}"
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    if stored.is_file():
        shutil.copyfile(stored, partial)
        partial.replace(path)
        return path
    draw(path)
    stored.parent.mkdir(parents=True, exist_ok=True)
    spare = stored.with_name(f".{stored.name}.{os.getpid()}.partial")
    shutil.copyfile(path, spare)
    os.replace(spare, stored)
    return path


@functools.cache
def _drawn_by():
    """What draws the pictures: this package's sources (read once per process), matplotlib's and Pillow's versions."""
    import matplotlib
    import PIL

    from .floor import code_key

    return code_key(), matplotlib.__version__, PIL.__version__


def _animated(crane):
    """What an animation draws of a crane: its axes' positions, the hook's and the load's positions (none: a crane
    without them is not animated)."""
    return (*(a.position for a in crane.axes), *crane.hook, *crane.load) if crane.hook and crane.load else ()


def animation_needs(columns):
    """What a recorded run misses to be animated, one line (empty: nothing): one instance with what
    :func:`_animated` names of a registered plant."""
    if find_crane(columns, _animated)[1] is not None:
        return ""
    wanted = "; ".join(f"{c.model_identifier}: {', '.join(_animated(c.crane))}" for c in components.registered("plant")
                       if c.crane is not None and _animated(c.crane))
    return f"a plant's outputs ({wanted})"


def animate(signals, path, title="", fps=15, progress=False):
    """An animation of the crane: rail, trolley, both cables, hook and payload, with the time.

    ``signals`` holds ``time`` and the plant's outputs (any instance prefix) that its roles name: the first axis's
    position, the hook's and the load's positions (a side view: their first and last coordinates); a crane in two
    horizontal axes (hook and load in three coordinates) is drawn in both vertical planes and from above
    (:func:`.spatial_plots.spatial_frames`). Written as
    GIF (pillow), or MP4 when the path ends in .mp4 (needs ffmpeg).

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
    def column(name):
        return np.asarray(next(v for k, v in signals.items() if k == name or k.endswith("." + name)))

    crane = find_crane(signals, _animated)[1].crane
    t = column("time")
    delay = frame_delay(fps)
    count = int(math.floor((t[-1] - t[0]) / delay + 1e-9)) + 1
    frames = np.searchsorted(t, t[0] + delay * np.arange(count) + 1e-9, side="right") - 1
    if len(crane.hook) == 3:  # two horizontal axes: both vertical planes and the top view (spatial_plots.py)
        from .spatial_plots import spatial_frames

        images = spatial_frames(column, crane, t, frames, title, progress)
    else:
        images = _side_frames(column, crane, t, frames, title, progress)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    if path.suffix == ".mp4":
        _write_mp4(images, partial, 1.0 / delay)
    else:
        _write_gif(images, partial, round(100 * delay))
    partial.replace(path)
    return path


def show_progress(n, count, progress):
    """``frame k/n`` on stderr every 10 frames and at the last, when ``progress``."""
    if progress and ((n + 1) % 10 == 0 or n + 1 == count):
        sys.stderr.write(f"\rframe {n + 1}/{count}" + ("\n" if n + 1 == count else ""))
        sys.stderr.flush()


def _side_frames(column, crane, t, frames, title, progress):
    """The frames of a planar crane seen from the side (RGBA arrays, opaque)."""
    plt = pyplot()
    names = (crane.axes[0].position, crane.hook[0], crane.hook[-1], crane.load[0], crane.load[-1])
    x, x1, y1, x2, y2 = (column(n) for n in names)
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
    clock = GlyphText(clock, fig.canvas.get_renderer())  # drawn onto each frame's copy from glyphs rendered once
    images = []
    for n, i in enumerate(frames):
        trolley.set_x(x[i] - 0.15)
        cables.set_data([x[i], x1[i], x2[i]], [0.0, y1[i], y2[i]])
        hook.set_data([x1[i]], [y1[i]])
        payload.set_data([x2[i]], [y2[i]])
        first = np.searchsorted(t, t[i] - 2.0)  # the payload's path over the last 2 s
        trail.set_data(x2[first:i + 1], y2[first:i + 1])
        fig.canvas.restore_region(background)
        for artist in (trail, cables, trolley, hook, payload):
            ax.draw_artist(artist)
        images.append(np.asarray(fig.canvas.buffer_rgba()).copy())  # RGBA: a plain copy (the alpha goes when written)
        clock.draw(images[-1], f"t = {t[i]:5.2f} s   hook {math.degrees(math.atan2(x1[i] - x[i], -y1[i])):+5.1f} deg")
        show_progress(n, len(frames), progress)
    plt.close(fig)
    return images


def frame_delay(fps):
    """Seconds between frames for ``fps``: whole centiseconds (as GIF stores them), at least 2 (browsers
    show shorter delays as 10)."""
    return max(2, round(100 / fps)) / 100


def _write_gif(images, path, delay_cs):
    """A GIF of RGB (or opaque RGBA) frames, each shown ``delay_cs`` centiseconds. Not optimised: Pillow's
    optimisation (each frame's palette cut to the colours it uses, unchanged pixels made transparent) took 0.2 CPU-s
    of a 143-frame GIF's 0.3, for files a fifth smaller; the frames shown are the same."""
    from PIL import Image  # Pillow comes with matplotlib: the plot extra

    sample = np.concatenate([images[0][..., :3], images[len(images) // 2][..., :3], images[-1][..., :3]])
    palette = Image.fromarray(sample).quantize(colors=64, method=Image.Quantize.MEDIANCUT)  # every colour that moves
    frames = [Image.fromarray(a).convert("RGB").quantize(palette=palette, dither=Image.Dither.NONE) for a in images]
    frames[0].save(path, format="GIF", save_all=True, append_images=frames[1:], duration=10 * delay_cs, loop=0,
                   optimize=False)


def _write_mp4(images, path, fps):
    """An MP4 (H.264) of RGB (or opaque RGBA) frames through ffmpeg."""
    height, width = images[0].shape[:2]
    command = ["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s",
               f"{width}x{height}", "-r", f"{fps:.6g}", "-i", "-", "-pix_fmt", "yuv420p", "-vf",
               "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4", str(path)]
    subprocess.run(command, input=b"".join(np.ascontiguousarray(a[..., :3]).tobytes() for a in images), check=True)


def animate_all(rows, scenario, out_dir, fps=15, store=None):
    """A GIF (and an MP4 where ffmpeg is available) of each controller's nominal run of a scenario.

    An animation is drawn again only when its run changed: ``.drawn.json`` in ``out_dir`` keeps the
    case id each file was drawn from. One drawn before on this machine from the same run is copied from
    ``store`` (see :func:`kept`). Returns the paths written now.
    """
    paths = []
    for job in animation_jobs(rows, scenario, out_dir, fps):
        paths.append(draw_animation(*job, store=store))
        record_drawn(job)
    return paths


def animation_jobs(rows, scenario, out_dir, fps=15):
    """The animations :func:`animate_all` draws now of a scenario's nominal runs (those its ledger does not list as
    drawn from the same run): ``[(path, case_id, fps, title, signals)]``, each for :func:`draw_animation` (in any
    process), then :func:`record_drawn` (in one process: the ledger is one file)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    ledger = out_dir / ".drawn.json"
    drawn = json.loads(ledger.read_text()) if ledger.exists() else {}
    jobs = []
    for r in sorted(_nominal(rows, scenario), key=lambda r: r["controller"]):
        if animation_needs(r["signals"]):
            continue
        title = f"{scenario}, {r['controller']}" + ("" if r["status"] == "ok" else " (failed)")
        for suffix in (".gif", ".mp4") if shutil.which("ffmpeg") else (".gif",):
            path = out_dir / f"{scenario}_{r['controller']}{suffix}"
            if drawn.get(path.name) == f"{r['case_id']} {fps} fps" and path.exists():
                continue
            jobs.append((path, r["case_id"], fps, title, r["signals"]))
    return jobs


def draw_animation(path, case_id, fps, title, signals, store=None):
    """An animation of :func:`animation_jobs` (:func:`animate`), or its copy from ``store`` (:func:`kept`); its path."""
    return kept(path, [case_id, fps, title], lambda path: animate(signals, path, title, fps=fps), store)


def record_drawn(job):
    """Write in its folder's ledger that the animation of a job of :func:`animation_jobs` is drawn from its run."""
    path, case_id, fps = job[:3]
    ledger = Path(path).parent / ".drawn.json"
    drawn = json.loads(ledger.read_text()) if ledger.exists() else {}
    drawn[Path(path).name] = f"{case_id} {fps} fps"
    partial = ledger.with_suffix(".partial")
    partial.write_text(json.dumps(drawn, indent=1, sort_keys=True))
    partial.replace(ledger)


RUN_PICTURES = ("S1", "S2", "S7")  # the scenarios whose nominal runs plot_all draws, as OUT/<scenario>.png


def prune(rows, out_dir, scenarios):
    """Remove the pictures an earlier board left in ``out_dir`` that this one (``rows``; animated: ``scenarios``)
    does not draw: ``<scenario>.png`` of :data:`RUN_PICTURES` without a run now, and the animations the folder's
    ledger (``animations/.drawn.json``) lists of other runs. Only those: nothing else in the folder is touched.
    Returns the paths removed."""
    out_dir, removed = Path(out_dir), []
    for s in RUN_PICTURES:
        if not _nominal(rows, s) and (out_dir / f"{s}.png").is_file():
            (out_dir / f"{s}.png").unlink()
            removed.append(out_dir / f"{s}.png")
    ledger = out_dir / "animations" / ".drawn.json"
    if ledger.exists():
        drawn = json.loads(ledger.read_text())
        now = {f"{s}_{r['controller']}" for s in scenarios for r in _nominal(rows, s)
               if not animation_needs(r["signals"])}
        for name in [n for n in drawn if Path(n).stem not in now]:
            (ledger.parent / name).unlink(missing_ok=True)
            removed.append(ledger.parent / name)
            del drawn[name]
        partial = ledger.with_suffix(".partial")
        partial.write_text(json.dumps(drawn, indent=1, sort_keys=True))
        partial.replace(ledger)
    return removed
