"""Discrete-time LQR of the crane linearised about the hanging equilibrium: the LqrController component.

The gains are designed when initialisation ends, from the controller's own
parameters (its model of the plant, the weights and the communication step),
so they always follow what the user set. The same law tracks a reference
(``x_ref``, ``dx_ref``, ``ddx_ref`` and the swing it induces, from a
``TrajectoryPlanner``): feedforward plus feedback on the error.
"""

import dataclasses
from collections import namedtuple

from . import limits, linalg
from .component import Component
from .parameters import PLANT_RULES, plant_parameters
from .plant import linearisation
from .rules import check, finite, non_negative, one_of, positive, rule
from .tables import CRANE_MODEL, MEASURED_STATE, STATE, controller_model, input_, output, parameter, positions

WEIGHTS = tuple("q_" + name for name in STATE)
REFERENCE = ("x_ref", "dx_ref", "theta1_ref", "dtheta1_ref", "theta2_ref", "dtheta2_ref")


def continuous_model(p):
    """``(A, B)`` of ``s' = A s + B u`` for ``s = (x, dx, theta1, dtheta1, theta2, dtheta2)`` about rest.

    Notes
    -----
    ``x'' = u`` (eq 12) and the linearised eqs (8)-(9) of
    :func:`crane_fmu.model.plant.linearisation`.
    """
    big_w, small_w = linearisation(p)
    a = linalg.zeros(6, 6)
    a[0][1] = a[2][3] = a[4][5] = 1.0
    for row, i in ((3, 0), (5, 1)):
        a[row][2], a[row][4] = -big_w[i][0], -big_w[i][1]
    b = [[0.0], [1.0], [0.0], [-small_w[0]], [0.0], [-small_w[1]]]
    return a, b


def design(p, weights, r, h):
    """The state-feedback gains ``K`` (6) of the discrete LQR of :func:`continuous_model` for the step ``h``."""
    return design_of(*continuous_model(p), weights, r, h)


def design_of(a, b, weights, r, h):
    """The gains ``K`` of the discrete LQR of one axis ``s' = A s + B u`` (one input) for the step ``h``.

    Minimises ``sum_k s_k' Q s_k + r u_k^2`` for the zero-order-hold
    discretisation, ``Q = diag(weights)``:
    ``K = (r + Bd' P Bd)^-1 Bd' P Ad`` with ``P`` from the discrete algebraic Riccati equation.
    """
    ad, bd = linalg.zoh(a, b, h)
    n = len(weights)
    q = [[weights[i] if i == j else 0.0 for j in range(n)] for i in range(n)]
    big_p = linalg.dare(ad, bd, q, [[r]])
    pb = linalg.matmul(big_p, bd)
    bt_p_b = linalg.dot([row[0] for row in bd], [row[0] for row in pb])
    bt_p_a = linalg.matmul(linalg.transpose(pb), ad)[0]
    return tuple(v / (r + bt_p_b) for v in bt_p_a)


SCHEDULE_POINTS = 21

Config = namedtuple("Config", "gains x_d u_max v_max h schedule offset_free plant", defaults=(0.0, None))
Config.__doc__ = ("The gains for l1, the limits, the gain schedule: ``(l1 values, gains)`` of designs over "
                  "[l1_low, l1_high], or None; the offset-free target's choice and the crane model it is computed "
                  "on (:func:`force_target`).")

OFFSET_FREE = {0.0: "the forces ignored", 1.0: "the load at x_d", 2.0: "the trolley at x_d"}


