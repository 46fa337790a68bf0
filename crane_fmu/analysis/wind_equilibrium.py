"""Where the mean wind holds a hanging load: the static deflection of the double pendulum under the mean drag.

A steady horizontal force ``F1`` on the hook and ``F2`` on the load, the trolley at rest: the lower cable carries
the load's weight and ``F2``, the upper one both masses' weights and ``F1 + F2``, so (statics of eqs (4)-(5))

    tan theta2 = F2 / (m2 g),   tan theta1 = (F1 + F2) / ((m1 + m2) g).

The mean drag is the Wind component's at rest, ``0.5 rho Cd A U |U|`` (:func:`crane_fmu.model.wind.drag`). The
deflection itself no trolley motion removes while the load is at rest (S14 measures the swing about it).

In turbulence the load also leans with the wind's slow part, for seconds, and a controller that does not know the
coming gusts cannot take that lean away without leaving the load's band (:mod:`.wind_floor`). S10 therefore measures
the swing about the :func:`lean`: the angle averaged over one period of the slow swing mode, centred on each instant.
A swing at that period averages to its centre, a lean held or drifting over longer stays in the average: what is
left is the swing a controller can take away; the lean shows in the load's distance from the target.
"""

import dataclasses
import math

import numpy as np

from crane_fmu.model import wind
from crane_fmu.model.parameters import PlantParameters

# the design gust: the Wind's mean and twice its turbulence's standard deviation (98 % of the turbulence's samples
# below it), 13.8 m/s; the turbulence's slow part (time constant L / U, 6.7 s) leans a load held still for seconds
_WIND = wind.COMPONENT.defaults()
DESIGN_GUST = {"U_mean": _WIND["U_mean"] + 2.0 * _WIND["sigma"]}


def static_deflection(m1, m2, g, f1, f2):
    """``(theta1, theta2)`` [rad]: the cables' angles from the vertical under the steady forces ``f1`` (hook) and
    ``f2`` (load) [N], towards the forces."""
    return math.atan((f1 + f2) / ((m1 + m2) * g)), (math.atan(f2 / (m2 * g)) if m2 > 0 else 0.0)


def mean_drag(values=None):
    """``(F1, F2)`` [N]: the Wind component's drag on hook and load at rest in its mean wind (its parameters,
    ``values`` over its defaults)."""
    c = wind.COMPONENT.check(values or {})
    return wind.drag(c.drag1, c.mean, 0.0), wind.drag(c.drag2, c.mean, 0.0)


def wind_deflection(plant=None, values=None):
    """``(theta1, theta2)`` [rad] of the crane (``plant``: m1, m2, g over Section V's) in the Wind component's mean
    wind (``values``)."""
    p = dataclasses.replace(PlantParameters(), **{k: v for k, v in (plant or {}).items() if k in ("m1", "m2", "g")})
    return static_deflection(p.m1, p.m2, p.g, *mean_drag(values))


def lean(angle, samples):
    """The :func:`lean` (module notes) of ``angle`` (one value per step): its mean over ``samples`` steps (one period
    of the slow swing mode, made odd) centred on each step; NaN where that window does not fit in the run (half a
    period at each end)."""
    half = int(samples) // 2
    if half < 1:
        raise ValueError(f"the lean's window must span at least 2 steps, got samples={samples}")
    angle = np.asarray(angle, dtype=float)
    out = np.full(angle.shape, np.nan)
    if angle.size > 2 * half:
        total = np.concatenate([[0.0], np.cumsum(angle)])
        out[half:angle.size - half] = (total[2 * half + 1:] - total[:-2 * half - 1]) / (2 * half + 1)
    return out
