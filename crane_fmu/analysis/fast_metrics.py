"""The metrics of :mod:`crane_fmu.analysis.metrics` that the sweeps and the board compute, made by ``reductions.c``.

The batch path of native FMUs (:mod:`crane_fmu.native_batch`) computes its rows' figures with these
functions: the same arguments, the same results bit for bit, without numpy's temporary arrays (a
run's columns may be strided views of its block of rows). Each function below is the one of
``metrics.py`` of the same name, line for line: what numpy reduces is a call of ``reductions.c``,
which does numpy's arithmetic in numpy's order (its pairwise summation included); the rest is the
same Python. ``closed_loop_metrics`` leaves out the correlation of the first two angles (``corr_theta1_theta2``),
which no study asks for.

:data:`MIRRORS` is the :data:`metrics.VERSION` these functions were written against: where the
metrics module is another, :func:`available` is False and the batch path computes its figures with
the metrics module itself. Tests hold every function here to its twin on hand-made and recorded runs.
"""

import ctypes
import functools
import math
import threading
from pathlib import Path

import numpy as np

from crane_fmu.cosim.compiled_loop import compiled

from . import metrics
from .metrics import ARRIVAL_ANGLE, DIVERGED_ANGLE, SETTLED_BAND, _along_move, _axes, _distance, crane_signals

__all__ = ["available", "classify", "closed_loop_metrics", "crane_signals", "move_metrics", "peak_abs", "rms",
           "settling_time", "swing_deg", "SETTLED_BAND"]

MIRRORS = "533338505dc72225"  # the metrics.VERSION of metrics.py as these functions mirror it
SOURCE = Path(__file__).with_name("reductions.c")
SQUARES, EFFORT, TRAPEZOID, VARIATION, TRAPEZOID_OF = range(5)
_P, _L, _D = ctypes.c_void_p, ctypes.c_long, ctypes.c_double
_scratch = threading.local()  # each thread's room for the terms of a sum


@functools.cache
def _library():
    lib = compiled(SOURCE)
    if lib is not None:
        lib.extreme.restype, lib.extreme.argtypes = _D, [_P, _L, _L, _L, _D, _D, ctypes.c_int]
        lib.first_at_least.restype, lib.first_at_least.argtypes = _L, [_P, _L, _L, _D]
        lib.last_outside.restype, lib.last_outside.argtypes = _L, [_P, _P, _L, _P, _P, _P, _L, _D]
        lib.sum_of.restype, lib.sum_of.argtypes = _D, [ctypes.c_int, _P, _L, _P, _L, _P, _L, _L, _P]
    return lib


def available():
    """Whether these functions give the metrics module's figures: written against its version, and compiled."""
    return metrics.VERSION == MIRRORS and _library() is not None


def _column(values):
    """``(address, stride in doubles)`` of a 1-D float64 array."""
    if values.dtype != np.float64 or values.ndim != 1:
        raise TypeError(f"a column of float64 values, got {values.dtype} of {values.ndim} dimensions")
    return values.__array_interface__["data"][0], values.strides[0] // 8


def _extreme(values, start=0, stop=None, sign=1.0, offset=0.0, absolute=True):
    stop = len(values) if stop is None else stop
    if stop <= start:
        raise ValueError("zero-size array to reduction operation maximum which has no identity")
    return _library().extreme(*_column(values), start, stop, sign, offset, absolute)


def _from(t, threshold):
    """The first index of the mask ``t >= threshold`` (a run's time grid never decreases)."""
    return _library().first_at_least(*_column(t), len(t), threshold)


def _sum(kind, a, b=None, t=None):
    n = len(a)
    columns = [_column(c) if c is not None else (None, 0) for c in (a, b, t)]
    terms = getattr(_scratch, "terms", None)
    if terms is None or len(terms) < n:
        terms = _scratch.terms = np.empty(max(n, 1024))
    return _library().sum_of(kind, *columns[0], *columns[1], *columns[2], n, terms.__array_interface__["data"][0])


def peak_abs(values):
    """Largest absolute value."""
    return _extreme(values)


def rms(values):
    """Root mean square."""
    return float(np.sqrt(_sum(SQUARES, values) / len(values)))


