"""Metrics of recorded runs: peaks, frequencies, settling, classification.

All functions take numpy arrays sampled on a uniform time grid, in SI units.

:data:`VERSION` is a hash of this file: every result table and journal that holds
figures made here records it, so that figures of another version of the metrics are
computed again, never mixed with these.
"""

import hashlib
import math
from pathlib import Path

import numpy as np

VERSION = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()[:16]

CRANE_OUTPUTS = ("x", "theta1", "theta2")  # what the crane metrics need from some instance
DIVERGED_ANGLE = math.pi / 2  # a swing beyond 90 degrees counts as divergence
SETTLED_BAND = math.radians(0.1)  # a swing below 0.1 degree counts as settled
CONVERGING = ("converges", "decaying")  # the outcomes of classify() that head for rest
ARRIVAL_ANGLE = math.radians(0.5)  # an arrival leaves both angles within 0.5 degree
BOUND_TOLERANCE = 1e-9  # relative: a drive at its speed limit reaches it through rounding


def crane_signals(columns, extra=()):
    """``time``, ``x``, ``theta1``, ``theta2`` and ``u`` of a recorded run of any system (and of ``extra``).

    The crane signals are the outputs ``x``, ``theta1``, ``theta2`` of the first
    instance that has all three, and ``u`` of the first other instance that
    outputs ``u`` (zero when none does). ``extra`` names more outputs of that first
    instance (``dx``, ``x1``, ...), kept where it has them.

    Raises
    ------
    ValueError
        When no instance outputs ``x``, ``theta1`` and ``theta2``.
    """
    def key(instance, name):  # columns without an instance prefix (one FMU, e.g. a container) have instance ""
        return f"{instance}.{name}" if instance else name

    instances = list(dict.fromkeys(name.rpartition(".")[0] for name in columns))
    plant = next((i for i in instances if all(key(i, n) in columns for n in CRANE_OUTPUTS)), None)
    if plant is None:
        raise ValueError(f"these results have no instance with outputs {', '.join(CRANE_OUTPUTS)}; columns: "
                         + ", ".join(columns))
    signals = {"time": columns["time"], **{n: columns[key(plant, n)] for n in CRANE_OUTPUTS + tuple(extra)
                                           if key(plant, n) in columns}}
    source = u_column(columns)
    signals["u"] = columns[source] if source else np.zeros_like(columns["time"])
    return signals


def u_column(columns):
    """The column of the demanded ``u`` that :func:`crane_signals` takes, or None when no column gives it
    (a plant alone: its ``u`` is then zero, and a plot must not show a demand that was never made)."""
    instances = list(dict.fromkeys(name.rpartition(".")[0] for name in columns))
    plant = next((i for i in instances if all((f"{i}.{n}" if i else n) in columns for n in CRANE_OUTPUTS)), None)
    sources = [f"{i}.u" if i else "u" for i in instances if i != plant] + (["u"] if plant == "" else [])
    return next((k for k in sources if k in columns), None)


def peak_abs(values):
    """Largest absolute value."""
    return float(np.max(np.abs(values)))


def rms(values):
    """Root mean square."""
    return float(np.sqrt(np.mean(np.square(values))))


def dominant_frequencies(t, signal, count=2, min_relative_power=0.05):
    """The strongest spectral peaks of ``signal`` [Hz], strongest first.

    Uses a Hann-windowed FFT with 8x zero padding and parabolic interpolation
    of each peak; peaks weaker than ``min_relative_power`` times the strongest
    are dropped.
    """
    x = np.asarray(signal, float) - np.mean(signal)
    dt = float(t[1] - t[0])
    n = len(x)
    nfft = 8 * int(2 ** math.ceil(math.log2(n)))
    power = np.abs(np.fft.rfft(x * np.hanning(n), nfft)) ** 2
    freqs = np.fft.rfftfreq(nfft, dt)
    is_peak = (power[1:-1] > power[:-2]) & (power[1:-1] >= power[2:])
    idx = np.nonzero(is_peak)[0] + 1
    idx = idx[np.argsort(power[idx])[::-1]]
    if len(idx) == 0:
        return []
    found = []
    for i in idx:
        if power[i] < min_relative_power * power[idx[0]] or len(found) == count:
            break
        a, b, c = np.log(power[i - 1:i + 2] + 1e-300)
        shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c != 0 else 0.0
        found.append(float(freqs[i] + shift * (freqs[1] - freqs[0])))
    return found


