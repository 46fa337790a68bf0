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

DIVERGED_ANGLE = math.pi / 2  # a swing beyond 90 degrees counts as divergence
SETTLED_BAND = math.radians(0.1)  # a swing below 0.1 degree counts as settled
CONVERGING = ("converges", "decaying")  # the outcomes of classify() that head for rest
ARRIVAL_ANGLE = math.radians(0.5)  # an arrival leaves both angles within 0.5 degree
BOUND_TOLERANCE = 1e-9  # relative: a drive at its speed limit reaches it through rounding


def needs(crane):
    """The outputs the crane metrics need of the plant: each axis's position and the swing angles."""
    return tuple(a.position for a in crane.axes) + tuple(crane.swing)


def _key(instance, name):  # columns without an instance prefix (one FMU, e.g. a container) have instance ""
    return f"{instance}.{name}" if instance else name


def find_crane(columns, wanted=needs):
    """``(instance, plant)``: the first instance of a recorded run that has a registered plant's outputs
    (``wanted(crane)``, none: not this plant; by default :func:`needs` of its crane roles), and that plant's
    component; ``(None, None)`` when there is none. Where the run has the outputs of several plants (the spatial
    crane has the planar one's ``x1``, ``y1``, ...), the plant that names the most of them."""
    from crane_fmu import components

    instances = list(dict.fromkeys(name.rpartition(".")[0] for name in columns))
    found, most = (None, None), 0
    for plant in components.registered("plant"):
        if plant.crane is not None:
            names = wanted(plant.crane)
            instance = next((i for i in instances if names and all(_key(i, n) in columns for n in names)), None)
            if instance is not None and len(names) > most:
                found, most = (instance, plant), len(names)
    return found


def crane_signals(columns, extra=()):
    """A recorded run's crane signals, by the plant's roles (:class:`~crane_fmu.model.component.Crane`).

    The plant is the first instance that has a registered plant's axis positions and swing angles
    (:func:`find_crane`); its demands are the outputs of that name of the first other instance (zero when
    none gives them).

    Returns
    -------
    dict
        ``time``; ``crane`` (the plant's roles), ``plant`` (its component) and ``instance``; ``position``,
        ``velocity`` and ``demand``: a list of arrays, one per axis (a velocity the run did not record is None);
        ``swing``: ``{name: array}`` of the swing angles;
        and the plant's outputs named in ``extra`` (``x1``, ``l1_now``, ...) where it has them.

    Raises
    ------
    ValueError
        When no instance has a registered plant's outputs.
    """
    plant, component = find_crane(columns)
    if plant is None:
        from crane_fmu import components

        wanted = "; ".join(", ".join(needs(c.crane)) for c in components.registered("plant") if c.crane)
        raise ValueError(f"these results have no instance with a crane's outputs ({wanted}); columns: "
                         + ", ".join(columns))
    crane = component.crane
    demands = demand_columns(columns, plant, crane)
    return {"time": columns["time"], "crane": crane, "instance": plant, "plant": component,
            "position": [columns[_key(plant, a.position)] for a in crane.axes],
            "velocity": [columns.get(_key(plant, a.velocity)) for a in crane.axes],
            "swing": {n: columns[_key(plant, n)] for n in crane.swing},
            "demand": [columns[k] if k else np.zeros_like(columns["time"]) for k in demands],
            **plant_outputs(columns, plant, extra)}


def plant_outputs(columns, instance, names):
    """``{name: column}`` of the outputs ``names`` of ``instance`` that the run recorded."""
    return {n: columns[_key(instance, n)] for n in names if _key(instance, n) in columns}


def demand_columns(columns, plant=None, crane=None):
    """The columns of each axis's demand that :func:`crane_signals` takes (None for an axis no column gives:
    a plant alone, whose demand is then zero, and a plot must not show a demand that was never made)."""
    if crane is None:
        plant, component = find_crane(columns)
        if plant is None:
            return []
        crane = component.crane
    instances = list(dict.fromkeys(name.rpartition(".")[0] for name in columns))
    found = []
    for demand in crane.demands:
        sources = [_key(i, demand) for i in instances if i != plant] + ([demand] if plant == "" else [])
        found.append(next((k for k in sources if k in columns), None))
    return found


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


