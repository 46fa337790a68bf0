"""The LqrController3D component: the discrete LQR of the crane in three dimensions, one design per axis.

Linearised at rest, the spatial double pendulum of :mod:`.plant3d` is two uncoupled planar cranes, one per
horizontal axis (:func:`.plant3d.linearised`). The controller reads each axis' block of that linearisation by
the plant's roles (its axes and states) and designs the planar LQR for it (:func:`.lqr.design_of`); each axis's
demand is then the planar law of :func:`.lqr.control` on that axis' states: ``u_a = dd_ref - K_a (s_a - s_a,ref)``
within ``|u| <= u_max`` and ``|v| <= v_max``. The nonlinear coupling between the axes is left to feedback.
"""

from collections import namedtuple

from . import limits, linalg
from .component import Component
from .lqr import DEFAULT_WEIGHTS, WEIGHTS, design_of
from .parameters import PLANT_RULES
from .plant3d import _SWING_ROWS, CRANE, SWING_STATE
from .rules import check, finite, non_negative, positive
from .tables import CRANE_MODEL, controller_model, input_, output, parameter, positions

AXES = tuple(a.position for a in CRANE.axes)  # ("x", "y")


def axis_states(axis):
    """The states of one axis, in the planar order: ``(x, dx, theta1x, dtheta1x, theta2x, dtheta2x)``."""
    return (axis, "d" + axis, "theta1" + axis, "dtheta1" + axis, "theta2" + axis, "dtheta2" + axis)


def axis_model(values, axis):
    """``(A, B)`` of one axis: its block of the plant's linearisation at rest (the crane's ``linearised`` role)."""
    a, b = CRANE.linearised({name: values[name] for name in CRANE_MODEL})
    rows = [CRANE.state.index(name) for name in axis_states(axis)]
    column = AXES.index(axis)
    return [[a[i][j] for j in rows] for i in rows], [[b[i][column]] for i in rows]


Config = namedtuple("Config", "gains targets u_max v_max h")
Config.__doc__ = "Each axis's gains (6) and target, in :data:`AXES` order; the limits and the step."


def configure(values):
    """Validated parameters and each axis's design."""
    check(RULES, values)
    weights = [values[name] for name in WEIGHTS]
    gains = tuple(design_of(*axis_model(values, axis), weights, values["r"], values["h"]) for axis in AXES)
    u_max, v_max = limits.of(values)
    return Config(gains=gains, targets=tuple(values[axis + "_d"] for axis in AXES), u_max=u_max, v_max=v_max,
                  h=values["h"])


def control(config, k, measured, reference, dd_ref):
    """Axis ``k``'s demand: :func:`.lqr.control` on its states, ``u = dd_ref - K (s - s_ref)`` within the limits,
    with ``s_ref = reference + (target, 0, ...)``."""
    error = [s - r for s, r in zip(measured, reference)]
    error[0] -= config.targets[k]
    u = dd_ref - linalg.dot(config.gains[k], error)
    return limits.limited(u, measured[1], config.u_max, config.v_max, config.h)


def _output(config, state, inputs):
    return tuple(control(config, k, [inputs[i] for i in _MEASURED[k]], [inputs[i] for i in _REFERENCES[k]],
                         inputs[_DD_REF[k]]) for k in range(len(AXES)))


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
    *limits.parameters(),
) + tuple(input_(name, _SWING_ROWS[name][0], "measured " + _SWING_ROWS[name][1]) for name in SWING_STATE) + (
    *_references("x"), *_references("y"),
    output("ux", "m/s2", "demanded trolley acceleration along x, ddx_ref - Kx (s_x - s_x,ref), limited"),
    output("uy", "m/s2", "demanded trolley acceleration along y, ddy_ref - Ky (s_y - s_y,ref), limited"),
)
IN = positions(VARIABLES, "input")
_MEASURED = tuple(tuple(getattr(IN, name) for name in axis_states(axis)) for axis in AXES)
_REFERENCES = tuple(tuple(getattr(IN, name + "_ref") for name in axis_states(axis)) for axis in AXES)
_DD_REF = tuple(getattr(IN, f"dd{axis}_ref") for axis in AXES)
RULES = (*PLANT_RULES, *non_negative(*WEIGHTS), *positive("r", "h"), *finite("x_d", "y_d"), *limits.RULES)

COMPONENT = Component(
    "LqrController3D", "controller",
    "Discrete-time LQR of the crane in three dimensions, one planar design per horizontal axis from the plant's "
    "linearisation at rest; tracks each axis' references; outputs: trolley accelerations ux, uy, direct "
    "feedthrough",
    VARIABLES, configure, _output, feedthrough=True, report=report,
    depends_on={"ux": tuple(v.name for v in VARIABLES if v.causality == "input" and v.name in
                            {*axis_states("x"), *(n + "_ref" for n in axis_states("x")), "ddx_ref"}),
                "uy": tuple(v.name for v in VARIABLES if v.causality == "input" and v.name in
                            {*axis_states("y"), *(n + "_ref" for n in axis_states("y")), "ddy_ref"})},
    crane_model=CRANE_MODEL, native="lqr3d.c", rules=RULES)