def _last_outside(signals, band):
    """``signals`` as ``(column, offset, divisor, factor)``; see ``reductions.c``."""
    n, count = len(signals[0][0]), len(signals)
    if count > 8:
        raise ValueError(f"at most 8 signals settle together here, got {count}")
    columns = [_column(c) for c, *_ in signals]
    return _library().last_outside((ctypes.c_void_p * count)(*(a for a, _ in columns)),
                                   (ctypes.c_long * count)(*(s for _, s in columns)), count,
                                   (ctypes.c_double * count)(*(s[1] for s in signals)),
                                   (ctypes.c_double * count)(*(s[2] for s in signals)),
                                   (ctypes.c_double * count)(*(s[3] for s in signals)), n, band)


def _settling(t, signals, band):
    outside = _last_outside(signals, band)
    if outside == len(t) - 1:
        return None
    return float(t[0]) if outside < 0 else float(t[outside + 1])


def settling_time(t, signals, band):
    """Earliest time after which every signal stays within ``[-band, band]``.

    Returns None when some signal is outside the band at the last sample.
    """
    return _settling(t, [(s, 0.0, 1.0, 1.0) for s in signals], band)


def _swings(t, swing):
    """``(each angle's peak, A3, A4)`` of classify (A3 None: an empty third quarter); kept for the same arrays (a
    sweep's row classifies a run twice: the arrays are held, so no other array can have their ids meanwhile)."""
    key = (t, *swing)
    if getattr(_scratch, "swings", (None,))[0] != tuple(map(id, key)):
        span = t[-1] - t[0]
        third, last = _from(t, t[0] + 0.5 * span), _from(t, t[0] + 0.75 * span)
        value = ([peak_abs(angle) for angle in swing],
                 max(_extreme(angle, third, last) for angle in swing) if third < last else None,
                 max(_extreme(angle, last) for angle in swing))
        _scratch.swings = (tuple(map(id, key)), key, value)
    return _scratch.swings[2]


def classify(t, swing, completed, band=SETTLED_BAND):
    """``"converges"``, ``"decaying"``, ``"sustained oscillation"`` or ``"diverges"`` (see metrics.classify)."""
    if not completed:
        return "diverges"
    peaks, a3, a4 = _swings(t, list(swing))
    if any(peak > DIVERGED_ANGLE for peak in peaks):
        return "diverges"
    if a3 is None:  # an empty third quarter: numpy's maximum has nothing to reduce
        raise ValueError("zero-size array to reduction operation maximum which has no identity")
    if a4 > 1.2 * a3:
        return "diverges"
    if a4 < band:
        return "converges"
    if a4 < 0.9 * a3:
        return "decaying"
    return "sustained oscillation"


def closed_loop_metrics(t, x, swing, u, completed):
    """The metrics the report gives for every closed-loop run (angles in degrees), but the correlation of the
    first two angles (``corr_theta1_theta2``), which no study asks for (see metrics.closed_loop_metrics)."""
    def deg(value):
        return math.degrees(value) if math.isfinite(value) else None

    angles = list(swing.values())
    first = next(iter(swing))
    settle_05 = settling_time(t, angles, math.radians(0.5))
    settle_01 = settling_time(t, angles, math.radians(0.1))
    after_15 = _from(t, 15)
    return {
        "outcome": classify(t, angles, completed),
        "completed": completed,
        "end_time_s": float(t[-1]),
        "settling_0.5deg_s": settle_05,
        "settling_0.1deg_s": settle_01,
        **{f"max_{name}_deg": deg(peak_abs(angle)) for name, angle in swing.items()},
        f"rms_{first}_deg": deg(rms(swing[first])),
        "residual_after_15s_deg": (deg(max(_extreme(angle, after_15) for angle in angles)) if t[-1] >= 15 else None),
        "trolley_excursion_m": _finite(_extreme(x, offset=x[0])),
        "trolley_final_m": _finite(float(x[-1])),
        "peak_abs_u": _finite(peak_abs(u)),
    }


