"""The LqrController3D component: the discrete LQR of the crane in three dimensions, one design per axis.

Linearised at rest, the spatial double pendulum of :mod:`.plant3d` is two uncoupled planar cranes, one per
horizontal axis (:func:`.plant3d.linearised`). The controller reads each axis' block of that linearisation by
the plant's roles (its axes and states) and designs the planar LQR for it (:func:`.lqr.design_of`); each axis's
demand is then the planar law of :func:`.lqr.control` on that axis' states: ``u_a = dd_ref - K_a (s_a - s_a,ref)``
within ``|u| <= u_max`` and ``|v| <= v_max``. The nonlinear coupling between the axes is left to feedback.

The wind's force (issue 52, item 3). Each axis takes the estimated horizontal forces on its load and hook
(``F2x_hat``, ``F1x_hat``; ``F2y_hat``, ``F1y_hat``: a planar ``StateEstimator`` with the force states on that
axis' signals, sound as the linearisation at rest is the planar crane per axis, forces included:
tests/test_force3d.py) and with ``offset_free`` (1: the load, 2: the trolley at the axis' target) regulates to the
rest they hold, the planar :func:`.lqr.control`'s offset-free target (:func:`.lqr.force_target`) on each axis. No
force or ``offset_free = 0``: the plain law, bit for bit.
"""

from collections import namedtuple

from . import limits, linalg
from .component import Component
from .lqr import DEFAULT_WEIGHTS, OFFSET_FREE, WEIGHTS, design_of, force_target
from .parameters import PLANT_RULES, plant_parameters
from .plant3d import _SWING_ROWS, CRANE, SWING_STATE
from .rules import check, finite, non_negative, one_of, positive, rule
from .tables import CRANE_MODEL, controller_model, input_, output, parameter, positions

AXES = tuple(a.position for a in CRANE.axes)  # ("x", "y")


def axis_states(axis):
    """The states of one axis, in the planar order: ``(x, dx, theta1x, dtheta1x, theta2x, dtheta2x)``."""
    return (axis, "d" + axis, "theta1" + axis, "dtheta1" + axis, "theta2" + axis, "dtheta2" + axis)


def axis_forces(axis):
    """The estimated forces one axis takes, in :func:`.lqr.control`'s order: on the load, then on the hook."""
    return ("F2" + axis + "_hat", "F1" + axis + "_hat")


def axis_model(values, axis):
    """``(A, B)`` of one axis: its block of the plant's linearisation at rest (the crane's ``linearised`` role)."""
    a, b = CRANE.linearised({name: values[name] for name in CRANE_MODEL})
    rows = [CRANE.state.index(name) for name in axis_states(axis)]
    column = AXES.index(axis)
    return [[a[i][j] for j in rows] for i in rows], [[b[i][column]] for i in rows]


Config = namedtuple("Config", "gains targets u_max v_max h offset_free plant", defaults=(0.0, None))
Config.__doc__ = ("Each axis's gains (6) and target, in :data:`AXES` order; the limits and the step; the offset-free "
                  "target's choice and the crane model it is computed on (:func:`.lqr.force_target`).")


def configure(values):
    """Validated parameters and each axis's design."""
    check(RULES, values)
    weights = [values[name] for name in WEIGHTS]
    gains = tuple(design_of(*axis_model(values, axis), weights, values["r"], values["h"]) for axis in AXES)
    u_max, v_max = limits.of(values)
    return Config(gains=gains, targets=tuple(values[axis + "_d"] for axis in AXES), u_max=u_max, v_max=v_max,
                  h=values["h"], offset_free=values["offset_free"], plant=plant_parameters(values))


def control(config, k, measured, reference, dd_ref, forces=(0.0, 0.0)):
    """Axis ``k``'s demand: :func:`.lqr.control` on its states, ``u = dd_ref - K (s - s_ref)`` within the limits,
    with ``s_ref = reference + (target, 0, ...)``, moved with ``offset_free`` to the rest the axis' estimated
    forces ``(F2_hat, F1_hat)`` hold (:func:`.lqr.force_target`, eqs (8)-(9) at rest), as the planar law's."""
    error = [s - r for s, r in zip(measured, reference)]
    error[0] -= config.targets[k]
    if config.offset_free != 0.0 and (forces[0] != 0.0 or forces[1] != 0.0):
        dx, theta1, theta2 = force_target(config.plant, *forces)
        if config.offset_free == 1.0:  # the load at the target: the trolley upwind of it
            error[0] -= dx
        error[2] -= theta1
        error[4] -= theta2
    u = dd_ref - linalg.dot(config.gains[k], error)
    return limits.limited(u, measured[1], config.u_max, config.v_max, config.h)


