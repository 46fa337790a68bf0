"""Pictures of a crane that moves in two horizontal axes (``CranePlant3D``), read by the plant's roles.

- :func:`plot_top`: the trolley's, the hook's and the load's paths seen from above (``crane.axes``' positions,
  ``crane.hook`` and ``crane.load``'s horizontal coordinates), with a corridor around a centre line of waypoints
  (the racks of scenario S13) and how far the load came from that line;
- :func:`plot_swing`: each cable's swing angle over time (``crane.swing``: for the spatial crane the angle from the
  vertical in space, ``swing1`` and ``swing2``).

Results of different plants in one picture are refused (:func:`same_plant`): their signals do not compare.
"""

import math

import numpy as np

from .glyph_text import GlyphText
from .metrics import crane_signals, find_crane
from .plots import pyplot, save


def same_plant(runs):
    """``{label: crane_signals(columns, hook and load)}`` of runs of one plant; ValueError (one line) else."""
    signals = {}
    for label, columns in runs.items():
        _, plant = find_crane(columns)
        signals[label] = crane_signals(columns, (*plant.crane.hook, *plant.crane.load) if plant else ())
    kinds = {label: s["plant"].model_identifier for label, s in signals.items()}
    if len(set(kinds.values())) > 1:
        first, *_, other = sorted(kinds.items(), key=lambda item: item[1])
        raise ValueError(f"{first[0]} is a {first[1]} result and {other[0]} a {other[1]} one: one plot takes the "
                         "results of one plant")
    return signals


def horizontal(crane):
    """Whether ``crane`` moves in two horizontal axes and says where its hook and load are in both (a top view)."""
    return len(crane.axes) == 2 and len(crane.hook) == 3 and len(crane.load) == 3


def parse_corridor(text, width):
    """``[(x, y), ...]`` of ``--corridor X0,Y0,X1,Y1,...`` and its ``--corridor-width``; ValueError (one line)."""
    try:
        numbers = [float(item) for item in text.split(",")]
    except ValueError:
        raise ValueError(f"--corridor {text}: numbers X0,Y0,X1,Y1,... [m] separated by commas") from None
    if len(numbers) < 4 or len(numbers) % 2 or not all(map(math.isfinite, numbers)):
        raise ValueError(f"--corridor {text}: at least two points X0,Y0,X1,Y1 of finite numbers, in pairs")
    if width is None:
        raise ValueError("--corridor needs --corridor-width W: the corridor's width [m], > 0")
    if not (math.isfinite(width) and width > 0):
        raise ValueError(f"--corridor-width must be > 0 and finite with --corridor, got {width}")
    return list(zip(numbers[0::2], numbers[1::2]))


def distance_to_path(points, px, py):
    """The distance of each point ``(px[k], py[k])`` to the polyline ``points`` (its segments, ends included)."""
    px, py = np.asarray(px, float), np.asarray(py, float)
    best = np.full(px.shape, np.inf)
    for (ax, ay), (bx, by) in zip(points, points[1:]):
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        s = np.clip(((px - ax) * dx + (py - ay) * dy) / length2, 0.0, 1.0) if length2 > 0 else np.zeros_like(px)
        best = np.minimum(best, np.hypot(px - (ax + s * dx), py - (ay + s * dy)))
    return best


def _draw_corridor(ax, points, width):
    """The corridor: every point within ``width / 2`` of the centre line (each segment a band, each corner a disc)."""
    from matplotlib.patches import Circle, Polygon

    half = width / 2
    style = {"facecolor": "0.88", "edgecolor": "none", "zorder": 0}
    for (ax_, ay), (bx, by) in zip(points, points[1:]):
        length = math.hypot(bx - ax_, by - ay)
        if length == 0:
            continue
        nx, ny = -(by - ay) / length * half, (bx - ax_) / length * half
        ax.add_patch(Polygon([(ax_ + nx, ay + ny), (bx + nx, by + ny), (bx - nx, by - ny), (ax_ - nx, ay - ny)],
                             **style))
    for x, y in points:
        ax.add_patch(Circle((x, y), half, **style))
    xs, ys = zip(*points)
    ax.plot(xs, ys, ls=":", color="0.45", lw=1, label=f"corridor's centre line (width {width:g} m)")