def force_target(p, f2, f1=0.0):
    """``(dx, theta1, theta2)``: the rest that constant horizontal forces ``f2`` on the payload and ``f1`` on the hook
    hold, the target the offset-free LQR regulates to (``dx``: the trolley's shift for the load held at the target).

    At rest (``u = 0``, no rates) eqs (8)-(9) linearised are ``(m1 + m2) g theta1 = F1 + F2`` and
    ``g theta2 = F2 / m2`` (:func:`crane_fmu.model.estimator.force_columns`' statics; the wind's static deflection
    of ``analysis/wind_equilibrium.py`` with ``tan q = q``): the cables lean downwind by these angles, which no
    trolley motion takes away, and the load sits ``l1 theta1 + l2 theta2`` downwind of the trolley; the trolley's
    target moves upwind by as much.
    """
    theta1, theta2 = (f1 + f2) / ((p.m1 + p.m2) * p.g), f2 / (p.m2 * p.g)
    return -(p.l1 * theta1 + p.l2 * theta2), theta1, theta2


# A gain schedule over [l1_low, l1_high], or none (both 0): the LQR's and the MPC's.
SCHEDULED = "l1_low != 0 or l1_high != 0"
SCHEDULE_RULES = (*positive("l1_low", when=SCHEDULED),
                  rule("l1_high > l1_low and finite(l1_high)", "l1_high must be finite and > l1_low = {l1_low}, got "
                       "{l1_high}", when=SCHEDULED))


def configure(values):
    """Validated parameters and the gains designed from them (and the schedule over the cable length)."""
    check(RULES, values)
    p = plant_parameters(values)
    u_max, v_max = limits.of(values)
    weights = [values[name] for name in WEIGHTS]
    schedule = None
    low, high = values["l1_low"], values["l1_high"]
    if (low, high) != (0.0, 0.0):
        lengths = [low + (high - low) * i / (SCHEDULE_POINTS - 1) for i in range(SCHEDULE_POINTS)]
        schedule = (lengths, [design(dataclasses.replace(p, l1=length), weights, values["r"], values["h"])
                              for length in lengths])
    gains = design(p, weights, values["r"], values["h"])
    return Config(gains=gains, x_d=values["x_d"], u_max=u_max, v_max=v_max, h=values["h"], schedule=schedule,
                  offset_free=values["offset_free"], plant=p)


def scheduled_gains(config, l1):
    """The gains for the measured cable length ``l1``: linear between the schedule's designs (clamped to its range)."""
    if config.schedule is None or not l1 > 0:
        return config.gains
    lengths, table = config.schedule
    position = (min(max(l1, lengths[0]), lengths[-1]) - lengths[0]) / (lengths[1] - lengths[0])
    i = min(int(position), len(lengths) - 2)
    f = position - i
    return tuple(a + f * (b - a) for a, b in zip(table[i], table[i + 1]))


def control(config, measured, reference=(0.0,) * 6, ddx_ref=0.0, l1=0.0, forces=(0.0, 0.0)):
    """``u = ddx_ref - K (s - s_ref)`` within the limits, with ``s_ref = reference + (x_d, 0, ...)``.

    ``l1`` is the measured main cable length; with a schedule, ``K`` follows it. ``forces`` are the estimated
    horizontal forces on the payload and the hook (``F2_hat``, ``F1_hat``); with ``offset_free`` on, ``s_ref``
    moves to the rest they hold (:func:`force_target`): the steady error of the load (``offset_free = 1``) or the
    trolley (2) under constant forces goes to zero, where the plain law leaves the trolley where ``K`` balances the
    leaning cables. Forces 0 or ``offset_free = 0``: the plain law.
    """
    error = [s - r for s, r in zip(measured, reference)]
    error[0] -= config.x_d
    if config.offset_free != 0.0 and (forces[0] != 0.0 or forces[1] != 0.0):
        dx, theta1, theta2 = force_target(config.plant, *forces)
        if config.offset_free == 1.0:  # the load at x_d: the trolley upwind of it
            error[0] -= dx
        error[2] -= theta1
        error[4] -= theta2
    u = ddx_ref - linalg.dot(scheduled_gains(config, l1), error)
    return limits.limited(u, measured[1], config.u_max, config.v_max, config.h)


