"""The CranePlant3D FMU kind: the overhead crane in three dimensions, its variables, rules and communication step.

The equations of motion are in :mod:`.plant3d_equations` (the spatial double pendulum under a trolley that
moves in x and y, with the hoist), the plant as a host integrates it in :mod:`.plant3d_continuous`. Each
horizontal axis has the planar plant's drive (:mod:`.plant_limits`): the demand limited to its ``u_max``, a
first-order lag ``tau``, a speed limit ``v_max`` and rail ends; the hoist is the planar plant's. The state is
the swing-and-hoist state of :mod:`.plant3d_equations` followed by the two drives' accelerations and the
trolley's mean accelerations over the last sub-step (:data:`DRIVE_X`, ..., :data:`ACCEL_Y`).

Angles: ``theta1x`` and ``theta1y`` are the main cable's ``a`` and ``b`` of (S1), ``theta2x`` and ``theta2y`` the
lower cable's: ``theta.x`` is the angle of the cable's projection onto the x-z plane from the downward vertical
(the planar plant's ``theta``), ``theta.y`` the cable's angle out of that plane, towards +y. Linearised at rest
they are the swing angles of two planar cranes, one per axis.
"""

import math
from collections import namedtuple

from . import plant3d_continuous as continuous
from .component import Axis, Component, Continuous, Crane, Discard, Step
from .limits import NO_LIMIT, unlimited
from .linalg import total
from .parameters import PLANT_RULES, plant_parameters
from .plant3d_equations import DL1, DX, DY, L1, X, Y, outputs, rk4_step, substeps, swing_stepper
from .plant_equations import linearisation
from .plant_limits import clamp, drive_factors, held_cable, past_rail_end, reached_limit, within_speed
from .rules import check, finite, limit, non_negative, positive, rule
from .tables import CRANE_MODEL, PLANT_MODEL, input_, local, output, parameter, positions

DRIVE_X, DRIVE_Y = continuous.DRIVE_X, continuous.DRIVE_Y  # the drives' accelerations (after the lag)
ACCEL_X, ACCEL_Y = DRIVE_Y + 1, DRIVE_Y + 2  # the trolley's mean accelerations over the last sub-step
SWING_STATE = ("x", "dx", "y", "dy", "theta1x", "dtheta1x", "theta1y", "dtheta1y", "theta2x", "dtheta2x", "theta2y",
               "dtheta2y")
INITIAL_STATE = ("x0", "dx0", "y0", "dy0", "theta1x_0", "dtheta1x_0", "theta1y_0", "dtheta1y_0", "theta2x_0",
                 "dtheta2x_0", "theta2y_0", "dtheta2y_0")

INF = NO_LIMIT  # no limit, as a finite start value (limits.py says why); configure() makes it inf
UNLIMITED = ("ux_max", "vx_max", "x_min", "x_max", "uy_max", "vy_max", "y_min", "y_max", "l1_max", "dl1_max")

_SWING_ROWS = {
    "x": ("m", "trolley position along x (the bridge's rails' direction is y)"),
    "dx": ("m/s", "trolley velocity along x"),
    "y": ("m", "trolley position along y"),
    "dy": ("m/s", "trolley velocity along y"),
    "theta1x": ("rad", "hook cable's angle in the x-z plane from the vertical (its projection's; the planar theta1)"),
    "dtheta1x": ("rad/s", "rate of theta1x"),
    "theta1y": ("rad", "hook cable's angle out of the x-z plane, towards +y"),
    "dtheta1y": ("rad/s", "rate of theta1y"),
    "theta2x": ("rad", "load cable's angle in the x-z plane from the vertical (its projection's; the planar theta2)"),
    "dtheta2x": ("rad/s", "rate of theta2x"),
    "theta2y": ("rad", "load cable's angle out of the x-z plane, towards +y"),
    "dtheta2y": ("rad/s", "rate of theta2y"),
}


