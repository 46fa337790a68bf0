"""The plant's drive, rail and hoist limits: what stands between a demanded and an applied acceleration.

Plain functions of values and limits, used per RK4 sub-step by :func:`.plant.update`.
Each limit is inactive at its neutral value (``INF``, or ``tau = 0``).
"""

import math

from .component import Discard


def clamp(value, low, high):
    return min(max(value, low), high)


def drive_factors(tau, dt):
    """``(lag, mean)`` of the drive's first-order lag over a sub-step ``dt``.

    The drive's acceleration ``a`` follows the demand ``d`` exactly as
    ``a(dt) = d + (a(0) - d) lag`` with ``lag = exp(-dt / tau)``, and its mean over
    the sub-step is ``d + (a(0) - d) mean``; ``tau = 0`` is no lag: ``(0, 0)``.
    """
    if tau == 0:
        return 0.0, 0.0
    lag = math.exp(-dt / tau)
    return lag, tau / dt * (1.0 - lag)


def within_speed(accel, speed, speed_max, dt):
    """``accel`` limited so that ``speed`` ends the sub-step ``dt`` within ``+-speed_max``."""
    if speed_max == math.inf:
        return accel
    return clamp(accel, (-speed_max - speed) / dt, (speed_max - speed) / dt)


def past_rail_end(x_min, x_max, x, t, time, axis="x"):
    """The Discard of a step in which the trolley (at ``x`` along ``axis`` at time ``t``) would pass a rail end."""
    end, at = (f"{axis}_max", x_max) if x > x_max else (f"{axis}_min", x_min)
    return Discard(f"the trolley would pass the rail end {end} = {at!r} m ({axis} = {x!r} m) "
                   f"at t = {t!r} s: the step from t = {time!r} s is discarded")


AT_REST = 0.01  # m/s: a cable that reaches a hoist limit slower than this ends its move there


def reached_limit(held, t, speed):
    """``(is_warning, message)`` of a cable held at a hoist limit it reached at ``speed`` at ``t``.

    Slower than :data:`AT_REST` it is the end of a hoist move planned to stop there (a plan sampled at
    the communication step arrives with up to one step of its deceleration left, 0.5 mm/s in
    ``hoist-transport``): information. Faster, the limit stopped a moving cable: a warning.
    """
    if abs(speed) < AT_REST:
        return False, f"hoist: l1 reached {held!r} m at t = {t!r} s and is held there"
    return True, f"hoist: l1 hit the limit {held!r} m at {abs(speed)!r} m/s at t = {t!r} s and is held there"


def held_cable(l1, l1_min, l1_max):
    """The limit a cable of length ``l1`` is held at, or None when it lies within them."""
    if l1_min <= l1 <= l1_max:
        return None
    return l1_max if l1 > l1_max else l1_min