def move_metrics(t, x, dx, swing, u, x_d, residual_from=None, position_band=0.005,
                 angle_band=ARRIVAL_ANGLE, bounds=None):
    """The figures of a move to (or regulation at) ``x_d``, angles in degrees (see metrics.move_metrics): its
    elementwise arithmetic in numpy where there is more than one axis (the same bits), its reductions here."""
    xs, dxs, us, targets = _axes(x), _axes(dx), _axes(u), list(np.atleast_1d(x_d).astype(float))
    swing = list(swing)
    if len(xs) == 1:  # the position error x - x_d, made by the reductions themselves
        error, target = xs[0], targets[0]
    else:
        error, target = _distance([p - d for p, d in zip(xs, targets)]), 0.0
    arrival = _settling(t, [(error, target, 1.0, 1.0)] + [(angle, 0.0, angle_band, position_band)
                                                          for angle in swing], position_band)
    if residual_from is None:
        residual_from = t[0] + 0.75 * (t[-1] - t[0])
    window = _from(t, residual_from)
    last = _from(t, t[0] + 0.75 * (t[-1] - t[0]))
    if len(swing) == 2:
        ise_sum = _sum(TRAPEZOID, swing[0], swing[1], t)
    else:  # the squares summed in numpy's order, then their trapezoid
        squares = np.square(swing[0])
        for angle in swing[1:]:
            squares = squares + np.square(angle)
        ise_sum = _sum(TRAPEZOID_OF, squares, t=t)
    ise = math.degrees(math.degrees(float(ise_sum / 2)))
    duration = float(t[-1] - t[0])
    if len(xs) == 1:
        direction = 1.0 if targets[0] >= xs[0][0] else -1.0
        overshoot = _extreme(xs[0], sign=direction, offset=targets[0], absolute=False)
    else:
        overshoot = _extreme(_along_move(xs, targets), absolute=False)
    figures = {
        "arrival_s": arrival,
        "residual_deg": _swing(swing, window) if window < len(t) else None,
        "settling_0.5deg_s": settling_time(t, swing, math.radians(0.5)),
        "settling_0.1deg_s": settling_time(t, swing, math.radians(0.1)),
        "position_1cm_s": _settling(t, [(error, target, 1.0, 1.0)], 0.01),
        "overshoot_m": max(0.0, float(overshoot)),
        "final_error_m": abs(float(_distance([p[-1:] - d for p, d in zip(xs, targets)])[0])),
        "peak_abs_u": max(peak_abs(v) for v in us),
        "peak_abs_v": max(peak_abs(v) for v in dxs),
        "effort": sum(float(_sum(EFFORT, v, t=t)) for v in us),
        "end_swing_deg": _swing(swing, last),
        "peak_swing_deg": swing_deg(swing),
        "ise_swing_deg2s": _finite(ise),
        "rms_swing_deg": _finite(math.sqrt(ise / duration)) if duration > 0 else None,
        "u_total_variation": _finite(sum(float(_sum(VARIATION, v)) for v in us)),
    }
    figures.update(bounds_check(xs, dxs, us, bounds))
    return figures


def _swing(swing, start):
    return math.degrees(max(_extreme(angle, start) for angle in swing))


def swing_deg(swing):
    """The largest swing of any angle [deg]."""
    return _swing(list(swing), 0)


def bounds_check(x, dx, u, bounds):
    """``{"bounds_held": bool, "bounds_broken": str}`` of the bounds given, on every axis (see metrics.bounds_check)."""
    if not bounds:
        return {"bounds_held": None, "bounds_broken": None}
    xs, dxs, us = _axes(x), _axes(dx), _axes(u)

    def beyond(extreme, bound, sign):  # a maximum of a non-finite run is nan: never within
        return not sign * extreme <= sign * bound + metrics.BOUND_TOLERANCE * max(abs(bound), 1.0)

    checks = {"|u|": ("u_max", lambda b: any(beyond(peak_abs(v), b, 1) for v in us)),
              "|v|": ("v_max", lambda b: any(beyond(peak_abs(v), b, 1) for v in dxs)),
              "x_min": ("x_min", lambda b: any(beyond(-_extreme(v, sign=-1.0, absolute=False), b, -1) for v in xs)),
              "x_max": ("x_max", lambda b: any(beyond(_extreme(v, absolute=False), b, 1) for v in xs))}
    broken = [name for name, (key, check) in checks.items()
              if key in bounds and math.isfinite(bounds[key]) and check(bounds[key])]
    return {"bounds_held": not broken, "bounds_broken": ", ".join(broken)}


def _finite(value):
    return value if math.isfinite(value) else None