def _axis_parameters(name, what):
    return (
        parameter(f"u{name}_max", INF, "m/s2", f"{what}: largest |acceleration|; 1e60 or INF: no limit"),
        parameter(f"v{name}_max", INF, "m/s", f"{what}: largest speed; 1e60 or INF: no limit"),
        parameter(f"tau_{name}", 0.0, "s", f"{what}: first-order lag of the acceleration; 0: none"),
        parameter(f"{name}_min", -INF, "m", f"rail end: the trolley cannot pass below this {name}; -1e60 or -INF: "
                                            "none"),
        parameter(f"{name}_max", INF, "m", f"rail end: the trolley cannot pass above this {name}; 1e60 or INF: none"),
    )


VARIABLES = PLANT_MODEL + tuple(
    parameter(start, math.pi / 18 if start == "theta1x_0" else 0.0, _SWING_ROWS[name][0],
              "initial " + _SWING_ROWS[name][1])
    for start, name in zip(INITIAL_STATE, SWING_STATE)) + (
    parameter("max_substep", 1e-3, "s", "longest RK4 sub-step inside doStep"),
    parameter("c1", 0.0, "N.m.s/rad", "viscous damping of the hook cable's swing (at the trolley)"),
    parameter("c2", 0.0, "N.m.s/rad", "viscous damping of the load cable's swing relative to the hook cable's"),
    *_axis_parameters("x", "drive along x"),
    *_axis_parameters("y", "drive along y"),
    parameter("l1_min", 0.0, "m", "hoist: shortest main cable; 0: no limit"),
    parameter("l1_max", INF, "m", "hoist: longest main cable; 1e60 or INF: no limit"),
    parameter("dl1_max", INF, "m/s", "hoist: largest |cable speed|; 1e60 or INF: no limit"),
    input_("ux", "m/s2", "trolley acceleration along x demanded (held over each step)"),
    input_("uy", "m/s2", "trolley acceleration along y demanded (held over each step)"),
    input_("hoist", "m/s2", "hoist acceleration l1'' (held over each step), positive lowers the hook; unconnected: "
           "0, no hoisting"),
    input_("F1x", "N", "horizontal force on the hook along x (wind, a push); unconnected: 0, none"),
    input_("F1y", "N", "horizontal force on the hook along y; unconnected: 0, none"),
    input_("F2x", "N", "horizontal force on the load along x; unconnected: 0, none"),
    input_("F2y", "N", "horizontal force on the load along y; unconnected: 0, none"),
    *(output(name, unit, text) for name, (unit, text) in _SWING_ROWS.items()),
    output("x1", "m", "hook position along x"),
    output("y1", "m", "hook position along y"),
    output("z1", "m", "hook height (up positive; the trolley at 0)"),
    output("x2", "m", "load position along x"),
    output("y2", "m", "load position along y"),
    output("z2", "m", "load height (up positive; the trolley at 0)"),
    output("swing1", "rad", "hook cable's angle from the vertical (in space)"),
    output("swing2", "rad", "load cable's angle from the vertical (in space)"),
    output("energy", "J", "kinetic + potential energy of hook and load"),
    output("l1_now", "m", "main cable length trolley to hook now (starts at l1)"),
    output("dl1_now", "m/s", "main cable length rate, positive lowering"),
    output("ddx", "m/s2", "trolley acceleration along x over the last step, after the drive's limits and lag"),
    output("ddy", "m/s2", "trolley acceleration along y over the last step, after the drive's limits and lag"),
)

IN = positions(VARIABLES, "input")  # inputs[IN.hoist]: the inputs by name (continuous.INPUTS, the same order)

Drive = namedtuple("Drive", "u_max v_max tau low high")
Drive.__doc__ = ("One horizontal axis' drive and rail: ``|u| <= u_max``, lag ``tau``, ``|v| <= v_max``, "
                "``low <= x <= high``.")

# The parameters that the fast path (the swing stepper with the demands limited to their u_max and the rail and
# cable limits checked) takes into account; any other parameter away from its neutral default sends every step to
# the general path, so that no effect can be skipped.
FAST_PATH_PARAMETERS = {"m1", "m2", "l1", "l2", "g", *INITIAL_STATE, "max_substep", "ux_max", "uy_max", "x_min",
                        "x_max", "y_min", "y_max", "l1_min", "l1_max", "dl1_max"}  # dl1_max: no hoisting on it