def plot_top(runs, path, title="", corridor=None, width=None):
    """The paths seen from above of runs of a crane with two horizontal axes, to a PNG.

    Each run's trolley (dashed), hook (thin) and load (thick) in its own colour, the load's start (circle) and end
    (cross); with ``corridor`` (``[(x, y), ...]``, the centre line) and ``width``, the corridor shaded and, in the
    legend, the load's largest distance from the centre line (over ``width / 2``: it left the corridor).

    Returns
    -------
    dict
        ``title``, ``legend`` (its texts) and ``apart`` (``{label: the load's largest distance from the centre
        line [m]}``, with a corridor).

    Raises
    ------
    ValueError
        One line: results of different plants, or of a plant without two horizontal axes.
    """
    signals = same_plant(runs)
    s0 = next(iter(signals.values()))
    if not horizontal(s0["crane"]):
        axes = ", ".join(a.position for a in s0["crane"].axes)
        raise ValueError(f"--view top needs a crane that moves in two horizontal axes; {next(iter(signals))} is a "
                         f"{s0['plant'].model_identifier} result (axes {axes})")
    crane = s0["crane"]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    if corridor:
        _draw_corridor(ax, corridor, width)
    apart = {}
    for (label, s), color in zip(signals.items(), plt.rcParams["axes.prop_cycle"].by_key()["color"] * 10):
        (tx, ty), (hx, hy), (lx, ly) = s["position"], (s[crane.hook[0]], s[crane.hook[1]]), \
            (s[crane.load[0]], s[crane.load[1]])
        text = f"{label}: load"
        if corridor:
            apart[label] = float(distance_to_path(corridor, lx, ly).max())
            text += f" (at most {apart[label]:.3f} m from the centre line" + \
                (", left the corridor)" if apart[label] > width / 2 else ")")
        ax.plot(tx, ty, ls="--", lw=1, color=color, alpha=0.8, label=f"{label}: trolley")
        ax.plot(hx, hy, lw=0.8, color=color, alpha=0.6, label=f"{label}: hook")
        ax.plot(lx, ly, lw=2.0, color=color, label=text)
        ax.plot(lx[:1], ly[:1], "o", color=color, ms=6)
        ax.plot(lx[-1:], ly[-1:], "x", color=color, ms=9, mew=2)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{crane.axes[0].position} [m]")
    ax.set_ylabel(f"{crane.axes[1].position} [m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title or "seen from above: " + " vs ".join(runs) + " (o start, x end of the load)", fontsize=10)
    drawn = {"title": ax.get_title(), "legend": [t.get_text() for t in ax.get_legend().get_texts()], "apart": apart}
    save(fig, path)
    return drawn


def plot_swing(runs, path, title=""):
    """Each cable's swing angle over time (``crane.swing``, in degrees) of runs of one plant, a panel a cable.

    Returns
    -------
    dict
        ``title``, ``panels`` (their y labels) and ``peaks`` (``{label: [largest |angle| per cable, deg]}``).
    """
    signals = same_plant(runs)
    s0 = next(iter(signals.values()))
    described = {v.name: v.description for v in s0["plant"].variables}
    names = list(s0["swing"])
    plt = pyplot()
    fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(9, 2.6 * len(names)), squeeze=False)
    peaks = {}
    for label, s in signals.items():
        peaks[label] = []
        for ax, name in zip(axes[:, 0], names):
            degrees = np.degrees(s["swing"][name])
            peaks[label].append(float(np.abs(degrees).max()))
            ax.plot(s["time"], degrees, lw=1.2, label=f"{label} (peak {peaks[label][-1]:.3g} deg)")
    for ax, name in zip(axes[:, 0], names):
        ax.set_ylabel(f"{name} [deg]")
        ax.set_title(described[name], fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1, 0].set_xlabel("time [s]")
    fig.align_ylabels(axes[:, 0])
    fig.suptitle(title or "swing of each cable: " + " vs ".join(runs), fontsize=10)
    drawn = {"title": fig._suptitle.get_text(), "panels": [ax.get_ylabel() for ax in axes[:, 0]], "peaks": peaks}
    save(fig, path)
    return drawn


