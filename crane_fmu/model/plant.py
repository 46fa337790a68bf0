"""The CranePlant FMU kind: its variables, parameter rules and communication step.

The equations of motion are in :mod:`.plant_equations` (eqs (4)-(9) and their
extensions), the drive, rail and hoist limits in :mod:`.plant_limits`; this
module puts them together. The plant's state is the swing and hoist state of
:mod:`.plant_equations` followed by the drive's acceleration and the trolley's
mean acceleration over the last sub-step (positions :data:`DRIVE`, :data:`ACCEL`).
"""

import math
from collections import namedtuple

from . import plant_continuous
from .component import Axis, Component, Continuous, Crane, Discard, Step
from .limits import NO_LIMIT, unlimited
from .linalg import total
from .parameters import PLANT_RULES, plant_parameters
from .plant_equations import (  # noqa: F401 (the plant's equations, importable from here)
    DL1,
    DX,
    L1,
    MAX_SUBSTEPS,
    NO_LOAD,
    THETA1,
    X,
    accelerations_tangent,
    advance,
    angular_accelerations,
    derivative,
    energy,
    linearisation,
    outputs,
    paper_stepper,
    rk4_step,
    substeps,
)
from .plant_limits import clamp, drive_factors, held_cable, past_rail_end, reached_limit, within_speed
from .rules import check, finite, limit, non_negative, positive, rule
from .tables import CRANE_MODEL, PLANT_MODEL, input_, local, output, parameter

DRIVE, ACCEL = plant_continuous.DRIVE, plant_continuous.DRIVE + 1  # the drive's and the trolley's mean acceleration
INITIAL_STATE = ("x0", "dx0", "theta1_0", "dtheta1_0", "theta2_0", "dtheta2_0")

INF = NO_LIMIT  # no limit, as a finite start value (limits.py says why); configure() makes it inf
UNLIMITED = ("u_max", "v_max", "x_min", "x_max", "l1_max", "dl1_max")  # off at +-1e60 and beyond

VARIABLES = PLANT_MODEL + (
    parameter("x0", 0.0, "m", "initial trolley position"),
    parameter("dx0", 0.0, "m/s", "initial trolley velocity"),
    parameter("theta1_0", math.pi / 18, "rad", "initial hook swing angle"),
    parameter("dtheta1_0", 0.0, "rad/s", "initial hook swing rate"),
    parameter("theta2_0", 0.0, "rad", "initial payload swing angle"),
    parameter("dtheta2_0", 0.0, "rad/s", "initial payload swing rate"),
    parameter("max_substep", 1e-3, "s", "longest RK4 sub-step inside doStep"),
    parameter("c1", 0.0, "N.m.s/rad", "viscous damping at the trolley joint"),
    parameter("c2", 0.0, "N.m.s/rad", "viscous damping at the hook joint"),
    parameter("u_max", INF, "m/s2", "trolley drive: largest |acceleration|; 1e60 or INF: no limit"),
    parameter("v_max", INF, "m/s", "trolley drive: largest speed; 1e60 or INF: no limit"),
    parameter("tau", 0.0, "s", "trolley drive: first-order lag of the acceleration; 0: none"),
    parameter("x_min", -INF, "m", "rail end: the trolley cannot pass below this position; -1e60 or -INF: none"),
    parameter("x_max", INF, "m", "rail end: the trolley cannot pass above this position; 1e60 or INF: none"),
    parameter("l1_min", 0.0, "m", "hoist: shortest main cable; 0: no limit"),
    parameter("l1_max", INF, "m", "hoist: longest main cable; 1e60 or INF: no limit"),
    parameter("dl1_max", INF, "m/s", "hoist: largest |cable speed|; 1e60 or INF: no limit"),
    input_("u", "m/s2", "trolley acceleration demanded (held over each step)"),
    input_("hoist", "m/s2", "hoist acceleration l1'' (held over each step), positive lowers the hook; unconnected: "
           "0, no hoisting"),
    input_("F1", "N", "horizontal force on the hook (wind, a push); unconnected: 0, none"),
    input_("F2", "N", "horizontal force on the payload (wind, a push); unconnected: 0, none"),
    output("x", "m", "trolley position"),
    output("dx", "m/s", "trolley velocity"),
    output("theta1", "rad", "hook swing angle from vertical"),
    output("dtheta1", "rad/s", "hook swing rate"),
    output("theta2", "rad", "payload swing angle from vertical"),
    output("dtheta2", "rad/s", "payload swing rate"),
    output("x1", "m", "hook horizontal position, eq (4)"),
    output("y1", "m", "hook vertical position (up positive), eq (4)"),
    output("x2", "m", "payload horizontal position, eq (5)"),
    output("y2", "m", "payload vertical position (up positive), eq (5)"),
    output("energy", "J", "kinetic + potential energy of hook and payload, eqs (6)-(7)"),
    output("l1_now", "m", "main cable length trolley to hook now (starts at l1)"),
    output("dl1_now", "m/s", "main cable length rate, positive lowering"),
    output("ddx", "m/s2", "trolley acceleration over the last step, after the drive's limits and lag"),
)