Config = namedtuple("Config", "params max_substep state0 damping x_axis y_axis l1_min l1_max dl1_max swing_step fast")
Config.__doc__ = ("The plant's validated parameters (each axis a :class:`Drive`; limits that are off are inf); "
                  "``swing_step`` is :func:`.plant3d_equations.swing_stepper` for them, ``fast`` that every "
                  "parameter outside :data:`FAST_PATH_PARAMETERS` is neutral.")


# The parameter rules, in the order they are checked (rules.py).
RULES = (
    *positive("max_substep"),
    *PLANT_RULES,
    *non_negative("c1", "c2", "tau_x", "tau_y", "l1_min"),
    *limit("ux_max", "vx_max", "uy_max", "vy_max", "dl1_max", note="INF: no limit"),
    rule("m2 != 0 or c2 == 0", "c2 must be 0 when m2 = 0 (the hook joint then moves no mass), got {c2}"),
    rule("x_min < x_max", "x_min must be < x_max, got {x_min} and {x_max}"),
    rule("y_min < y_max", "y_min must be < y_max, got {y_min} and {y_max}"),
    *finite(*INITIAL_STATE),
    rule("x_min <= x0 <= x_max", "x0 must lie on the rail [{x_min}, {x_max}], got {x0}"),
    rule("y_min <= y0 <= y_max", "y0 must lie on the rail [{y_min}, {y_max}], got {y0}"),
    rule("l1_min <= l1 <= l1_max", "l1 must lie within [l1_min, l1_max] = [{l1_min}, {l1_max}], got {l1}"),
)


def configure(values):
    """Validated :class:`Config` from the CranePlant3D parameter values; the state starts at rest in the drives."""
    check(RULES, values)
    p = plant_parameters(values)
    state0 = tuple(values[name] for name in INITIAL_STATE)
    v = {**values, **{name: unlimited(values[name]) for name in UNLIMITED}}  # validated: numbers
    axes = [Drive(v[f"u{a}_max"], v[f"v{a}_max"], v[f"tau_{a}"], v[f"{a}_min"], v[f"{a}_max"]) for a in "xy"]
    fast = all(v[row.name] == (unlimited(row.start) if row.name in UNLIMITED else row.start) for row in VARIABLES
               if row.causality == "parameter" and row.name not in FAST_PATH_PARAMETERS)
    return Config(params=p, max_substep=v["max_substep"], state0=state0 + (p.l1, 0.0, 0.0, 0.0, 0.0, 0.0),
                  damping=(v["c1"], v["c2"]), x_axis=axes[0], y_axis=axes[1], l1_min=v["l1_min"], l1_max=v["l1_max"],
                  dl1_max=v["dl1_max"], swing_step=swing_stepper(p), fast=fast)


def _not_finite(time, inputs):
    return Discard(f"plant state became non-finite in the step from t={time!r} s (ux={inputs[IN.ux]!r}, "
                   f"uy={inputs[IN.uy]!r} m/s2); the step is discarded")  # IN.ux, IN.uy: 0, 1


def update(config, state, inputs, time, step):
    """The state after one communication step with the inputs held.

    Steps where nothing but the trolley's accelerations act, with the cable at rest within its limits and every
    other effect at its neutral parameter value, take :func:`fast_update`; the others :func:`general_update`.
    Both give the same numbers where both apply.
    """
    if config.fast and not any(inputs[IN.hoist:]) and state[DL1] == 0.0 \
            and config.l1_min <= state[L1] <= config.l1_max:
        return fast_update(config, state, inputs[IN.ux], inputs[IN.uy], time, step)
    return general_update(config, state, inputs, time, step)


def fast_update(c, state, ux, uy, time, step):
    """:func:`general_update` with nothing but the trolley acting: no hoisting, forces, damping, lags or speed
    limits."""
    n = 1 if 0.0 < step <= c.max_substep else substeps(step, c.max_substep)  # ValueError for an unusable step
    dt = step / n
    xa, ya = c.x_axis, c.y_axis
    ax = xa.u_max if ux > xa.u_max else -xa.u_max if ux < -xa.u_max else ux  # clamp(), without its calls
    ay = ya.u_max if uy > ya.u_max else -ya.u_max if uy < -ya.u_max else uy
    swing = state[:DRIVE_X]
    try:
        for k in range(n):
            swing = c.swing_step(swing, ax, ay, dt)
            if not xa.low <= swing[X] <= xa.high:
                raise past_rail_end(xa.low, xa.high, swing[X], time + (k + 1) * dt, time, "x")
            if not ya.low <= swing[Y] <= ya.high:
                raise past_rail_end(ya.low, ya.high, swing[Y], time + (k + 1) * dt, time, "y")
        # a finite sum has finite terms (inf and nan propagate); only an overflowing sum needs a closer look
        finite_state = math.isfinite(total(swing)) or all(map(math.isfinite, swing))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        finite_state = False
    if not finite_state:
        raise _not_finite(time, (ux, uy))
    return swing + (ax, ay, ax, ay)