def classify(t, swing, completed, band=SETTLED_BAND):
    """``"converges"``, ``"decaying"``, ``"sustained oscillation"`` or ``"diverges"``.

    Parameters
    ----------
    swing : sequence of arrays
        The swing angles [rad] (the planar crane: theta1 and theta2).
    completed : bool
        False when the run stopped early (an FMU refused a non-finite state).
    band : float
        Swing below this [rad] over the last quarter counts as settled.

    Notes
    -----
    With ``A3`` and ``A4`` the largest swing (any angle) over the third
    and the last quarter of the run:

    - diverges: the run stopped early, a swing angle passed 90 degrees, or
      the swing grows (``A4 > 1.2 A3``);
    - converges: settled (``A4 < band``), so a settling time to ``band`` exists;
    - decaying: not settled by the end, but the swing shrinks (``A4 < 0.9 A3``);
    - otherwise (``0.9 A3 <= A4 <= 1.2 A3``) a sustained oscillation, over this run (a law that
      decays more slowly than 10 % a quarter of the run looks sustained: give it a longer run).

    :data:`CONVERGING` holds the first two.
    """
    if not completed or any(peak_abs(angle) > DIVERGED_ANGLE for angle in swing):
        return "diverges"
    span = t[-1] - t[0]
    third = (t >= t[0] + 0.5 * span) & (t < t[0] + 0.75 * span)
    last = t >= t[0] + 0.75 * span
    a3 = max(peak_abs(angle[third]) for angle in swing)
    a4 = max(peak_abs(angle[last]) for angle in swing)
    if a4 > 1.2 * a3:
        return "diverges"
    if a4 < band:
        return "converges"
    if a4 < 0.9 * a3:
        return "decaying"
    return "sustained oscillation"


def closed_loop_metrics(t, x, swing, u, completed):
    """The metrics the report gives for every closed-loop run (angles in degrees).

    ``x`` and ``u``: the trolley's position and the demand along one axis (the sum of the others' is not
    taken); ``swing``: ``{name: angle}``, each angle's figures named after it (``max_theta1_deg``).
    """
    def deg(value):
        return math.degrees(value) if math.isfinite(value) else None

    angles = list(swing.values())
    first, second = (list(swing) + [None])[:2]
    settle_05 = settling_time(t, angles, math.radians(0.5))
    settle_01 = settling_time(t, angles, math.radians(0.1))
    figures = {
        "outcome": classify(t, angles, completed),
        "completed": completed,
        "end_time_s": float(t[-1]),
        "settling_0.5deg_s": settle_05,
        "settling_0.1deg_s": settle_01,
        **{f"max_{name}_deg": deg(peak_abs(angle)) for name, angle in swing.items()},
        f"rms_{first}_deg": deg(rms(swing[first])),
    }
    if second is not None:
        a, b = swing[first], swing[second]
        finite = np.isfinite(a) & np.isfinite(b)
        varies = completed and finite.all() and np.std(a) > 0 and np.std(b) > 0
        figures[f"corr_{first}_{second}"] = float(np.corrcoef(a, b)[0, 1]) if varies else None
    figures.update({
        "residual_after_15s_deg": (deg(max(peak_abs(angle[t >= 15]) for angle in angles)) if t[-1] >= 15 else None),
        "trolley_excursion_m": _finite(peak_abs(x - x[0])),
        "trolley_final_m": _finite(float(x[-1])),
        "peak_abs_u": _finite(peak_abs(u)),
    })
    return figures


