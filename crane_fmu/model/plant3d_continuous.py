"""The CranePlant3D as a host integrates it (Model Exchange): derivatives, their exact directional derivatives, events.

The continuous state is the spatial swing-and-hoist state of :mod:`.plant3d_equations` followed by the
two drives' accelerations: :data:`STATES`. Its derivative is :func:`.plant3d_equations.accelerations_tangent`,
the function the co-simulation's RK4 calls, with the trolley and hoist accelerations that the drives and the
limits let through. As for the planar plant (:mod:`.plant_continuous`), the limits that switch are event
indicators (:data:`INDICATORS`): per axis the speed limit holds the speed once reached while the demand
pushes on and a rail end ends the simulation; the hoist's cable limits and speed limit hold as the planar
hoist's. Which limits hold is the discrete state, a :class:`Mode`.
"""

import math
from collections import namedtuple

from .component import Discard
from .plant3d_equations import ANGLES, DL1, DX, DY, L1, X, Y, accelerations_tangent, outputs, outputs_tangent
from .plant_continuous import _hold, _room
from .plant_limits import reached_limit

DRIVE_X, DRIVE_Y = DL1 + 1, DL1 + 2  # after the swing and hoist state: the drives' accelerations (moving with a lag)
STATES = ("x", "dx", "y", "dy", "theta1x", "dtheta1x", "theta1y", "dtheta1y", "theta2x", "dtheta2x", "theta2y",
          "dtheta2y", "l1_now", "dl1_now", "drive_x", "drive_y")
INPUTS = ("ux", "uy", "hoist", "F1x", "F1y", "F2x", "F2y")
IN = namedtuple("InputPositions", INPUTS)(*range(len(INPUTS)))  # inputs[IN.hoist]: the inputs by name
INDICATORS = ("x_min", "x_max", "-vx_max", "vx_max", "y_min", "y_max", "-vy_max", "vy_max", "l1_min", "l1_max",
              "-dl1_max", "dl1_max")

Mode = namedtuple("Mode", "speed_x speed_y cable hoist")
Mode.__doc__ = ("Which limits hold: the trolley's speed along x and along y, the cable's length, the cable's speed; "
                "each -1 (held at the lower limit), 0 (free) or +1 (held at the upper limit).")
FREE = Mode(0, 0, 0, 0)

Event = namedtuple("Event", "state mode messages terminate")
Event.__doc__ = ("What :func:`event_update` returns: the state (changed where a limit was reached), the mode, "
                 "messages for the host's log, and the reason the simulation ends (None: it goes on).")

_NO_SEED = ((0.0,) * len(STATES), (0.0,) * len(INPUTS))


def initial(config):
    """The continuous state at the start, before the first event update (the co-simulation's ``state0``)."""
    return config.state0[:DRIVE_Y + 1]


def _drive(axis, u, drive, t_u, t_drive):
    """One axis' drive: its output (the trolley's acceleration before the speed limit), its rate, and their
    derivatives; the demand is limited to ``u_max`` (its derivative by ``u`` 0 beyond the limit), then lagged."""
    if u > axis.u_max:
        demand, t_demand = axis.u_max, 0.0
    elif u < -axis.u_max:
        demand, t_demand = -axis.u_max, 0.0
    else:
        demand, t_demand = u, t_u
    if axis.tau > 0:  # first-order lag: drive' = (demand - drive) / tau
        return drive, t_drive, (demand - drive) / axis.tau, (t_demand - t_drive) / axis.tau
    return demand, t_demand, 0.0, 0.0


def _drives(config, state, inputs, seed):
    """Both axes' :func:`_drive`."""
    ds, di = seed
    return (_drive(config.x_axis, inputs[IN.ux], state[DRIVE_X], di[IN.ux], ds[DRIVE_X]),
            _drive(config.y_axis, inputs[IN.uy], state[DRIVE_Y], di[IN.uy], ds[DRIVE_Y]))