def general_update(config, state, inputs, time, step):
    """The state after one communication step with the inputs held, every effect included.

    Per RK4 sub-step ``dt`` and per axis, as the planar plant's :func:`.plant.general_update`: the demand is
    limited to ``u_max``, the drive follows it with the lag ``tau`` (exactly, the trolley taking its mean over
    the sub-step), and the acceleration is limited so that the speed ends within ``v_max``; the hoist
    acceleration is limited by ``dl1_max``, and a cable reaching ``l1_min`` or ``l1_max`` is held there at rest.
    A trolley that would pass a rail end, or a state that becomes non-finite, discards the step. With the cable
    at rest and nothing but the trolley acting, a sub-step is :func:`.plant3d_equations.swing_stepper`'s (the same
    numbers as :func:`.plant3d_equations.rk4_step`'s, faster).
    """
    hoist, f1x, f1y, f2x, f2y = (inputs[i] for i in (IN.hoist, IN.F1x, IN.F1y, IN.F2x, IN.F2y))
    c, p = config, config.params
    if p.m2 == 0 and (f2x != 0 or f2y != 0):
        raise Discard(f"F2 = ({f2x!r}, {f2y!r}) N acts on a load of mass m2 = 0: the step is discarded")
    n = substeps(step, c.max_substep)  # ValueError for an unusable step
    dt = step / n
    forces = (f1x, f1y, f2x, f2y, *c.damping)
    axes = tuple((axis, clamp(inputs[i], -axis.u_max, axis.u_max), *drive_factors(axis.tau, dt), speed, at, name)
                 for axis, i, speed, at, name in ((c.x_axis, IN.ux, DX, X, "x"), (c.y_axis, IN.uy, DY, Y, "y")))
    messages, notes = [], []
    swing, drives, accels = state[:DRIVE_X], [state[DRIVE_X], state[DRIVE_Y]], [0.0, 0.0]
    try:
        for k in range(n):
            for i, (axis, demand, lag, mean, speed, _, _) in enumerate(axes):
                accel = demand + (drives[i] - demand) * mean if axis.tau > 0 else demand
                drives[i] = demand + (drives[i] - demand) * lag
                accels[i] = within_speed(accel, swing[speed], axis.v_max, dt)
            cable_rate = swing[DL1]
            hoist_now = within_speed(hoist, cable_rate, c.dl1_max, dt)
            if hoist_now == 0.0 and cable_rate == 0.0 and not any(forces):
                swing = c.swing_step(swing, accels[0], accels[1], dt)
            else:
                swing = rk4_step(swing, accels[0], accels[1], dt, p, hoist_now, forces)
            t = time + (k + 1) * dt
            for axis, _, _, _, _, at, name in axes:
                if not axis.low <= swing[at] <= axis.high:
                    raise past_rail_end(axis.low, axis.high, swing[at], t, time, name)
            held = held_cable(swing[L1], c.l1_min, c.l1_max)
            if held is not None:
                if cable_rate != 0.0:  # reached the limit in this sub-step (not already held there)
                    warning, text = reached_limit(held, t, swing[DL1])
                    (messages if warning else notes).append(text)
                swing = swing[:L1] + (held, 0.0)
        finite_state = all(map(math.isfinite, swing))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        finite_state = False
    if not finite_state:
        raise _not_finite(time, inputs)
    state = swing + (drives[0], drives[1], accels[0], accels[1])
    return Step(state, messages, notes) if messages or notes else state


