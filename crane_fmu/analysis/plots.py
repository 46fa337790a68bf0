"""Plots of co-simulation results (matplotlib, Agg backend)."""

import math

from .metrics import crane_signals, u_column

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


def plot_overlay(runs, path, title=""):
    """Trolley position, both swing angles and u of several crane runs on shared axes, to a PNG.

    ``runs`` is ``{label: columns}``; each run needs an instance with outputs ``x``, ``theta1``, ``theta2``.
    The ``u`` panel shows the runs that record a demanded ``u`` (none: no panel), each labelled with its
    peak ``|u|``; where one run's peak is over 20 times another's, its axis is symmetric-logarithmic
    (linear within the smallest peak), so that every run's ``u`` stays readable. Without ``title`` the
    runs' labels are the title.

    Returns
    -------
    dict
        What was drawn: ``title``, ``panels`` (each ``(y label, y scale)``) and ``legend`` (the runs' labels).
    """
    plt = pyplot()


    demanded = {label: u_column(columns) for label, columns in runs.items()}
    panels = 4 if any(demanded.values()) else 3
    fig, axes = plt.subplots(panels, 1, sharex=True, figsize=(9, 2.2 * panels))
    peaks = {}
    for label, columns in runs.items():
        s = crane_signals(columns)
        if demanded[label]:
            peaks[label] = float(abs(s["u"]).max())
            label_u = f"{label} (peak |u| {peaks[label]:.3g} m/s2)"
        else:
            label_u = f"{label} (no u recorded)" if panels == 4 else label
        axes[0].plot(s["time"], s["x"], lw=1.3, label=label_u)
        axes[1].plot(s["time"], [math.degrees(v) for v in s["theta1"]], lw=1.3)
        axes[2].plot(s["time"], [math.degrees(v) for v in s["theta2"]], lw=1.3)
        if demanded[label]:
            axes[3].plot(s["time"], s["u"], lw=1.3)
        elif panels == 4:
            axes[3].plot([], [])  # keep each run's colour in every panel
    labels = ["trolley x [m]", "hook angle theta1 [deg]", "payload angle theta2 [deg]", "demanded u [m/s2]"]
    nonzero = [p for p in peaks.values() if p > 0]
    if len(nonzero) > 1 and max(nonzero) > 20 * min(nonzero):
        axes[3].set_yscale("symlog", linthresh=min(nonzero))
        labels[3] = f"demanded u [m/s2]\n(symlog, linear within +-{min(nonzero):.3g})"
    for ax, label in zip(axes, labels):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=9)
    axes[-1].set_xlabel("time [s]")
    fig.align_ylabels(axes)
    axes[0].set_title(title or " vs ".join(runs))
    drawn = {"title": axes[0].get_title(), "panels": [(ax.get_ylabel(), ax.get_yscale()) for ax in axes],
             "legend": [text.get_text() for text in axes[0].get_legend().get_texts()]}
    save(fig, path)
    return drawn


def plot_run(columns, path, title=""):
    """Plot a run of any system to a PNG.

    A run with a crane (some instance outputs ``x``, ``theta1``, ``theta2``)
    shows trolley position, both swing angles and ``u`` if some other instance
    gives it; any other run shows its outputs, one panel each (the first
    :data:`MAX_PANELS`).

    Parameters
    ----------
    columns : dict
        Result columns (``time``, then ``instance.variable``), as from ``read_csv``.
    """
    plt = pyplot()


    t = columns["time"]
    try:
        s = crane_signals(columns)
        panels = [("trolley x [m]", s["x"], None), ("theta1 [deg]", [math.degrees(v) for v in s["theta1"]], None),
                  ("theta2 [deg]", [math.degrees(v) for v in s["theta2"]], "tab:orange")]
        drive = [values for name, values in columns.items() if name.endswith(".ddx")]
        if any(name == "u" or name.endswith(".u") for name in columns):
            panels.append(("u [m/s2]", s["u"], "tab:red"))
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
