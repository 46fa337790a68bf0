"""Actuator limits every controller and the planner share: |u| <= u_max, |dx| <= v_max."""

import math

from .tables import parameter


def parameters(u_max=2.0, v_max=1.0, what="u"):
    """The limit parameter rows; ``inf`` means no limit."""
    return (parameter("u_max", u_max, "m/s2", f"largest |{what}| (trolley acceleration); INF: no limit"),
            parameter("v_max", v_max, "m/s", "largest trolley speed it commands; INF: no limit"))


def check(values):
    """Validated ``(u_max, v_max)``: each > 0 (``inf`` allowed)."""
    for name in ("u_max", "v_max"):
        value = values[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ValueError(f"{name} must be > 0 (inf: no limit), got {value!r}")
    return values["u_max"], values["v_max"]


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
