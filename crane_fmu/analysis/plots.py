"""Plots of co-simulation results (matplotlib, Agg backend)."""

import math


def plot_run(columns, path, title=""):
    """Trolley position, both swing angles and the control input against time, to a PNG.

    Parameters
    ----------
    columns : dict
        Result columns (``time``, ``plant.x``, ``plant.theta1``, ... and
        optionally ``controller.u``), as from ``read_csv``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = columns["time"]
    has_u = "controller.u" in columns
    fig, axes = plt.subplots(3 + has_u, 1, sharex=True, figsize=(8, 2.2 * (3 + has_u)))
    axes[0].plot(t, columns["plant.x"])
    axes[0].set_ylabel("trolley x [m]")
    axes[1].plot(t, [math.degrees(v) for v in columns["plant.theta1"]])
    axes[1].set_ylabel("theta1 [deg]")
    axes[2].plot(t, [math.degrees(v) for v in columns["plant.theta2"]], color="tab:orange")
    axes[2].set_ylabel("theta2 [deg]")
    if has_u:
        axes[3].plot(t, columns["controller.u"], color="tab:red")
        axes[3].set_ylabel("u [m/s2]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