def _output(config, state, inputs):
    return tuple(control(config, k, [inputs[i] for i in _MEASURED[k]], [inputs[i] for i in _REFERENCES[k]],
                         inputs[_DD_REF[k]], [inputs[i] for i in _FORCES[k]]) for k in range(len(AXES)))


def report(config):
    """The designed gains per axis, for ``crane-fmu info``."""
    return {f"K{axis}_{name}": k for axis, gains in zip(AXES, config.gains)
            for name, k in zip(axis_states(axis), gains)}


def _references(axis):
    return tuple(input_(f"{name}_ref", _SWING_ROWS[name][0], f"reference {name}; unconnected: 0, regulation to "
                        f"{axis}_d") for name in axis_states(axis)) + (
        input_(f"dd{axis}_ref", "m/s2", f"reference trolley acceleration along {axis} (feedforward); "
               "unconnected: 0, none"),)


VARIABLES = controller_model() + tuple(
    parameter(name, value, "1", f"LQR state weight on {name[2:]} of each axis (Q diagonal, SI units)")
    for name, value in DEFAULT_WEIGHTS.items()) + (
    parameter("r", 0.05, "1", "LQR input weight on each axis' demand"),
    parameter("h", 1e-3, "s", "communication step the discrete design is for"),
    parameter("x_d", 0.0, "m", "target trolley position along x (added to x_ref)"),
    parameter("y_d", 0.0, "m", "target trolley position along y (added to y_ref)"),
    parameter("offset_free", 0.0, "1", "each axis' estimated forces (F2x_hat, F1x_hat; F2y_hat, F1y_hat): 0 ignored; "
                                       "1 the load, 2 the trolley held at the axis' target, the cables at the forces' "
                                       "rest (offset-free)"),
    *limits.parameters(),
) + tuple(input_(name, _SWING_ROWS[name][0], "measured " + _SWING_ROWS[name][1]) for name in SWING_STATE) + (
    *_references("x"), *_references("y"),
    *(input_(name, "N", f"estimated horizontal force on the {'payload' if name[1] == '2' else 'hook'} along "
             f"{axis} (a StateEstimator's on that axis); unconnected: 0, none")
      for axis in AXES for name in axis_forces(axis)),
    output("ux", "m/s2", "demanded trolley acceleration along x, ddx_ref - Kx (s_x - s_x,ref), limited"),
    output("uy", "m/s2", "demanded trolley acceleration along y, ddy_ref - Ky (s_y - s_y,ref), limited"),
)
IN = positions(VARIABLES, "input")
_MEASURED = tuple(tuple(getattr(IN, name) for name in axis_states(axis)) for axis in AXES)
_REFERENCES = tuple(tuple(getattr(IN, name + "_ref") for name in axis_states(axis)) for axis in AXES)
_DD_REF = tuple(getattr(IN, f"dd{axis}_ref") for axis in AXES)
_FORCES = tuple(tuple(getattr(IN, name) for name in axis_forces(axis)) for axis in AXES)
RULES = (*PLANT_RULES, *non_negative(*WEIGHTS), *positive("r", "h"), *finite("x_d", "y_d"), *limits.RULES,
         one_of("offset_free", tuple(OFFSET_FREE), "0 (the forces ignored), 1 (the load at the target) or 2 (the "
                                                   "trolley at the target)"),
         rule("m2 > 0", "m2 must be > 0 when offset_free != 0 (a force on a payload of no mass), got {m2}",
              when="offset_free != 0"))  # checked in this order (rules.py)

COMPONENT = Component(
    "LqrController3D", "controller",
    "Discrete-time LQR of the crane in three dimensions, one planar design per horizontal axis from the plant's "
    "linearisation at rest; tracks each axis' references; outputs: trolley accelerations ux, uy, direct "
    "feedthrough",
    VARIABLES, configure, _output, feedthrough=True, report=report,
    depends_on={"ux": tuple(v.name for v in VARIABLES if v.causality == "input" and v.name in
                            {*axis_states("x"), *(n + "_ref" for n in axis_states("x")), "ddx_ref",
                                *axis_forces("x")}),
                "uy": tuple(v.name for v in VARIABLES if v.causality == "input" and v.name in
                            {*axis_states("y"), *(n + "_ref" for n in axis_states("y")), "ddy_ref",
                                *axis_forces("y")})},
    crane_model=CRANE_MODEL, native="lqr3d.c", rules=RULES)