# The parameter rules, in the order they are checked (rules.py).
RULES = (
    *positive("max_substep"),
    *PLANT_RULES,
    *non_negative("c1", "c2", "tau", "l1_min"),
    *limit("u_max", "v_max", "dl1_max", note="INF: no limit"),
    rule("m2 != 0 or c2 == 0", "c2 must be 0 when m2 = 0 (the hook joint then moves no mass), got {c2}"),
    rule("x_min < x_max", "x_min must be < x_max, got {x_min} and {x_max}"),
    *finite(*INITIAL_STATE),
    rule("x_min <= x0 <= x_max", "x0 must lie on the rail [{x_min}, {x_max}], got {x0}"),
    rule("l1_min <= l1 <= l1_max", "l1 must lie within [l1_min, l1_max] = [{l1_min}, {l1_max}], got {l1}"),
)

U = 0  # the trolley acceleration among the inputs; the others (hoist, F1, F2) act when non-zero

# The parameters that the fast path (the paper's RK4 step with the demand limited to u_max and the
# rail and cable limits checked) takes into account; any other parameter away from its neutral
# default sends every step to the general path, so that no effect can be skipped.
FAST_PATH_PARAMETERS = {"m1", "m2", "l1", "l2", "g", *INITIAL_STATE, "max_substep", "u_max", "x_min", "x_max",
                        "l1_min", "l1_max", "dl1_max"}  # dl1_max: no hoisting on the fast path

Config = namedtuple("Config", "params max_substep state0 damping u_max v_max tau x_min x_max l1_min l1_max dl1_max "
                              "paper_step fast")
Config.__doc__ = ("The plant's validated parameters; ``paper_step`` is :func:`.plant_equations.paper_stepper` "
                  "for them, ``fast`` that every parameter outside :data:`FAST_PATH_PARAMETERS` is neutral.")


def configure(values):
    """Validated :class:`Config` from the CranePlant parameter values; the state starts at rest in the drive."""
    check(RULES, values)
    p = plant_parameters(values)
    state0 = tuple(values[name] for name in INITIAL_STATE)
    values = {**values, **{name: unlimited(values[name]) for name in UNLIMITED}}  # validated: numbers
    fast = all(values[v.name] == (unlimited(v.start) if v.name in UNLIMITED else v.start) for v in VARIABLES
               if v.causality == "parameter" and v.name not in FAST_PATH_PARAMETERS)
    return Config(params=p, max_substep=values["max_substep"], state0=state0 + (p.l1, 0.0, 0.0, 0.0),
                  damping=(values["c1"], values["c2"]), u_max=values["u_max"], v_max=values["v_max"],
                  tau=values["tau"], x_min=values["x_min"], x_max=values["x_max"], l1_min=values["l1_min"],
                  l1_max=values["l1_max"], dl1_max=values["dl1_max"], paper_step=paper_stepper(p), fast=fast)


def _not_finite(time, u):
    return Discard(f"plant state became non-finite in the step from t={time!r} s (u={u!r} m/s2); "
                   "the step is discarded")


def update(config, state, inputs, time, step):
    """The state after one communication step with the inputs held.

    Steps where nothing but the trolley acceleration acts, with the cable at rest within its limits
    and every other effect at its neutral parameter value, take :func:`fast_update`; the others
    :func:`general_update`. Both give the same numbers where both apply.
    """
    if config.fast and not any(inputs[U + 1:]) and state[DL1] == 0.0 \
            and config.l1_min <= state[L1] <= config.l1_max:
        return fast_update(config, state, inputs[U], time, step)
    return general_update(config, state, inputs, time, step)


def fast_update(c, state, u, time, step):
    """:func:`general_update` of the paper's model: no hoisting, forces, damping, lag or speed limits."""
    n = 1 if 0.0 < step <= c.max_substep else substeps(step, c.max_substep)  # ValueError for an unusable step
    dt = step / n
    demand = c.u_max if u > c.u_max else -c.u_max if u < -c.u_max else u  # clamp(), without its two calls
    swing = state[:DRIVE]
    try:
        for k in range(n):
            swing = c.paper_step(swing, demand, dt)
            if not c.x_min <= swing[X] <= c.x_max:
                raise past_rail_end(c.x_min, c.x_max, swing[X], time + (k + 1) * dt, time)
        # a finite sum has finite terms (inf and nan propagate); only an overflowing sum needs a closer look
        finite_state = math.isfinite(total(swing)) or all(map(math.isfinite, swing))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        finite_state = False
    if not finite_state:
        raise _not_finite(time, u)
    return swing + (demand, demand)


