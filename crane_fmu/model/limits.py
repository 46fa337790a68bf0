"""Actuator limits every controller and the planner share: |u| <= u_max, |dx| <= v_max.

"No limit" is a value of :data:`NO_LIMIT` (1e60, Modelica's ``inf``) or beyond, ``INF`` included; it is the
start value of every limit that is off by default. A finite start value because hosts read and log every
parameter: OMSimulator logs an error for each one that reads as +-inf, libcosim refuses them in system
files. The models turn such a value into ``inf`` when they are configured (:func:`unlimited`), so 1e60 and
INF give the same run, bit for bit.
"""

import math

from .rules import NO_LIMIT, limit, unlimited  # noqa: F401 (NO_LIMIT and unlimited() are the limits' own)
from .tables import parameter

RULES = limit("u_max", "v_max")  # each > 0; 1e60 or more (INF too) is no limit


def parameters(u_max=2.0, v_max=1.0, what="u"):
    """The limit parameter rows; 1e60 or more (INF too) means no limit."""
    return (parameter("u_max", u_max, "m/s2", f"largest |{what}| (trolley acceleration); 1e60 or INF: no limit"),
            parameter("v_max", v_max, "m/s", "largest trolley speed it commands; 1e60 or INF: no limit"))


def of(values):
    """``(u_max, v_max)`` of values that meet :data:`RULES`, 1e60 or more as ``inf`` (no limit)."""
    return unlimited(values["u_max"]), unlimited(values["v_max"])


def limited(u, dx, u_max, v_max, h):
    """``u`` within ``+-u_max``, and such that the speed after a step ``h`` with ``u`` held stays within ``+-v_max``.

    A trolley already faster than ``v_max`` is braked at ``u_max``.
    """
    low, high = -u_max, u_max
    if math.isfinite(v_max):
        low, high = max(low, (-v_max - dx) / h), min(high, (v_max - dx) / h)
        if low > high:  # outside the speed band: brake
            return -u_max if dx > 0 else u_max
    return min(max(u, low), high)