def _output(config, state, inputs):
    return (control(config, inputs[IN.x:IN.dtheta2 + 1], inputs[IN.x_ref:IN.dtheta2_ref + 1], inputs[IN.ddx_ref],
                    inputs[IN.l1_now], (inputs[IN.F2_hat], inputs[IN.F1_hat])),)


def report(config):
    """The designed gains (and the schedule's range), for ``crane-fmu info``."""
    derived = {"K_" + name: k for name, k in zip(STATE, config.gains)}
    if config.schedule:
        lengths, table = config.schedule
        derived["schedule"] = (f"{len(lengths)} designs for l1 from {lengths[0]:g} to {lengths[-1]:g} m; K_theta1 "
                               f"from {table[0][2]:.6g} to {table[-1][2]:.6g}")
    return derived


DEFAULT_WEIGHTS = dict(zip(WEIGHTS, (50.0, 0.0, 400.0, 10.0, 50.0, 5.0)))
# the planner's references, tracked by this controller and the HardHitController
# (unconnected, as in regulation: 0, the target x_d alone; cosim.connections.UNCONNECTED)
REFERENCE_INPUTS = tuple(input_(name, unit, f"reference {text}; unconnected: 0, regulation to x_d") for name, unit, text
                         in zip(REFERENCE, ("m", "m/s", "rad", "rad/s", "rad", "rad/s"),
                                ("trolley position (plus x_d)", "trolley velocity", "hook swing angle",
                                 "hook swing rate", "payload swing angle", "payload swing rate"))) + (
    input_("ddx_ref", "m/s2", "reference trolley acceleration (feedforward); unconnected: 0, none"),)

VARIABLES = controller_model() + tuple(
    parameter(name, value, "1", f"LQR state weight on {name[2:]} (Q diagonal, SI units)")
    for name, value in DEFAULT_WEIGHTS.items()) + (
    parameter("r", 0.05, "1", "LQR input weight on u"),
    parameter("h", 1e-3, "s", "communication step the discrete design is for"),
    parameter("x_d", 0.0, "m", "target trolley position (added to x_ref)"),
    parameter("l1_low", 0.0, "m", "gain schedule: shortest main cable designed for; 0 with l1_high = 0: none"),
    parameter("l1_high", 0.0, "m", "gain schedule: longest main cable designed for"),
    parameter("offset_free", 0.0, "1", "the estimated forces F2_hat, F1_hat: 0 ignored; 1 the load, 2 the trolley "
                                       "held at x_d, the cables at the forces' rest (offset-free)"),
    *limits.parameters(),
) + MEASURED_STATE + REFERENCE_INPUTS + (
    input_("l1_now", "m", "measured main cable length, for the gain schedule; 0: not measured"),
    input_("F2_hat", "N", "estimated horizontal force on the payload (a StateEstimator's); unconnected: 0, none"),
    input_("F1_hat", "N", "estimated horizontal force on the hook (a StateEstimator's); unconnected: 0, none"),
    output("u", "m/s2", "demanded trolley acceleration, ddx_ref - K (s - s_ref), limited"),
)
IN = positions(VARIABLES, "input")
RULES = (*PLANT_RULES, *non_negative(*WEIGHTS), *positive("r", "h"), *finite("x_d"), *limits.RULES,
         *SCHEDULE_RULES, one_of("offset_free", tuple(OFFSET_FREE), "0 (the forces ignored), 1 (the load at x_d) or 2 "
                                                                     "(the trolley at x_d)"),
         rule("m2 > 0", "m2 must be > 0 when offset_free != 0 (a force on a payload of no mass), got {m2}",
              when="offset_free != 0"))  # checked in this order (rules.py)


COMPONENT = Component(
    "LqrController", "controller",
    "Discrete-time LQR of the double-pendulum crane about the hanging equilibrium, designed from its parameters "
    "at initialisation; tracks x_ref, dx_ref, ddx_ref; output: trolley acceleration u, direct feedthrough",
    VARIABLES, configure, _output, feedthrough=True, report=report,
    crane_model=CRANE_MODEL, native="lqr.c", rules=RULES)
