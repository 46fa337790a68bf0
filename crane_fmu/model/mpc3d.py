"""The MpcController3D component: the constrained MPC of :mod:`.mpc` on each axis of the crane in three dimensions.

Linearised at rest the spatial crane is a planar crane per axis (:func:`.plant3d.linearised`), so each axis runs
the planar MPC (:mod:`.mpc`: the shortest move within the drive's limits, planned, tracked by a QP every interval)
on its own states, with that axis' limits as the constraints of its QPs. The nonlinear coupling is left to the
tracking and to new plans.

A path: with ``corridor > 0`` the load goes from ``(x0, y0)`` through the waypoint ``(x_via, y_via)`` to
``(x_d, y_d)``; each axis makes its one move of the path (an L path: x, then y), the later leg started as early as
a time-optimal move of the limits the plans use (``1 - margin`` of them) keeps within half the corridor of the
path's centre line (:func:`.path.plan`, unshaped). Before its start an axis holds its start position.

The wind's force: each axis' planar MPC takes that axis' estimated forces (``F2x_hat``, ``F1x_hat``; ``F2y_hat``,
``F1y_hat``: a planar ``StateEstimator`` with the force states on the axis' signals) and, with ``offset_free``
(1: the load, 2: the trolley at the axis' target), tracks and hands over to the rest they hold
(:func:`.mpc.force_shift`).
Its C twin is fmu_src/models/mpc3d.c (over mpc_axis.c, the planar MPC's C), bit-equal.
"""

from collections import namedtuple

from . import mpc, path
from .component import Component, Step
from .planner import TIME_ROUNDING
from .plant3d import _SWING_ROWS, SWING_STATE
from .rules import check, finite, non_negative
from .tables import CRANE_MODEL, input_, output, parameter, positions

AXES = ("x", "y")
Q_X = 600.0  # the trolley's weight: a path's corner is met on time (the planar MPC's 50 keeps the move's end soft)
OWN = ("x_d", "l1_low", "l1_high")  # the planar MPC's parameters each axis sets (no gain schedule: no hoist)
PLANAR = {v.name for v in mpc.VARIABLES if v.causality == "parameter"} - set(OWN)


def axis_states(axis):
    """The states of one axis, in the planar order: ``(x, dx, theta1x, dtheta1x, theta2x, dtheta2x)``."""
    return (axis, "d" + axis, "theta1" + axis, "dtheta1" + axis, "theta2" + axis, "dtheta2" + axis)


def axis_forces(axis):
    """The estimated forces one axis takes, in the planar MPC's order: on the load, then on the hook."""
    return ("F2" + axis + "_hat", "F1" + axis + "_hat")


Axis = namedtuple("Axis", "before after t0")
Axis.__doc__ = "One axis: the planar MPC's configuration before its move's start ``t0`` (holding) and after it."
Config = namedtuple("Config", "axes memo")
Config.__doc__ = ("The axes (:class:`Axis`), and the last state split into the axes' (the same objects for the output "
                  "and the step, so that each axis' solve is made once: :func:`.mpc._solved`).")


def configure(values):
    """Validated parameters and each axis' planar MPC configurations (their designs made here)."""
    check(RULES, values)
    planar = {name: values[name] for name in PLANAR}
    moves = {a: {"x0": values[a + "0"], "x_d": values[a + "_d"], "t0": 0.0} for a in AXES}
    if values["corridor"] > 0:
        shrink = 1.0 - values["margin"]
        waypoints = [tuple(values[a + suffix] for a in AXES) for suffix in ("0", "_via", "_d")]
        moves = path.plan(waypoints, values["corridor"] / 2, {
            **{n: values[n] for n in CRANE_MODEL}, "shaper": "none", "u_max": values["u_max"] * shrink,
            "v_max": values["v_max"] * shrink})
    axes = []
    for a in AXES:
        fixed = {"l1_low": 0.0, "l1_high": 0.0}
        after = mpc.configure({**planar, "x_d": moves[a]["x_d"], **fixed})
        before = after if moves[a]["t0"] <= 0 else mpc.configure({**planar, "x_d": moves[a]["x0"], **fixed})
        axes.append(Axis(before, after, moves[a]["t0"]))
    return Config(tuple(axes), {})


def _started(axis, time):
    """Whether the axis' move has started at ``time``: a time within the planner's rounding margin short of its start
    ``t0`` is at it, as the planner takes a time within it of a step of its plan (a host that adds up its steps,
    OMSimulator, reaches mpc3d-path's t0 = 2.864 s as 2.86399999999990..., where the master's ``k h`` is 2.864)."""
    return time >= axis.t0 - TIME_ROUNDING * max(1.0, abs(time))


def _config(axis, time):
    return axis.after if _started(axis, time) else axis.before