def general_update(config, state, inputs, time, step):
    """The state after one communication step, every effect included.

    Per RK4 sub-step ``dt``: the demand is limited to ``u_max``; the drive's
    acceleration follows it with the lag ``tau`` (exactly, and the trolley takes
    its mean over the sub-step); the trolley's acceleration is then limited so
    that the speed ends within ``v_max``; the hoist acceleration is limited
    likewise by ``dl1_max``, and a cable reaching ``l1_min`` or ``l1_max`` is held
    there at rest (reported in the step's messages). A trolley that would pass a
    rail end, or a state that becomes non-finite, discards the step. A cable reaching a hoist limit at
    rest is a note for the log, at speed a warning (:func:`.plant_limits.reached_limit`).
    """
    u, hoist, f1, f2 = inputs
    c, p = config, config.params
    if p.m2 == 0 and f2 != 0:
        raise Discard(f"F2 = {f2!r} N acts on a payload of mass m2 = 0: the step is discarded")
    n = substeps(step, c.max_substep)  # ValueError for an unusable step
    dt = step / n
    forces = (f1, f2, *c.damping)
    demand = clamp(u, -c.u_max, c.u_max)
    lag, mean = drive_factors(c.tau, dt)
    messages, notes = [], []
    swing, drive = state[:DRIVE], state[DRIVE]
    try:
        for k in range(n):
            accel = demand + (drive - demand) * mean if c.tau > 0 else demand
            drive = demand + (drive - demand) * lag
            cable_rate = swing[DL1]
            accel = within_speed(accel, swing[DX], c.v_max, dt)
            hoist_now = within_speed(hoist, cable_rate, c.dl1_max, dt)
            if hoist_now == 0.0 and cable_rate == 0.0 and not any(forces):
                swing = c.paper_step(swing, accel, dt)
            else:
                swing = rk4_step(swing, accel, dt, p, hoist_now, forces)
            t = time + (k + 1) * dt
            if not c.x_min <= swing[X] <= c.x_max:
                raise past_rail_end(c.x_min, c.x_max, swing[X], t, time)
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
        raise _not_finite(time, u)
    state = swing + (drive, accel)
    return Step(state, messages, notes) if messages or notes else state


def _outputs(config, state, inputs):
    return outputs(state, config.params) + (state[L1], state[DL1], state[ACCEL])


CONTINUOUS = Continuous(
    states=plant_continuous.STATES,
    derivatives=("dx", "ddx", "dtheta1", "der(dtheta1)", "dtheta2", "der(dtheta2)", "dl1_now", "der(dl1_now)",
                 "der(drive)"),
    variables=(
        local("drive", "m/s2", "trolley drive's acceleration, after its lag tau, before the speed limit"),
        local("der(dtheta1)", "rad/s2", "hook swing acceleration, eqs (8)-(9)"),
        local("der(dtheta2)", "rad/s2", "payload swing acceleration, eqs (8)-(9)"),
        local("der(dl1_now)", "m/s2", "hoist acceleration applied (0 while the cable or its speed is held)"),
        local("der(drive)", "m/s3", "rate of the drive's acceleration, (demand - drive) / tau"),
    ),
    indicators=plant_continuous.INDICATORS,
    initial=plant_continuous.initial,
    derivatives_of=plant_continuous.derivatives,
    outputs_of=plant_continuous.output_values,
    indicators_of=plant_continuous.event_indicators,
    event_update=plant_continuous.event_update,
    free_mode=plant_continuous.FREE,
)

def linearised(values):
    """The state ``(x, dx, theta1, dtheta1, theta2, dtheta2)`` at rest linearised: ``(A, B)``, input ``u``.

    Notes
    -----
    The swing rows are :func:`.plant_equations.linearisation`'s ``q'' = -W q - w u``; the trolley's ``x'' = u``.
    """
    big_w, small_w = linearisation(plant_parameters(values))
    a = [[0.0] * 6 for _ in range(6)]
    a[0][1] = a[2][3] = a[4][5] = 1.0
    for row, i in ((3, 0), (5, 1)):
        a[row][2], a[row][4] = -big_w[i][0], -big_w[i][1]
    return a, [[0.0], [1.0], [0.0], [-small_w[0]], [0.0], [-small_w[1]]]


CRANE = Crane(
    state=("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"), starts=INITIAL_STATE, axes=(Axis("x", "dx", "u"),),
    swing=("theta1", "theta2"), sensed=("x", "theta1", "theta2"), model=tuple(v.name for v in PLANT_MODEL),
    hook=("x1", "y1"), load=("x2", "y2"), hoist="hoist", cable="l1_now", forces=("F1", "F2"),
    start_swing="theta1_0", linearised=linearised)

COMPONENT = Component(
    "CranePlant", "plant",
    "Overhead crane with a double-pendulum payload (hook m1 on cable l1, payload m2 on cable l2); "
    "inputs: trolley and hoist accelerations, horizontal forces; fixed-step RK4 inside doStep",
    VARIABLES, configure, _outputs,
    initial_state=lambda config: config.state0, update=update, continuous=CONTINUOUS,
    crane_model=CRANE_MODEL, native="crane_plant.c", crane=CRANE, rules=RULES)
