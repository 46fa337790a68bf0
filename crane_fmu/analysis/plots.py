"""Plots of co-simulation results (matplotlib, Agg backend)."""

import math
import textwrap

from .metrics import crane_signals, demand_columns

MAX_PANELS = 8


def pyplot():
    """matplotlib's pyplot on the Agg backend (no screen), imported on first use (the plot extra)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path, dpi=110):
    """Lay out, write and close a figure; return ``path``."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)
    return path


def panels_of(s):
    """``[(label, values)]`` of a crane's signals (:func:`~.metrics.crane_signals`): each axis's position [m], then
    each swing angle [deg], labelled from the plant's variable descriptions (``hook swing angle theta1 [deg]``)."""
    described = {v.name: v.description for v in s["plant"].variables}

    def words(name):  # the description up to its qualifiers: "hook swing angle from vertical" -> "hook swing angle"
        return described[name].split(" from ")[0].split(",")[0].split(" (")[0].removesuffix(f" along {name}")

    crane = s["crane"]
    positions = [(f"{words(a.position)} {a.position} [m]", values) for a, values in zip(crane.axes, s["position"])]
    return positions + [(f"{words(name)} {name} [deg]", [math.degrees(v) for v in values])
                        for name, values in s["swing"].items()]


def plot_overlay(runs, path, title=""):
    """Trolley position, the swing angles and u of several runs of one crane on shared axes, to a PNG.

    ``runs`` is ``{label: columns}``; each run needs a plant's outputs (:func:`~.metrics.crane_signals`), and
    the panels are the first run's (:func:`panels_of`). The ``u`` panel shows the runs that record a demanded
    ``u`` (none: no panel), each labelled with its
    peak ``|u|``; where one run's peak is over 20 times another's, its axis is symmetric-logarithmic
    (linear within the smallest peak), so that every run's ``u`` stays readable. Without ``title`` the
    runs' labels are the title.

    Returns
    -------
    dict
        What was drawn: ``title``, ``panels`` (each ``(y label, y scale)``) and ``legend`` (the runs' labels).
    """
    plt = pyplot()


    demanded = {label: any(demand_columns(columns)) for label, columns in runs.items()}
    signals = {label: crane_signals(columns) for label, columns in runs.items()}
    first = next(iter(signals.values()))
    rows = panels_of(first)
    demand = len(rows) if any(demanded.values()) else None
    fig, axes = plt.subplots(len(rows) + (demand is not None), 1, sharex=True,
                             figsize=(9, 2.2 * (len(rows) + (demand is not None))))
    peaks = {}
    for label, s in signals.items():
        if demanded[label]:
            peaks[label] = max(float(abs(u).max()) for u in s["demand"])
            label_u = f"{label} (peak |u| {peaks[label]:.3g} m/s2)"
        else:
            label_u = f"{label} (no u recorded)" if demand is not None else label
        for i, (_, values) in enumerate(panels_of(s)):
            axes[i].plot(s["time"], values, lw=1.3, label=label_u if i == 0 else None)
        if demanded[label]:
            for u in s["demand"]:
                axes[demand].plot(s["time"], u, lw=1.3)
        elif demand is not None:
            axes[demand].plot([], [])  # keep each run's colour in every panel
    labels = [label for label, _ in rows] + ["demanded " + ", ".join(first["crane"].demands) + " [m/s2]"]
    nonzero = [p for p in peaks.values() if p > 0]
    if len(nonzero) > 1 and max(nonzero) > 20 * min(nonzero):
        axes[demand].set_yscale("symlog", linthresh=min(nonzero))
        labels[demand] += f"\n(symlog, linear within +-{min(nonzero):.3g})"
    for ax, label in zip(axes, labels):
        ax.set_ylabel(label if "\n" in label else textwrap.fill(label, 22))  # two lines: no label runs into the next
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=9)
    axes[-1].set_xlabel("time [s]")
    fig.align_ylabels(axes)
    axes[0].set_title(title or " vs ".join(runs))
    drawn = {"title": axes[0].get_title(), "panels": [(label, ax.get_yscale()) for ax, label in zip(axes, labels)],
             "legend": [text.get_text() for text in axes[0].get_legend().get_texts()]}
    save(fig, path)
    return drawn


def plot_run(columns, path, title=""):
    """Plot a run of any system to a PNG.

    A run with a crane (some instance has a registered plant's outputs) shows
    the trolley's position, the swing angles (:func:`panels_of`) and the demands
    if some other instance gives them; any other run shows its outputs, one
    panel each (the first :data:`MAX_PANELS`).

    Parameters
    ----------
    columns : dict
        Result columns (``time``, then ``instance.variable``), as from ``read_csv``.
    """
    plt = pyplot()


    t = columns["time"]
    try:
        s = crane_signals(columns)
        panels = [(label, values, color) for (label, values), color in
                  zip(panels_of(s), [None] * len(s["position"]) + ["tab:blue", "tab:orange"] * len(s["swing"]))]
        drive = [values for name, values in columns.items() if name.endswith(".ddx")]
        if any(demand_columns(columns)):
            panels += [(f"{name} [m/s2]", u, "tab:red") for name, u in zip(s["crane"].demands, s["demand"])]
        elif drive and drive[0].any():  # no controller: the plant's own record of its acceleration
            panels.append(("trolley acceleration [m/s2]", drive[0], "tab:red"))
        hoisted = [values for name, values in columns.items()
                   if name.endswith(".l1_now") and values.min() < values.max()]
        if hoisted:
            panels.append(("l1 [m]", hoisted[0], "tab:green"))
    except ValueError:
        panels = [(name, values, None) for name, values in columns.items() if name != "time"][:MAX_PANELS]
    if not panels:
        raise ValueError("nothing to plot: the run recorded no outputs")
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(8, 2.2 * len(panels)), squeeze=False)
    for ax, (label, values, color) in zip(axes[:, 0], panels):
        ax.plot(t, values, color=color)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.align_ylabels(axes[:, 0])
    if title:
        axes[0, 0].set_title(title)
    save(fig, path)
