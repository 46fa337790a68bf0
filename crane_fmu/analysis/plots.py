"""Plots of co-simulation results (matplotlib, Agg backend)."""

import math

MAX_PANELS = 8


def pyplot():
    """matplotlib's pyplot on the Agg backend (no screen), imported on first use."""
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
    """
    plt = pyplot()

    from .metrics import crane_signals

    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 8.5))
    for label, columns in runs.items():
        s = crane_signals(columns)
        axes[0].plot(s["time"], s["x"], lw=1.3, label=label)
        axes[1].plot(s["time"], [math.degrees(v) for v in s["theta1"]], lw=1.3)
        axes[2].plot(s["time"], [math.degrees(v) for v in s["theta2"]], lw=1.3)
        axes[3].plot(s["time"], s["u"], lw=1.3)
    for ax, label in zip(axes, ("trolley x [m]", "hook angle theta1 [deg]", "payload angle theta2 [deg]",
                                "demanded u [m/s2]")):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=9)
    axes[-1].set_xlabel("time [s]")
    if title:
        axes[0].set_title(title)
    save(fig, path)


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

    from .metrics import crane_signals

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