def derivatives(config, state, inputs, mode, seed=None):
    """The time derivative of the continuous state; with ``seed``, also its derivative along it.

    Parameters
    ----------
    config : plant3d.Config
        The validated parameters.
    state : tuple
        The continuous state, :data:`STATES`.
    inputs : tuple
        ``(ux, uy, hoist, F1x, F1y, F2x, F2y)``.
    mode : Mode
        The limits that hold.
    seed : (tuple, tuple), optional
        A change of the state and of the inputs: the direction of a directional derivative.

    Returns
    -------
    tuple, or (tuple, tuple) with ``seed``
        ``d state / dt`` in the order of :data:`STATES` (and its derivative along ``seed``).

    Raises
    ------
    Discard
        For a force on a load of mass 0, or a state where the derivative is not finite.
    """
    c, p = config, config.params
    hoist, f1x, f1y, f2x, f2y = (inputs[i] for i in (IN.hoist, IN.F1x, IN.F1y, IN.F2x, IN.F2y))
    if p.m2 == 0 and (f2x != 0 or f2y != 0):
        raise Discard(f"F2 = ({f2x!r}, {f2y!r}) N acts on a load of mass m2 = 0")
    ds, di = seed or _NO_SEED
    (ax, t_ax, rx, t_rx), (ay, t_ay, ry, t_ry) = _drives(c, state, inputs, (ds, di))
    if mode.speed_x:
        ax, t_ax = 0.0, 0.0
    if mode.speed_y:
        ay, t_ay = 0.0, 0.0
    if mode.cable:
        rate, t_rate, lift, t_lift = 0.0, 0.0, 0.0, 0.0
    else:
        rate, t_rate = state[DL1], ds[DL1]
        lift, t_lift = (0.0, 0.0) if mode.hoist else (hoist, di[IN.hoist])
    load = (lift, f1x, f1y, f2x, f2y, *c.damping)
    angles = state[ANGLES]
    try:
        dd, tdd = accelerations_tangent(angles, ax, ay, p, state[L1], rate, load,
                                        (*ds[ANGLES], t_ax, t_ay, ds[L1], t_rate, t_lift,
                                         *(di[i] for i in (IN.F1x, IN.F1y, IN.F2x, IN.F2y))))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        dd = tdd = (math.nan,) * 4
    values = (state[DX], ax, state[DY], ay, angles[1], dd[0], angles[3], dd[1], angles[5], dd[2], angles[7], dd[3],
              rate, lift, rx, ry)
    if not all(map(math.isfinite, values)):
        raise Discard(f"the plant's derivatives are not finite at this state ({', '.join(map(repr, state))})")
    if seed is None:
        return values
    ta = ds[ANGLES]
    return values, (ds[DX], t_ax, ds[DY], t_ay, ta[1], tdd[0], ta[3], tdd[1], ta[5], tdd[2], ta[7], tdd[3], t_rate,
                    t_lift, t_rx, t_ry)


def applied_accelerations(config, state, inputs, mode):
    """The trolley's accelerations now: each demand after its drive's limit and lag and its speed limit."""
    (ax, *_), (ay, *_) = _drives(config, state, inputs, _NO_SEED)
    return 0.0 if mode.speed_x else ax, 0.0 if mode.speed_y else ay


def output_values(config, state, inputs, mode, seed=None):
    """The CranePlant3D's outputs in table order (and their derivative along ``seed``).

    The swing state, :func:`.plant3d_equations.outputs`, ``l1_now``, ``dl1_now``, and ``ddx``, ``ddy`` the
    trolley's accelerations now, the derivatives of ``dx``, ``dy``.
    """
    if seed is None:
        return state[:L1] + outputs(state, config.params) + (state[L1], state[DL1]) + \
            applied_accelerations(config, state, inputs, mode)
    ds, di = seed
    values = output_values(config, state, inputs, mode)
    (_, t_ax, _, _), (_, t_ay, _, _) = _drives(config, state, inputs, seed)
    t_accel = (0.0 if mode.speed_x else t_ax, 0.0 if mode.speed_y else t_ay)
    return values, ds[:L1] + outputs_tangent(state, config.params, ds) + (ds[L1], ds[DL1]) + t_accel


def _pair(value, low, high, held, pressing):
    """The indicators of a quantity's lower and upper limit: the room left while free, the push while held."""
    return (-pressing if held < 0 else _room(-value, -low)), (pressing if held > 0 else _room(value, high))


