"""The scoreboard's pictures: comparison plots and animations of the crane (matplotlib, Agg)."""

import math
import shutil
from pathlib import Path

import numpy as np

from .plots import pyplot, save
from .scoreboard import SCENARIOS

COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:gray")


def _colours(rows):
    """One colour per controller, the same in every picture."""
    names = list(dict.fromkeys(r["controller"] for r in rows))
    return {name: COLOURS[i % len(COLOURS)] for i, name in enumerate(names)}


def _nominal(rows, scenario):
    return [r for r in rows if r["scenario"] == scenario and r.get("signals")]


def plot_runs(rows, scenario, path):
    """Trolley position, both angles and u against time, one line per controller, for a scenario's nominal case."""
    runs = _nominal(rows, scenario)
    if not runs:
        return None
    plt = pyplot()
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 9))
    colours = _colours(rows)
    for r in runs:
        s, colour = r["signals"], colours[r["controller"]]
        label = r["controller"] + ("" if r["status"] == "ok" else " (failed)")
        axes[0].plot(s["time"], s["plant.x"], color=colour, lw=1.2, label=label)
        axes[1].plot(s["time"], np.degrees(s["plant.theta1"]), color=colour, lw=1.2)
        axes[2].plot(s["time"], np.degrees(s["plant.theta2"]), color=colour, lw=1.2)
        axes[3].plot(s["time"], s["controller.u"], color=colour, lw=1.2)
    for ax, label in zip(axes, ("trolley x [m]", "hook angle theta1 [deg]", "payload angle theta2 [deg]",
                                "demanded u [m/s2]")):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    finite = [v for r in runs for v in np.degrees(r["signals"]["plant.theta1"]) if math.isfinite(v)]
    limit = min(max(abs(min(finite)), abs(max(finite)), 1.0) * 1.1, 90.0)
    axes[1].set_ylim(-limit, limit)
    axes[2].set_ylim(-limit, limit)
    axes[3].set_ylim(-3, 3)  # the drive gives at most 2 m/s2; larger demands are clipped in the picture
    axes[0].legend(fontsize=8, loc="best")
    axes[0].set_title(f"{scenario}: {SCENARIOS[scenario].title}")
    axes[-1].set_xlabel("time [s]")
    return save(fig, path, dpi=100)


def plot_summary(rows, path):
    """Per scenario, each controller's ranking metric (worst case), as bars; failures marked."""
    from .scoreboard import summarise

    plt = pyplot()
    scenarios = [s for s in SCENARIOS if summarise(rows, s)]
    colours = _colours(rows)
    fig, axes = plt.subplots(1, len(scenarios), figsize=(2.6 * len(scenarios), 3.8), squeeze=False)
    for ax, sid in zip(axes[0], scenarios):
        lines = summarise(rows, sid)
        key = SCENARIOS[sid].rank_by
        names = [line["controller"] for line in lines]
        values = [line[key] if line[key] is not None and not line["failed"] else 0.0 for line in lines]
        bars = ax.bar(range(len(names)), values, color=[colours[n] for n in names])
        for bar, line in zip(bars, lines):
            if line["failed"] or line[key] is None:
                ax.text(bar.get_x() + bar.get_width() / 2, 0, "failed" if line["failed"] else "never",
                        ha="center", va="bottom", rotation=90, fontsize=8)
        limit = next((t.limit for t in SCENARIOS[sid].targets if t.metric == key), None)
        if limit is not None:
            ax.axhline(limit, color="k", ls="--", lw=0.8, label="target")
        ax.set_xticks(range(len(names)), [n.replace("Controller", "") for n in names], rotation=45, ha="right",
                      fontsize=8)
        ax.set_title(f"{sid}: {key}", fontsize=9)
    return save(fig, path, dpi=100)


def plot_all(rows, out_dir):
    paths = [plot_runs(rows, s, Path(out_dir) / f"{s}.png") for s in ("S1", "S2", "S7")]
    return [p for p in paths if p] + [plot_summary(rows, Path(out_dir) / "summary.png")]


def animate(signals, path, title="", fps=25):
    """An animation of the crane: rail, trolley, both cables, hook and payload, with the time.

    ``signals`` holds ``time`` and the plant's ``x``, ``x1``, ``y1``, ``x2``, ``y2`` (any
    instance prefix). Written as GIF (pillow), or MP4 when the path ends in .mp4 (needs ffmpeg).
    """
    plt = pyplot()
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter

    def column(name):
        return np.asarray(next(v for k, v in signals.items() if k == name or k.endswith("." + name)))

    t, x, x1, y1, x2, y2 = (column(n) for n in ("time", "x", "x1", "y1", "x2", "y2"))
    every = max(1, round(1.0 / (fps * (t[1] - t[0]))))
    frames = range(0, len(t), every)
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    span = [min(x.min(), x2.min()) - 0.6, max(x.max(), x2.max()) + 0.6]
    ax.set_xlim(*span)
    ax.set_ylim(min(y2.min(), -1.0) - 0.3, 0.35)
    ax.set_aspect("equal")
    ax.plot(span, [0.05, 0.05], color="0.3", lw=3)  # the rail
    ax.set_xlabel("x [m]")
    ax.set_title(title, fontsize=10)
    trolley = plt.Rectangle((x[0] - 0.15, 0.0), 0.3, 0.1, color="0.35")
    ax.add_patch(trolley)
    (cables,) = ax.plot([], [], color="k", lw=1.5)
    (hook,) = ax.plot([], [], "o", color="tab:blue", ms=7)
    (payload,) = ax.plot([], [], "s", color="tab:orange", ms=13)
    (trail,) = ax.plot([], [], color="tab:orange", lw=0.6, alpha=0.5)
    clock = ax.text(0.02, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)

    def draw(i):
        trolley.set_x(x[i] - 0.15)
        cables.set_data([x[i], x1[i], x2[i]], [0.0, y1[i], y2[i]])
        hook.set_data([x1[i]], [y1[i]])
        payload.set_data([x2[i]], [y2[i]])
        trail.set_data(x2[max(0, i - 2 * fps * every):i + 1], y2[max(0, i - 2 * fps * every):i + 1])
        clock.set_text(f"t = {t[i]:5.2f} s   hook {math.degrees(math.atan2(x1[i] - x[i], -y1[i])):+5.1f} deg")
        return trolley, cables, hook, payload, trail, clock

    animation = FuncAnimation(fig, draw, frames=frames, blit=True)
    path = Path(path)
    writer = FFMpegWriter(fps=fps) if path.suffix == ".mp4" else PillowWriter(fps=fps)
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    animation.save(partial, writer=writer, dpi=80)
    partial.replace(path)
    plt.close(fig)
    return path


def animate_all(rows, scenario, out_dir):
    """A GIF (and an MP4 where ffmpeg is available) of each controller's nominal run of a scenario."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for r in _nominal(rows, scenario):
        if "plant.x2" not in r["signals"]:
            continue
        title = f"{scenario}, {r['controller']}" + ("" if r["status"] == "ok" else " (failed)")
        for suffix in (".gif", ".mp4") if shutil.which("ffmpeg") else (".gif",):
            paths.append(animate(r["signals"], out_dir / f"{scenario}_{r['controller']}{suffix}", title, fps=15))
    return paths
