"""The CranePlant as a host integrates it (Model Exchange): derivatives, their exact directional derivatives, events.

The continuous state is the swing and hoist state of :mod:`.plant_equations` followed by the
drive's acceleration: :data:`STATES` (the names of the FMU's variables). Its derivative is
:func:`.plant_equations.angular_accelerations`, the function the co-simulation's RK4 calls,
with the trolley and hoist accelerations that the drive and the limits let through.

The limits that switch are event indicators (:data:`INDICATORS`), not an ``if`` inside the
derivative: the trolley's speed limit ``v_max`` and the hoist's ``dl1_max`` hold the speed
once reached while the demand pushes on, the cable limits ``l1_min``, ``l1_max`` hold the
cable at rest, and a rail end ``x_min``, ``x_max`` ends the simulation (the co-simulation
discards the step that would pass it). Which limits hold is the discrete state, a
:class:`Mode`; :func:`event_update` changes it where a host stops at an event. An indicator
is positive while its mode stays: the distance to a free limit, or the acceleration that
presses against a held one.
"""

import math
from collections import namedtuple

from .component import Discard
from .plant_equations import DL1, DX, L1, SWING, X, accelerations_tangent, outputs, outputs_tangent
from .plant_limits import reached_limit

DRIVE = DL1 + 1  # after the swing and hoist state: the drive's acceleration (moves only with a lag tau > 0)
STATES = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2", "l1_now", "dl1_now", "drive")
INPUTS = ("u", "hoist", "F1", "F2")
IN = namedtuple("Inputs", INPUTS)(*range(len(INPUTS)))  # their positions: inputs[IN.hoist]
INDICATORS = ("x_min", "x_max", "-v_max", "v_max", "l1_min", "l1_max", "-dl1_max", "dl1_max")

Mode = namedtuple("Mode", "speed cable hoist")
Mode.__doc__ = ("Which limits hold: the trolley's speed, the cable's length, the cable's speed; each -1 (held at "
                "the lower limit), 0 (free) or +1 (held at the upper limit).")
FREE = Mode(0, 0, 0)

Event = namedtuple("Event", "state mode messages terminate")
Event.__doc__ = ("What :func:`event_update` returns: the state (changed where a limit was reached), the mode, "
                 "messages for the host's log, and the reason the simulation ends (None: it goes on).")

_NO_SEED = ((0.0,) * len(STATES), (0.0,) * len(INPUTS))


def initial(config):
    """The continuous state at the start, before the first event update (the co-simulation's ``state0``)."""
    return config.state0[:DRIVE + 1]


def _demand(config, u):
    """The demand within ``u_max`` and its derivative by ``u`` (1 within the limit, 0 beyond it)."""
    if u > config.u_max:
        return config.u_max, 0.0
    if u < -config.u_max:
        return -config.u_max, 0.0
    return u, 1.0


def _trolley(config, state, inputs, seed):
    """The drive's output (the trolley's acceleration before the speed limit), its rate, and their derivatives."""
    demand, gain = _demand(config, inputs[IN.u])
    t_demand = gain * seed[1][IN.u]
    if config.tau > 0:  # first-order lag: drive' = (demand - drive) / tau
        drive, t_drive = state[DRIVE], seed[0][DRIVE]
        return drive, t_drive, (demand - drive) / config.tau, (t_demand - t_drive) / config.tau
    return demand, t_demand, 0.0, 0.0


def derivatives(config, state, inputs, mode, seed=None):
    """The time derivative of the continuous state; with ``seed``, also its derivative along it.

    Parameters
    ----------
    config : plant.Config
        The validated parameters.
    state : tuple
        The continuous state, :data:`STATES`.
    inputs : tuple
        ``(u, hoist, F1, F2)``.
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
        For a force F2 on a payload of mass 0, or a state where the derivative is not finite.

    Notes
    -----
    ``x'' = u`` within the drive's limits (eq 12); the angular accelerations are eqs (8)-(9) with
    their extensions, :func:`.plant_equations.angular_accelerations`. A held speed has no
    acceleration; a held cable has ``l1' = l1'' = 0``.
    """
    c, p = config, config.params
    u, hoist, f1, f2 = inputs
    if p.m2 == 0 and f2 != 0:
        raise Discard(f"F2 = {f2!r} N acts on a payload of mass m2 = 0")
    ds, di = seed or _NO_SEED
    accel, t_accel, drive_rate, t_drive_rate = _trolley(c, state, inputs, (ds, di))
    if mode.speed:
        accel, t_accel = 0.0, 0.0
    if mode.cable:
        rate, t_rate, lift, t_lift = 0.0, 0.0, 0.0, 0.0
    else:
        rate, t_rate = state[DL1], ds[DL1]
        lift, t_lift = (0.0, 0.0) if mode.hoist else (hoist, di[1])
    load = (rate, lift, f1, f2, *c.damping)
    _, dx, theta1, dtheta1, theta2, dtheta2 = state[SWING]
    try:
        (dd1, dd2), (t1, t2) = accelerations_tangent(
            theta1, dtheta1, theta2, dtheta2, accel, p, state[L1], load,
            (ds[2], ds[3], ds[4], ds[5], t_accel, ds[L1], t_rate, t_lift, di[2], di[3]))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        dd1 = dd2 = math.nan
    values = (dx, accel, dtheta1, dd1, dtheta2, dd2, rate, lift, drive_rate)
    if not all(map(math.isfinite, values)):
        raise Discard(f"the plant's derivatives are not finite at this state ({', '.join(map(repr, state))})")
    if seed is None:
        return values
    return values, (ds[DX], t_accel, ds[3], t1, ds[5], t2, t_rate, t_lift, t_drive_rate)