def move_metrics(t, x, dx, swing, u, x_d, residual_from=None, position_band=0.005,
                 angle_band=ARRIVAL_ANGLE, bounds=None):
    """The figures of a move to (or regulation at) ``x_d``, angles in degrees.

    Parameters
    ----------
    x, dx, u : array or sequence of arrays
        The trolley's position and velocity and the demand, one array per axis (one array: one axis).
    swing : sequence of arrays
        The swing angles [rad] (the planar crane: theta1 and theta2).
    x_d : float or sequence of float
        The target, one per axis; on two axes the position error is the distance in the plane.
    residual_from : float, optional
        Start [s] of the window of the residual swing, which the task fixes (for a move: the planned
        move's end plus one slow swing period); by default the last quarter of the run.
    bounds : dict, optional
        ``u_max`` [m/s2], ``v_max`` [m/s], ``x_min``, ``x_max`` [m] (any of them): the bounds checked at
        every sample, on every axis; a missing one is not checked.

    Returns
    -------
    dict
        ``arrival_s``: from when on the trolley stays within ``position_band`` of
        ``x_d`` and every angle within ``angle_band`` (None: never);
        ``residual_deg``: the largest swing (any angle) from ``residual_from`` to the end, as
        measured (None: the run ended before the window);
        ``settling_0.5deg_s``, ``settling_0.1deg_s``: the angles alone;
        ``position_1cm_s``: the trolley alone, within 1 cm; ``overshoot_m``: the
        farthest the trolley went past ``x_d`` (in the direction of the move);
        ``final_error_m``; ``peak_abs_u``, ``peak_abs_v`` (of any axis); ``effort``: the
        integral of u^2 (summed over the axes) with u held over each step [m2/s3]; ``end_swing_deg``: the
        largest swing over the last quarter of the run (what is left of the swing);
        ``peak_swing_deg``: the largest swing of the run; ``ise_swing_deg2s``: the integral of the
        angles' squares summed (theta1^2 + theta2^2, trapezoidal) [deg2 s]; ``rms_swing_deg``: its mean over
        the run, square-rooted; ``u_total_variation``: the sum of |u_k - u_(k-1)| [m/s2] (how much the
        command chatters, summed over the axes); ``bounds_held``: every bound held at every sample (None: no
        bounds given); ``bounds_broken``: the bounds that did not ("" when all held), each within
        :data:`BOUND_TOLERANCE` of its value.
    """
    xs, dxs, us, targets = _axes(x), _axes(dx), _axes(u), list(np.atleast_1d(x_d).astype(float))
    swing = list(swing)
    error = _distance([p - d for p, d in zip(xs, targets)])
    arrival = settling_time(t, [error] + [angle / angle_band * position_band for angle in swing], position_band)
    if residual_from is None:
        residual_from = t[0] + 0.75 * (t[-1] - t[0])
    window = t >= residual_from
    last = t >= t[0] + 0.75 * (t[-1] - t[0])
    squares = np.square(swing[0])
    for angle in swing[1:]:
        squares = squares + np.square(angle)
    ise = math.degrees(math.degrees(_trapezoid(squares, t)))
    duration = float(t[-1] - t[0])
    figures = {
        "arrival_s": arrival,
        "residual_deg": swing_deg(angle[window] for angle in swing) if window.any() else None,
        "settling_0.5deg_s": settling_time(t, swing, math.radians(0.5)),
        "settling_0.1deg_s": settling_time(t, swing, math.radians(0.1)),
        "position_1cm_s": settling_time(t, [error], 0.01),
        "overshoot_m": max(0.0, float(np.max(_along_move(xs, targets)))),
        "final_error_m": abs(float(_distance([p[-1:] - d for p, d in zip(xs, targets)])[0])),
        "peak_abs_u": max(peak_abs(v) for v in us),
        "peak_abs_v": max(peak_abs(v) for v in dxs),
        "effort": sum(float(np.sum(np.square(v[:-1]) * np.diff(t))) for v in us),
        "end_swing_deg": swing_deg(angle[last] for angle in swing),
        "peak_swing_deg": swing_deg(swing),
        "ise_swing_deg2s": _finite(ise),
        "rms_swing_deg": _finite(math.sqrt(ise / duration)) if duration > 0 else None,
        "u_total_variation": _finite(sum(float(np.sum(np.abs(np.diff(v)))) for v in us)),
    }
    figures.update(bounds_check(xs, dxs, us, bounds))
    return figures


def _axes(values):
    """One array per axis: a single array is one axis."""
    return [np.asarray(values)] if np.ndim(values) == 1 else [np.asarray(v) for v in values]


def _distance(errors):
    """The position error: on one axis the signed error itself (its size is what the bands take), on more the
    distance in the plane."""
    return errors[0] if len(errors) == 1 else np.sqrt(sum(np.square(e) for e in errors))


def _along_move(xs, targets):
    """How far past the target the trolley is, along the direction of the move (negative: short of it)."""
    if len(xs) == 1:
        direction = 1.0 if targets[0] >= xs[0][0] else -1.0
        return direction * (xs[0] - targets[0])
    start = [p[0] for p in xs]
    length = math.hypot(*(d - s for d, s in zip(targets, start)))
    if length == 0:
        return _distance([p - d for p, d in zip(xs, targets)])
    return sum((p - d) * ((d - s) / length) for p, d, s in zip(xs, targets, start))


def swing_deg(swing):
    """The largest swing of any angle [deg]."""
    return math.degrees(max(peak_abs(angle) for angle in swing))


def bounds_check(x, dx, u, bounds):
    """``{"bounds_held": bool, "bounds_broken": str}`` of the bounds given (see :func:`move_metrics`), on every
    axis (``x``, ``dx``, ``u``: an array, or one per axis).

    A bound holds when no sample passes it by more than :data:`BOUND_TOLERANCE` of its size; a
    non-finite sample breaks every bound on it.
    """
    if not bounds:
        return {"bounds_held": None, "bounds_broken": None}
    xs, dxs, us = _axes(x), _axes(dx), _axes(u)

    def beyond(extreme, bound, sign):  # np.max/np.min give nan for a non-finite run: never within
        return not sign * extreme <= sign * bound + BOUND_TOLERANCE * max(abs(bound), 1.0)

    checks = {"|u|": ("u_max", lambda b: any(beyond(np.max(np.abs(v)), b, 1) for v in us)),
              "|v|": ("v_max", lambda b: any(beyond(np.max(np.abs(v)), b, 1) for v in dxs)),
              "x_min": ("x_min", lambda b: any(beyond(np.min(v), b, -1) for v in xs)),
              "x_max": ("x_max", lambda b: any(beyond(np.max(v), b, 1) for v in xs))}
    broken = [name for name, (key, check) in checks.items()
              if key in bounds and math.isfinite(bounds[key]) and check(bounds[key])]
    return {"bounds_held": not broken, "bounds_broken": ", ".join(broken)}


def _trapezoid(y, t):
    return float(np.sum((y[1:] + y[:-1]) * np.diff(t)) / 2)


def _finite(value):
    return value if math.isfinite(value) else None
