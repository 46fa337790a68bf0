"""An input-shaped plan for a path of waypoints in the plane: one ``TrajectoryPlanner`` move per axis, timed.

The path is a polyline of waypoints ``(x, y)`` through which the trolley takes the load, leg after leg. Each axis
is moved by its own :mod:`.planner` (a shaped rest-to-rest move); a leg's axes start together. A leg may start
before the one before it has ended, as long as the reference stays within ``margin`` of the path's centre line
at every instant (it then cuts the corner by at most ``margin``); ``margin = 0``: each leg starts when the last
has ended. What is kept within ``margin`` is the trolley's reference, or (``load=True``) the load's planned position:
the trolley's reference plus the swing the planner's linear model gives it, ``x_ref + l1 theta1_ref + l2 theta2_ref``
per axis (the planner's references, its model's ``l1`` and ``l2``), which a corridor between racks constrains.
The start is the earliest such time, found by bisection to :data:`RESOLUTION` over the reference sampled every
:data:`SAMPLE` s.

An axis moves once along the path (a TrajectoryPlanner makes one move): an L path, a diagonal, not a zigzag.
"""

import math

from . import planner

RESOLUTION = 1e-3  # s: the start times' (the communication step of the systems that run the plan)
SAMPLE = 1e-2  # s: where the reference is checked against the corridor


def distance_to_path(point, waypoints):
    """The distance [m] from ``point`` to the polyline through ``waypoints``."""
    best = math.inf
    for (ax, ay), (bx, by) in zip(waypoints, waypoints[1:]):
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        f = 0.0 if length2 == 0 else min(1.0, max(0.0, ((point[0] - ax) * dx + (point[1] - ay) * dy) / length2))
        best = min(best, math.hypot(point[0] - ax - f * dx, point[1] - ay - f * dy))
    return best


def _config(values, x0, x_d, t0):
    return planner.configure({**planner.COMPONENT.defaults(), **values, "x0": x0, "x_d": x_d, "t0": t0})


def planned_point(config, t, load=False, lengths=(0.0, 0.0)):
    """Where one axis' plan has the trolley (``load=False``) or the load (``lengths``: ``l1``, ``l2``) at ``t``."""
    x, _, _, theta1, _, theta2, _ = planner.reference(config, t)
    return x + lengths[0] * theta1 + lengths[1] * theta2 if load else x


def plan(waypoints, margin=0.0, values=None, axes=("x", "y"), load=False):
    """``{axis: {"x0", "x_d", "t0"}}``: each axis' planner parameters along the path.

    Parameters
    ----------
    waypoints : sequence of (x, y)
        The path, from the start; at least two.
    margin : float
        How far [m] the reference may leave the path's centre line (>= 0).
    values : dict, optional
        The planners' other parameters (their model of the crane, ``u_max``, ``v_max``, ``shaper``).
    load : bool
        Keep the load's planned position within ``margin`` (its linear model's), not the trolley's reference.

    Raises
    ------
    ValueError
        One line: fewer than two waypoints, a negative margin, or an axis that moves in two legs.
    """
    points = [tuple(float(v) for v in p) for p in waypoints]
    if len(points) < 2 or any(len(p) != len(axes) for p in points):
        raise ValueError(f"waypoints must be two or more points ({', '.join(axes)}), got {waypoints!r}")
    if not (margin >= 0 and math.isfinite(margin)):
        raise ValueError(f"margin must be >= 0 and finite, got {margin!r}")
    values = values or {}
    model = {**planner.COMPONENT.defaults(), **values}
    lengths = (model["l1"], model["l2"])
    moves, configs, start, end = {}, {}, 0.0, 0.0
    for leg, (a, b) in enumerate(zip(points, points[1:])):
        moving = [k for k in range(len(axes)) if a[k] != b[k]]
        for k in moving:
            if axes[k] in moves:
                raise ValueError(f"waypoints: the {axes[k]} axis moves in two legs (leg {leg + 1}); a path moves each "
                                 "axis once")

        def within(t0, a=a, b=b, moving=moving, start=start):  # called in this leg only
            trial = {**configs, **{axes[k]: _config(values, a[k], b[k], t0) for k in moving}}
            t, last = start, max((c.end for c in trial.values()), default=start)  # nothing moved yet: at the start
            while t <= last + SAMPLE:
                where = [planned_point(trial[name], t, load, lengths) if name in trial else points[0][k]
                         for k, name in enumerate(axes)]
                if distance_to_path(where, points) > margin + 1e-12:
                    return False
                t += SAMPLE
            return True

        t0 = end
        if margin > 0 and leg > 0 and within(start):
            t0 = start
        elif margin > 0 and leg > 0:
            low, high = start, end  # low: leaves the corridor; high: the last leg's end, within
            while high - low > RESOLUTION:
                mid = 0.5 * (low + high)
                low, high = (low, mid) if within(mid) else (mid, high)
            t0 = math.ceil(round(high / RESOLUTION, 6)) * RESOLUTION
        for k in moving:
            moves[axes[k]] = {"x0": a[k], "x_d": b[k], "t0": t0}
            configs[axes[k]] = _config(values, a[k], b[k], t0)
        start, end = t0, max([end] + [configs[axes[k]].end for k in moving])
    return {name: moves.get(name, {"x0": points[0][k], "x_d": points[0][k], "t0": 0.0})
            for k, name in enumerate(axes)}