def settling_time(t, signals, band):
    """Earliest time after which every signal stays within ``[-band, band]``.

    Returns None when some signal is outside the band at the last sample.
    """
    inside = np.all([np.abs(s) <= band for s in signals], axis=0)
    if not inside[-1]:
        return None
    outside = np.nonzero(~inside)[0]
    return float(t[0]) if len(outside) == 0 else float(t[outside[-1] + 1])


def classify(t, theta1, theta2, completed, band=SETTLED_BAND):
    """``"converges"``, ``"decaying"``, ``"sustained oscillation"`` or ``"diverges"``.

    Parameters
    ----------
    completed : bool
        False when the run stopped early (an FMU refused a non-finite state).
    band : float
        Swing below this [rad] over the last quarter counts as settled.

    Notes
    -----
    With ``A3`` and ``A4`` the largest swing (either angle) over the third
    and the last quarter of the run:

    - diverges: the run stopped early, a swing angle passed 90 degrees, or
      the swing grows (``A4 > 1.2 A3``);
    - converges: settled (``A4 < band``), so a settling time to ``band`` exists;
    - decaying: not settled by the end, but the swing shrinks (``A4 < 0.9 A3``);
    - otherwise (``0.9 A3 <= A4 <= 1.2 A3``) a sustained oscillation, over this run (a law that
      decays more slowly than 10 % a quarter of the run looks sustained: give it a longer run).

    :data:`CONVERGING` holds the first two.
    """
    if not completed or peak_abs(theta1) > DIVERGED_ANGLE or peak_abs(theta2) > DIVERGED_ANGLE:
        return "diverges"
    span = t[-1] - t[0]
    third = (t >= t[0] + 0.5 * span) & (t < t[0] + 0.75 * span)
    last = t >= t[0] + 0.75 * span
    a3 = max(peak_abs(theta1[third]), peak_abs(theta2[third]))
    a4 = max(peak_abs(theta1[last]), peak_abs(theta2[last]))
    if a4 > 1.2 * a3:
        return "diverges"
    if a4 < band:
        return "converges"
    if a4 < 0.9 * a3:
        return "decaying"
    return "sustained oscillation"


def closed_loop_metrics(t, x, theta1, theta2, u, completed):
    """The metrics the report gives for every closed-loop run (angles in degrees)."""
    def deg(value):
        return math.degrees(value) if math.isfinite(value) else None

    settle_05 = settling_time(t, [theta1, theta2], math.radians(0.5))
    settle_01 = settling_time(t, [theta1, theta2], math.radians(0.1))
    finite = np.isfinite(theta1) & np.isfinite(theta2)
    corr = (float(np.corrcoef(theta1, theta2)[0, 1])
            if completed and finite.all() and np.std(theta1) > 0 and np.std(theta2) > 0 else None)
    return {
        "outcome": classify(t, theta1, theta2, completed),
        "completed": completed,
        "end_time_s": float(t[-1]),
        "settling_0.5deg_s": settle_05,
        "settling_0.1deg_s": settle_01,
        "max_theta1_deg": deg(peak_abs(theta1)),
        "max_theta2_deg": deg(peak_abs(theta2)),
        "rms_theta1_deg": deg(rms(theta1)),
        "corr_theta1_theta2": corr,
        "residual_after_15s_deg": (deg(max(peak_abs(theta1[t >= 15]), peak_abs(theta2[t >= 15])))
                                   if t[-1] >= 15 else None),
        "trolley_excursion_m": _finite(peak_abs(x - x[0])),
        "trolley_final_m": _finite(float(x[-1])),
        "peak_abs_u": _finite(peak_abs(u)),
    }


