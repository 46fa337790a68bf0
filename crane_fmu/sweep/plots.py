"""A study's chosen metric over two varied parameters: heat maps, one panel per value of the other axes."""

import math

import numpy as np

OUTCOME_CODES = {"converges": 0, "decaying": 1, "sustained oscillation": 2, "diverges": 3}


def _value(row, metric):
    value = row.get(metric)
    if metric == "outcome":
        return OUTCOME_CODES.get(value, math.nan)
    return math.nan if value is None else float(value)


def _label(value, unit=None):
    if isinstance(value, float) and unit in ("rad", "rad/s"):
        value = math.degrees(value)
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _name(name, unit):
    """An axis name with its unit; angles are shown in degrees."""
    return f"{name} [{unit.replace('rad', 'deg')}]" if unit else name


def _order(values):
    """Numbers in numeric order, other values as text."""
    return sorted(set(values), key=lambda v: (0, v, "") if isinstance(v, (int, float)) else (1, 0, str(v)))


def plot_study(rows, study, path, max_panels=12, units=None):
    """Plot ``study.plot`` (default: outcome over the first two varied parameters) to a PNG.

    Each combination of the other grid axes gets its own panel. On a grid the
    panel is a heat map; with sampled parameters it is a scatter.
    """
    import matplotlib  # optional: the plot extra

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    units = units or {}
    axes_names = [names[0] for names, *_ in list(study.grid.values()) + list(study.sampled.values())]
    metric = study.plot.get("metric", "outcome")
    x_name, y_name = study.plot.get("x", axes_names[0]), study.plot.get("y", axes_names[1])
    others = [n for n in (names[0] for names, _ in study.grid.values()) if n not in (x_name, y_name)]
    panels = {}
    for row in rows:
        panels.setdefault(tuple(row[n] for n in others), []).append(row)
    keys = list(panels)[:max_panels]
    cols = min(len(keys), 3)
    fig, axs = plt.subplots((len(keys) + cols - 1) // cols, cols, figsize=(5 * cols, 4.6 * math.ceil(len(keys) / cols)),
                            squeeze=False, layout="constrained")
    norm = dict(vmin=0, vmax=3) if metric == "outcome" else dict(
        vmin=np.nanmin([_value(r, metric) for r in rows] + [np.inf]),
        vmax=np.nanmax([_value(r, metric) for r in rows] + [-np.inf]))
    if not all(map(math.isfinite, norm.values())):
        norm = {}
    image = None
    for ax, key in zip(axs.flat, keys):
        part = panels[key]
        xs, ys, zs = [r[x_name] for r in part], [r[y_name] for r in part], [_value(r, metric) for r in part]
        ux, uy = _order(xs), _order(ys)
        if study.sampled:
            image = ax.scatter(xs, ys, c=zs, cmap="viridis", s=40, **norm)
        else:
            grid = np.full((len(uy), len(ux)), np.nan)
            for x, y, z in zip(xs, ys, zs):
                grid[uy.index(y), ux.index(x)] = z
            image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis", **norm)
            ax.set_xticks(range(len(ux)), [_label(v, units.get(x_name)) for v in ux], rotation=60, fontsize=7)
            ax.set_yticks(range(len(uy)), [_label(v, units.get(y_name)) for v in uy], fontsize=7)
        ax.set_xlabel(_name(x_name, units.get(x_name)))
        ax.set_ylabel(_name(y_name, units.get(y_name)))
        ax.set_title(", ".join(f"{n} = {_label(v, units.get(n))}" for n, v in zip(others, key)) or metric, fontsize=8)
    for ax in list(axs.flat)[len(keys):]:
        ax.set_visible(False)
    bar = fig.colorbar(image, ax=axs, shrink=0.8)
    if metric == "outcome":
        bar.set_ticks(list(OUTCOME_CODES.values()), labels=list(OUTCOME_CODES))
    bar.set_label(f"{metric} (blank: not available)")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