def linearised(values):
    """The swing state (:data:`SWING_STATE`) at rest linearised: ``(A, B)``, inputs ``(ux, uy)`` (lists of rows).

    ``values``: the crane's model parameters (``m1``, ``m2``, ``l1``, ``l2``, ``g``), each defaulting to its start.

    Notes
    -----
    Two planar cranes, one per axis (the axes' tests: ``tests/test_plant3d.py``): each axis' rows are
    :func:`.plant_equations.linearisation`'s ``q'' = -W q - w u`` and the trolley's ``x'' = u``; no coupling.
    """
    big_w, small_w = linearisation(plant_parameters({**{v.name: v.start for v in PLANT_MODEL}, **values}))
    n = len(SWING_STATE)
    a, b = [[0.0] * n for _ in range(n)], [[0.0, 0.0] for _ in range(n)]
    for column, axis in enumerate("xy"):
        x, dx, q1, w1, q2, w2 = (SWING_STATE.index(name) for name in (
            axis, "d" + axis, "theta1" + axis, "dtheta1" + axis, "theta2" + axis, "dtheta2" + axis))
        a[x][dx] = a[q1][w1] = a[q2][w2] = 1.0
        for row, i in ((w1, 0), (w2, 1)):
            a[row][q1], a[row][q2] = -big_w[i][0], -big_w[i][1]
            b[row][column] = -small_w[i]
        b[dx][column] = 1.0
    return a, b


def _outputs(config, state, inputs):
    return state[:L1] + outputs(state, config.params) + (state[L1], state[DL1], state[ACCEL_X], state[ACCEL_Y])


CONTINUOUS = Continuous(
    states=continuous.STATES,
    derivatives=("dx", "ddx", "dy", "ddy", "dtheta1x", "der(dtheta1x)", "dtheta1y", "der(dtheta1y)", "dtheta2x",
                 "der(dtheta2x)", "dtheta2y", "der(dtheta2y)", "dl1_now", "der(dl1_now)", "der(drive_x)",
                 "der(drive_y)"),
    variables=(
        local("drive_x", "m/s2", "drive's acceleration along x, after its lag tau_x, before the speed limit"),
        local("drive_y", "m/s2", "drive's acceleration along y, after its lag tau_y, before the speed limit"),
        local("der(dtheta1x)", "rad/s2", "acceleration of theta1x"),
        local("der(dtheta1y)", "rad/s2", "acceleration of theta1y"),
        local("der(dtheta2x)", "rad/s2", "acceleration of theta2x"),
        local("der(dtheta2y)", "rad/s2", "acceleration of theta2y"),
        local("der(dl1_now)", "m/s2", "hoist acceleration applied (0 while the cable or its speed is held)"),
        local("der(drive_x)", "m/s3", "rate of the drive's acceleration along x, (demand - drive) / tau_x"),
        local("der(drive_y)", "m/s3", "rate of the drive's acceleration along y, (demand - drive) / tau_y"),
    ),
    indicators=continuous.INDICATORS,
    initial=continuous.initial,
    derivatives_of=continuous.derivatives,
    outputs_of=continuous.output_values,
    indicators_of=continuous.event_indicators,
    event_update=continuous.event_update,
    free_mode=continuous.FREE,
)

CRANE = Crane(
    state=SWING_STATE, starts=INITIAL_STATE, axes=(Axis("x", "dx", "ux"), Axis("y", "dy", "uy")),
    swing=("swing1", "swing2"), sensed=("x", "y", "theta1x", "theta1y", "theta2x", "theta2y"),
    model=tuple(v.name for v in PLANT_MODEL), hook=("x1", "y1", "z1"), load=("x2", "y2", "z2"), hoist="hoist",
    cable="l1_now", forces=("F1x", "F1y", "F2x", "F2y"), start_swing="theta1x_0", linearised=linearised)

COMPONENT = Component(
    "CranePlant3D", "plant",
    "Overhead crane in three dimensions: a trolley moving in x and y (a drive per axis), the hook (m1 on cable l1) "
    "and the load (m2 on cable l2) as a spatial double pendulum, the hoist; inputs: trolley and hoist "
    "accelerations, horizontal forces; fixed-step RK4 inside doStep",
    VARIABLES, configure, _outputs,
    initial_state=lambda config: config.state0, update=update, continuous=CONTINUOUS,
    crane_model=CRANE_MODEL, native="crane_plant3d.c", crane=CRANE, rules=RULES)