def spatial_frames(column, crane, t, frames, title="", progress=False):
    """The animation's frames (RGB arrays) of a crane in two horizontal axes: three views side by side, the x-z
    plane, the y-z plane (each the cables' projection) and the top view with the load's path so far.

    ``column(name)`` gives a recorded output by name; ``frames`` the sample shown in each frame.
    """
    from .score_plots import show_progress

    plt = pyplot()
    (px, py), hook, load = [a.position for a in crane.axes], crane.hook, crane.load
    x, y = column(px), column(py)
    x1, y1, z1 = (column(n) for n in hook)
    x2, y2, z2 = (column(n) for n in load)
    fig, axes = plt.subplots(1, 3, figsize=(11.5, 4.0), dpi=80)
    low = min(float(z2.min()), -1.0) - 0.3
    views = ((axes[0], x, x1, x2, z1, z2, f"{px} [m]", "z [m]", f"side view, the {px}-z plane"),
             (axes[1], y, y1, y2, z1, z2, f"{py} [m]", "z [m]", f"side view, the {py}-z plane"))
    moving = []
    for ax, trolley, h, load_, hz, lz, xlabel, ylabel, name in views:
        span = [min(trolley.min(), load_.min()) - 0.6, max(trolley.max(), load_.max()) + 0.6]
        ax.set_xlim(*span)
        ax.set_ylim(low, 0.35)
        ax.set_aspect("equal")
        ax.plot(span, [0.05, 0.05], color="0.3", lw=3)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(name, fontsize=9)
        (cables,) = ax.plot([], [], color="k", lw=1.5, animated=True)
        (hook_dot,) = ax.plot([], [], "o", color="tab:blue", ms=6, animated=True)
        (load_dot,) = ax.plot([], [], "s", color="tab:orange", ms=10, animated=True)
        (cart,) = ax.plot([], [], "s", color="0.35", ms=9, animated=True)
        moving.append((ax, (trolley, h, load_, hz, lz), (cables, hook_dot, load_dot, cart)))
    top = axes[2]
    top.set_xlim(min(x.min(), x2.min()) - 0.5, max(x.max(), x2.max()) + 0.5)
    top.set_ylim(min(y.min(), y2.min()) - 0.5, max(y.max(), y2.max()) + 0.5)
    top.set_aspect("equal")
    top.set_xlabel(f"{px} [m]")
    top.set_ylabel(f"{py} [m]")
    top.set_title("seen from above", fontsize=9)
    top.grid(True, alpha=0.3)
    (path,) = top.plot([], [], color="tab:orange", lw=1.0, animated=True)
    (cables_top,) = top.plot([], [], color="k", lw=1.2, animated=True)
    (cart_top,) = top.plot([], [], "s", color="0.35", ms=9, animated=True)
    (load_top,) = top.plot([], [], "s", color="tab:orange", ms=8, animated=True)
    clock = fig.text(0.01, 0.97, "", va="top", fontsize=9, animated=True)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    clock = GlyphText(clock, fig.canvas.get_renderer())  # drawn onto each frame's copy from glyphs rendered once
    images = []
    for n, i in enumerate(frames):
        fig.canvas.restore_region(background)
        for ax, (trolley, h, load_, hz, lz), (cables, hook_dot, load_dot, cart) in moving:
            cables.set_data([trolley[i], h[i], load_[i]], [0.0, hz[i], lz[i]])
            hook_dot.set_data([h[i]], [hz[i]])
            load_dot.set_data([load_[i]], [lz[i]])
            cart.set_data([trolley[i]], [0.05])
            for artist in (cables, cart, hook_dot, load_dot):
                ax.draw_artist(artist)
        path.set_data(x2[:i + 1], y2[:i + 1])
        cables_top.set_data([x[i], x1[i], x2[i]], [y[i], y1[i], y2[i]])
        cart_top.set_data([x[i]], [y[i]])
        load_top.set_data([x2[i]], [y2[i]])
        for artist in (path, cables_top, cart_top, load_top):
            top.draw_artist(artist)
        images.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
        clock.draw(images[-1], f"t = {t[i]:5.2f} s")
        show_progress(n, len(frames), progress)
    plt.close(fig)
    return images