def event_indicators(config, state, inputs, mode):
    """The event indicators in the order of :data:`INDICATORS`; each is positive while its mode stays.

    As :func:`.plant_continuous.event_indicators`, per axis: the rail ends, the speed limits; then the hoist's.
    """
    c = config
    (push_x, *_), (push_y, *_) = _drives(c, state, inputs, _NO_SEED)
    lift = inputs[IN.hoist]
    return (_pair(state[X], c.x_axis.low, c.x_axis.high, 0, 0.0)
            + _pair(state[DX], -c.x_axis.v_max, c.x_axis.v_max, mode.speed_x, push_x)
            + _pair(state[Y], c.y_axis.low, c.y_axis.high, 0, 0.0)
            + _pair(state[DY], -c.y_axis.v_max, c.y_axis.v_max, mode.speed_y, push_y)
            + _pair(state[L1], c.l1_min, c.l1_max, mode.cable, lift)
            + _pair(state[DL1], -c.dl1_max, c.dl1_max, mode.hoist, lift))


def _rail_end(axis, name, position, speed, accel):
    """``(limit's name, position)`` of the rail end the trolley is at and moving past along one axis, or None."""
    outward = speed if speed != 0 else accel
    if position > axis.high or (position == axis.high and outward > 0):
        return f"{name}_max", axis.high
    if position < axis.low or (position == axis.low and outward < 0):
        return f"{name}_min", axis.low
    return None


def event_update(config, state, inputs, mode, time):
    """The state and mode after an event at ``time`` (also at the end of initialisation).

    Returns
    -------
    Event
        The trolley at a rail end and moving past it ends the simulation (``terminate`` says why); a speed
        that reached its limit is set onto it and held while the demand pushes on; a cable that reached
        ``l1_min`` or ``l1_max`` is set onto it at rest and held while the hoist pulls on.
    """
    c = config
    state = list(state)
    (push_x, *_), (push_y, *_) = _drives(c, state, inputs, _NO_SEED)
    lift = inputs[IN.hoist]
    for axis, name, at, speed, push, held in ((c.x_axis, "x", X, DX, push_x, mode.speed_x),
                                             (c.y_axis, "y", Y, DY, push_y, mode.speed_y)):
        end = _rail_end(axis, name, state[at], state[speed], 0.0 if held else push)
        if end is not None:
            return Event(tuple(state), mode, [], f"the trolley reached the rail end {end[0]} = {end[1]!r} m "
                                                 f"({name} = {state[at]!r} m) at t = {time!r} s")
    messages = []
    state[DX], speed_x, _ = _hold(state[DX], push_x, push_x, mode.speed_x, -c.x_axis.v_max, c.x_axis.v_max)
    state[DY], speed_y, _ = _hold(state[DY], push_y, push_y, mode.speed_y, -c.y_axis.v_max, c.y_axis.v_max)
    dl1 = state[DL1]
    state[L1], cable, reached = _hold(state[L1], dl1, lift, mode.cable, c.l1_min, c.l1_max)
    if cable or reached:
        if reached and dl1 != 0.0:
            messages.append(reached_limit(state[L1], time, dl1)[1])
        state[DL1], hoist = 0.0, 0
    else:
        state[DL1], hoist, _ = _hold(dl1, lift, lift, mode.hoist, -c.dl1_max, c.dl1_max)
    return Event(tuple(state), Mode(speed_x, speed_y, cable, hoist), messages, None)


def jacobians(config, state, inputs, mode):
    """``(A, B, C, D)``: the derivatives' and the outputs' Jacobians by the state and the inputs, exactly.

    Lists of rows, as :func:`.plant_continuous.jacobians`.
    """
    n, m = len(STATES), len(INPUTS)
    columns = []
    for k in range(n + m):
        seed = (tuple(float(j == k) for j in range(n)), tuple(float(n + j == k) for j in range(m)))
        columns.append((derivatives(config, state, inputs, mode, seed)[1],
                        output_values(config, state, inputs, mode, seed)[1]))

    def rows(part, cols):
        return [list(r) for r in zip(*(columns[k][part] for k in cols))]

    return rows(0, range(n)), rows(0, range(n, n + m)), rows(1, range(n)), rows(1, range(n, n + m))