def move_metrics(t, x, dx, theta1, theta2, u, x_d, residual_from=None, position_band=0.005,
                 angle_band=ARRIVAL_ANGLE, bounds=None):
    """The figures of a move to (or regulation at) ``x_d``, angles in degrees.

    Parameters
    ----------
    residual_from : float, optional
        Start [s] of the window of the residual swing, which the task fixes (for a move: the planned
        move's end plus one slow swing period); by default the last quarter of the run.
    bounds : dict, optional
        ``u_max`` [m/s2], ``v_max`` [m/s], ``x_min``, ``x_max`` [m] (any of them): the bounds checked at
        every sample; a missing one is not checked.

    Returns
    -------
    dict
        ``arrival_s``: from when on the trolley stays within ``position_band`` of
        ``x_d`` and both angles within ``angle_band`` (None: never);
        ``residual_deg``: the largest swing (either angle) from ``residual_from`` to the end, as
        measured (None: the run ended before the window);
        ``settling_0.5deg_s``, ``settling_0.1deg_s``: the angles alone;
        ``position_1cm_s``: the trolley alone, within 1 cm; ``overshoot_m``: the
        farthest the trolley went past ``x_d`` (in the direction of the move);
        ``final_error_m``; ``peak_abs_u``, ``peak_abs_v``; ``effort``: the
        integral of u^2 with u held over each step [m2/s3]; ``end_swing_deg``: the
        largest swing over the last quarter of the run (what is left of the swing);
        ``peak_swing_deg``: the largest swing of the run; ``ise_swing_deg2s``: the integral of
        theta1^2 + theta2^2 (trapezoidal) [deg2 s]; ``rms_swing_deg``: its mean over the run, square-rooted;
        ``u_total_variation``: the sum of |u_k - u_(k-1)| [m/s2] (how much the command chatters);
        ``bounds_held``: every bound held at every sample (None: no bounds given); ``bounds_broken``:
        the bounds that did not ("" when all held), each within :data:`BOUND_TOLERANCE` of its value.
    """
    arrival = settling_time(t, [x - x_d, theta1 / angle_band * position_band, theta2 / angle_band * position_band],
                            position_band)
    if residual_from is None:
        residual_from = t[0] + 0.75 * (t[-1] - t[0])
    window = t >= residual_from
    last = t >= t[0] + 0.75 * (t[-1] - t[0])
    direction = 1.0 if x_d >= x[0] else -1.0
    ise = math.degrees(math.degrees(_trapezoid(np.square(theta1) + np.square(theta2), t)))
    duration = float(t[-1] - t[0])
    figures = {
        "arrival_s": arrival,
        "residual_deg": swing_deg(theta1[window], theta2[window]) if window.any() else None,
        "settling_0.5deg_s": settling_time(t, [theta1, theta2], math.radians(0.5)),
        "settling_0.1deg_s": settling_time(t, [theta1, theta2], math.radians(0.1)),
        "position_1cm_s": settling_time(t, [x - x_d], 0.01),
        "overshoot_m": max(0.0, float(np.max(direction * (x - x_d)))),
        "final_error_m": abs(float(x[-1]) - x_d),
        "peak_abs_u": peak_abs(u),
        "peak_abs_v": peak_abs(dx),
        "effort": float(np.sum(np.square(u[:-1]) * np.diff(t))),
        "end_swing_deg": swing_deg(theta1[last], theta2[last]),
        "peak_swing_deg": swing_deg(theta1, theta2),
        "ise_swing_deg2s": _finite(ise),
        "rms_swing_deg": _finite(math.sqrt(ise / duration)) if duration > 0 else None,
        "u_total_variation": _finite(float(np.sum(np.abs(np.diff(u))))),
    }
    figures.update(bounds_check(x, dx, u, bounds))
    return figures


def swing_deg(theta1, theta2):
    """The largest swing of either angle [deg]."""
    return math.degrees(max(peak_abs(theta1), peak_abs(theta2)))


def bounds_check(x, dx, u, bounds):
    """``{"bounds_held": bool, "bounds_broken": str}`` of the bounds given (see :func:`move_metrics`).

    A bound holds when no sample passes it by more than :data:`BOUND_TOLERANCE` of its size; a
    non-finite sample breaks every bound on it.
    """
    if not bounds:
        return {"bounds_held": None, "bounds_broken": None}

    def beyond(extreme, bound, sign):  # np.max/np.min give nan for a non-finite run: never within
        return not sign * extreme <= sign * bound + BOUND_TOLERANCE * max(abs(bound), 1.0)

    checks = {"|u|": ("u_max", lambda b: beyond(np.max(np.abs(u)), b, 1)),
              "|v|": ("v_max", lambda b: beyond(np.max(np.abs(dx)), b, 1)),
              "x_min": ("x_min", lambda b: beyond(np.min(x), b, -1)),
              "x_max": ("x_max", lambda b: beyond(np.max(x), b, 1))}
    broken = [name for name, (key, check) in checks.items()
              if key in bounds and math.isfinite(bounds[key]) and check(bounds[key])]
    return {"bounds_held": not broken, "bounds_broken": ", ".join(broken)}


def _trapezoid(y, t):
    return float(np.sum((y[1:] + y[:-1]) * np.diff(t)) / 2)


def _finite(value):
    return value if math.isfinite(value) else None