def applied_acceleration(config, state, inputs, mode):
    """The trolley's acceleration now: the demand after the drive's limit and lag and the speed limit."""
    return 0.0 if mode.speed else _trolley(config, state, inputs, _NO_SEED)[0]


def output_values(config, state, inputs, mode, seed=None):
    """The CranePlant's outputs in table order (and their derivative along ``seed``).

    The co-simulation's outputs (:func:`.plant_equations.outputs`, ``l1_now``, ``dl1_now``) with
    ``ddx`` the trolley's acceleration now, the derivative of ``dx``.
    """
    if seed is None:
        accel = applied_acceleration(config, state, inputs, mode)
        return outputs(state, config.params) + (state[L1], state[DL1], accel)
    ds, di = seed
    values = output_values(config, state, inputs, mode)
    t_accel = 0.0 if mode.speed else _trolley(config, state, inputs, seed)[1]
    return values, outputs_tangent(state, config.params, ds) + (ds[L1], ds[DL1], t_accel)


def _room(value, limit):
    """``limit - value`` (the room to a limit above), or 1 when there is no limit."""
    return limit - value if math.isfinite(limit) else 1.0


def event_indicators(config, state, inputs, mode):
    """The event indicators in the order of :data:`INDICATORS`; each is positive while its mode stays.

    A free limit's indicator is the room left to it, which reaches zero where the limit is reached;
    a held speed's or cable's is the acceleration pressing against it, which reaches zero where the
    demand lets go. Without the limit (``INF``) the indicator is 1.
    """
    c = config
    x, dx, l1, dl1 = state[X], state[DX], state[L1], state[DL1]
    push = _trolley(c, state, inputs, _NO_SEED)[0]
    lift = inputs[IN.hoist]

    def pair(value, low, high, held, pressing):
        return (-pressing if held < 0 else _room(-value, -low)), (pressing if held > 0 else _room(value, high))

    return (pair(x, c.x_min, c.x_max, 0, 0.0) + pair(dx, -c.v_max, c.v_max, mode.speed, push)
            + pair(l1, c.l1_min, c.l1_max, mode.cable, lift) + pair(dl1, -c.dl1_max, c.dl1_max, mode.hoist, lift))


def _rail_end(c, x, dx, accel):
    """The rail end the trolley is at and moving past, or None."""
    outward = dx if dx != 0 else accel
    if x > c.x_max or (x == c.x_max and outward > 0):
        return "x_max", c.x_max
    if x < c.x_min or (x == c.x_min and outward < 0):
        return "x_min", c.x_min
    return None


def _hold(value, rate, pressing, held, low, high):
    """``(value, held, reached)`` of one limited quantity after an event.

    A held quantity is let go when the acceleration ``pressing`` turns away from its limit. A free one
    that reached a limit while moving or pressed towards it (or passed it, within the host's event
    tolerance) is set onto it (``reached``) and held while pressed on.
    """
    if held > 0 and pressing < 0 or held < 0 and pressing > 0:
        held = 0
    if held == 0:
        if value > high or (value == high and (rate > 0 or pressing > 0)):
            return high, (1 if pressing > 0 else 0), True
        if value < low or (value == low and (rate < 0 or pressing < 0)):
            return low, (-1 if pressing < 0 else 0), True
    return value, held, False


def event_update(config, state, inputs, mode, time):
    """The state and mode after an event at ``time`` (also at the end of initialisation).

    Returns
    -------
    Event
        The trolley at a rail end and moving past it ends the simulation (``terminate`` says why);
        a speed that reached its limit is set onto it and held while the demand pushes on; a cable
        that reached ``l1_min`` or ``l1_max`` is set onto it at rest and held while the hoist pulls on.
    """
    c = config
    state = list(state)
    push = _trolley(c, state, inputs, _NO_SEED)[0]
    lift = inputs[IN.hoist]
    end = _rail_end(c, state[X], state[DX], 0.0 if mode.speed else push)
    if end is not None:
        return Event(tuple(state), mode, [], f"the trolley reached the rail end {end[0]} = {end[1]!r} m "
                                             f"(x = {state[X]!r} m) at t = {time!r} s")
    messages = []
    state[DX], speed, _ = _hold(state[DX], push, push, mode.speed, -c.v_max, c.v_max)
    dl1 = state[DL1]
    state[L1], cable, reached = _hold(state[L1], dl1, lift, mode.cable, c.l1_min, c.l1_max)
    if cable or reached:
        if reached and dl1 != 0.0:
            messages.append(reached_limit(state[L1], time, dl1)[1])
        state[DL1], hoist = 0.0, 0
    else:
        state[DL1], hoist, _ = _hold(dl1, lift, lift, mode.hoist, -c.dl1_max, c.dl1_max)
    return Event(tuple(state), Mode(speed, cable, hoist), messages, None)


def jacobians(config, state, inputs, mode):
    """``(A, B, C, D)``: the derivatives' and the outputs' Jacobians by the state and the inputs, exactly.

    Lists of rows: ``A[i][j] = d(derivative i)/d(state j)``, ``B`` by the inputs, ``C`` and ``D``
    the outputs' (table order) likewise; columns from :func:`derivatives` and :func:`output_values`
    along each unit seed. At rest the swing rows are :func:`.plant_equations.linearisation`.
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