def initial_state(config):
    """``(time, length of the x axis' state, x axis' state..., y axis' state...)``."""
    x, y = (mpc.initial_state(_config(a, 0.0)) for a in config.axes)
    return (0.0, float(len(x))) + x + y


def _split(config, state):
    memo = config.memo
    if memo.get("state") is not state:
        n = int(state[1])
        memo["state"], memo["split"] = state, (state[2:2 + n], state[2 + n:])
    return memo["split"]


def _axis_inputs(inputs, k):
    # the planar MPC's inputs: the axis' states, l1_now (none), the axis' F2_hat, F1_hat
    return tuple(inputs[i] for i in _MEASURED[k]) + (0.0,) + tuple(inputs[i] for i in _FORCES[k])


def _output(config, state, inputs):
    time = state[0]
    return tuple(mpc.COMPONENT.output(_config(a, time), s, _axis_inputs(inputs, k))[0]
                 for k, (a, s) in enumerate(zip(config.axes, _split(config, state))))


def update(config, state, inputs, time, step):
    """Each axis' planar MPC step; an axis whose move starts within the step starts its MPC afresh (a new plan)."""
    new, messages = [], []
    for k, (a, s) in enumerate(zip(config.axes, _split(config, state))):
        done = mpc.update(_config(a, state[0]), s, _axis_inputs(inputs, k), time, step)
        if isinstance(done, Step):
            messages += [f"{AXES[k]} axis: {m}" for m in done.messages]
            done = done.state
        if not _started(a, state[0]) and _started(a, time + step):
            done = mpc.initial_state(a.after)
        new.append(tuple(done))
    result = (time + step, float(len(new[0]))) + new[0] + new[1]
    return Step(result, messages) if messages else result


def report(config):
    """Each axis' move start and the planar MPC's report."""
    return {**{f"t0_{a}_s": axis.t0 for a, axis in zip(AXES, config.axes)}, **mpc.report(config.axes[0].after)}


def _own(v):
    if v.name == "q_x":
        return v._replace(start=Q_X)
    if v.name == "offset_free":
        return v._replace(description="each axis' estimated forces (F2x_hat, F1x_hat; F2y_hat, F1y_hat): 0 ignored; "
                                      "1 the load, 2 the trolley held at the axis' target, the cables at the forces' "
                                      "rest (offset-free)")
    return v


VARIABLES = tuple(_own(v) for v in mpc.VARIABLES if v.causality == "parameter" and v.name not in OWN) + (
    parameter("x0", 0.0, "m", "where the trolley starts along x (a path's first point)"),
    parameter("y0", 0.0, "m", "where the trolley starts along y"),
    parameter("x_d", 0.0, "m", "target trolley position along x: the plan's end"),
    parameter("y_d", 0.0, "m", "target trolley position along y: the plan's end"),
    parameter("x_via", 0.0, "m", "a path's waypoint along x (with corridor > 0)"),
    parameter("y_via", 0.0, "m", "a path's waypoint along y (with corridor > 0)"),
    parameter("corridor", 0.0, "m", "a path through (x_via, y_via): the width kept about its centre line; 0: a "
                                    "straight move to (x_d, y_d)"),
) + tuple(input_(name, _SWING_ROWS[name][0], "measured " + _SWING_ROWS[name][1]) for name in SWING_STATE) + (
    *(input_(name, "N", f"estimated horizontal force on the {'payload' if name[1] == '2' else 'hook'} along "
             f"{axis} (a StateEstimator's on that axis); unconnected: 0, none")
      for axis in AXES for name in axis_forces(axis)),
    output("ux", "m/s2", "demanded trolley acceleration along x: the x axis' MPC's, held over its interval"),
    output("uy", "m/s2", "demanded trolley acceleration along y: the y axis' MPC's, held over its interval"),
)
IN = positions(VARIABLES, "input")
_MEASURED = tuple(tuple(getattr(IN, n) for n in axis_states(a)) for a in AXES)
_FORCES = tuple(tuple(getattr(IN, n) for n in axis_forces(a)) for a in AXES)
RULES = (*(r for r in mpc.RULES if set(r.names) <= PLANAR), *finite("x0", "y0", "x_d", "y_d", "x_via", "y_via"),
         *non_negative("corridor"))  # >= 0 and finite

COMPONENT = Component(
    "MpcController3D", "controller",
    "Constrained model-predictive control of the crane in three dimensions: the planar MPC on each axis (its "
    "drive's limits as constraints), straight to (x_d, y_d) or along a path through a waypoint; outputs: trolley "
    "accelerations ux, uy",
    VARIABLES, configure, _output, feedthrough=True, initial_state=initial_state, update=update, report=report,
    depends_on={f"u{a}": axis_states(a) + axis_forces(a) for a in AXES},  # each axis' demand reads its own inputs
    crane_model=CRANE_MODEL, native="mpc3d.c", rules=RULES)
