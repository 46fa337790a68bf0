"""The reproduced Figures 4, 5, 7 and 8 (PNG), drawn from the runs' signals."""

import math
from pathlib import Path

from .paper_cases import FORMS
from .plots import pyplot, save


def _deg(values):
    return [math.degrees(v) for v in values]


def _angle_figure(runs, label, title, path):
    """Two panels, theta1 and theta2 [deg] against time, one line per run (Figures 4 and 5)."""
    plt = pyplot()
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 5.5))
    for r in runs:
        s = r["signals"]
        axes[0].plot(s["time"], _deg(s["theta1"]), lw=1, label=label(r))
        axes[1].plot(s["time"], _deg(s["theta2"]), lw=1, label=label(r))
    axes[0].set_ylabel("first-order angle theta1 [deg]")
    axes[1].set_ylabel("second-order angle theta2 [deg]")
    axes[1].set_xlabel("time [s]")
    axes[0].legend(fontsize=8, ncol=4)
    axes[0].set_title(title)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return save(fig, path)


def _loop_panels(axes, s, label, **style):
    axes[0].plot(s["time"], s["x"], label=label, **style)
    axes[1].plot(s["time"], _deg(s["theta1"]), label=label, **style)
    axes[2].plot(s["time"], _deg(s["theta2"]), label=label, **style)


FALLBACK_LIMITS = {"x": 5.0, "theta1": 180.0, "theta2": 180.0, "u": 1000.0}


def _diverged(r):
    return r["metrics"].get("outcome") == "diverges"


def _limit_to(axes, runs, keys=("x", "theta1", "theta2", "u")):
    """Y limits from the runs that did not diverge, so a blow-up does not flatten the rest."""
    for ax, key in zip(axes, keys):
        values = [v for r in runs if not _diverged(r) for v in r["signals"].get(key, [])]
        if not values:
            ax.set_ylim(-FALLBACK_LIMITS[key], FALLBACK_LIMITS[key])
            continue
        scale = math.degrees if "theta" in key else float
        low, high = scale(min(values)), scale(max(values))
        pad = 0.1 * (high - low) or 1.0
        ax.set_ylim(low - pad, high + pad)


def _style(axes, labels=("trolley x [m]", "theta1 [deg]", "theta2 [deg]")):
    for ax, label in zip(axes, labels):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)


def draw_all(results, out_dir):
    """Write figure4.png, figure5.png, figure7.png and figure8.png; return their paths."""
    plt = pyplot()
    out_dir = Path(out_dir)
    group = {g: [r for r in results.values() if r["case"].figure == g] for g in ("fig4", "fig5", "fig7", "fig8")}
    paths = [
        _angle_figure(sorted(group["fig4"], key=lambda r: r["case"].plant["theta1_0"]),
                      lambda r: f"theta1(0) = {math.degrees(r['case'].plant['theta1_0']):.0f} deg",
                      "Fig. 4: free swing, l1 = 1 m, l2 = 0.25 m", out_dir / "figure4.png"),
        _angle_figure(sorted(group["fig5"], key=lambda r: r["case"].plant["l2"]),
                      lambda r: f"l2 = {r['case'].plant['l2']:g} m",
                      "Fig. 5: free swing, l1 = 1 m, theta1(0) = 10 deg", out_dir / "figure5.png"),
    ]

    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(9, 9))
    by_form = {r["case"].form.key if r["case"].form else None: r for r in group["fig7"]}
    _loop_panels(axes, by_form[None]["signals"], "without controller", color="0.6", lw=1)
    for form in FORMS:
        r = by_form[form.key]
        end = (f" (diverged, stopped at {r['signals']['time'][-1]:.3f} s)" if not r["completed"]
               else " (diverged)" if _diverged(r) else "")
        _loop_panels(axes, r["signals"], form.label + end, lw=1)
        axes[3].plot(r["signals"]["time"], r["signals"]["u"], lw=1, label=form.label)
    axes[0].set_title("Fig. 7: with and without the backstepping controller (Section V)")
    axes[0].legend(fontsize=8)
    axes[3].set_xlabel("time [s]")
    _limit_to(axes, group["fig7"])
    _style(axes, ("trolley x [m]", "theta1 [deg]", "theta2 [deg]", "u [m/s2]"))
    paths.append(save(fig, out_dir / "figure7.png"))

    fig, axes = plt.subplots(3, len(FORMS), sharex="col", figsize=(13, 8), squeeze=False)
    for col, form in enumerate(FORMS):
        runs = sorted((r for r in group["fig8"] if r["case"].form == form), key=lambda r: r["case"].plant["l1"])
        for r in runs:
            end = (f" (diverged at {r['signals']['time'][-1]:.3f} s)" if not r["completed"]
                   else " (diverged)" if _diverged(r) else "")
            _loop_panels(axes[:, col], r["signals"], f"l1 = {r['case'].plant['l1']:g} m{end}", lw=1,
                         ls="--" if len(runs) > 1 and r is runs[-1] else "-")
        stops = [r["signals"]["time"][-1] for r in runs]
        early = all(not r["completed"] for r in runs) and max(stops) < 0.2 * runs[0]["case"].stop_time
        if early:  # every run stopped within a fraction of the axis: a time axis of their own
            axes[0, col].set_xlim(0, 1.25 * max(stops))
        axes[0, col].set_title(f"Fig. 8, {form.label}" + (" (own time axis: every run diverged)" if early else ""))
        axes[0, col].legend(fontsize=8)
        axes[2, col].set_xlabel("time [s]")
        _limit_to(axes[:, col], runs)
        _style(axes[:, col])
    paths.append(save(fig, out_dir / "figure8.png"))
    return paths
