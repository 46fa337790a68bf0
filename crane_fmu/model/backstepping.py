"""Backstepping anti-swing law of the paper, eqs (10)-(21): the BacksteppingController component."""

import math

from . import limits
from .component import Component
from .parameters import GAIN_RULES, PLANT_FIELDS, PLANT_RULES, ControllerGains, plant_parameters
from .rules import check, positive
from .tables import CRANE_MODEL, MEASURED_STATE, controller_model, output, parameter, positions


def drift_and_input_gain(theta1, dtheta1, theta2, dtheta2, p, b3_form="derived"):
    """The vectors f(x) and b(x) of eq (11), X3 = f(x) + b(x) u.

    Parameters
    ----------
    theta1, dtheta1, theta2, dtheta2 : float
        Swing angles [rad] and rates [rad/s].
    p : PlantParameters
        The controller's model of the plant.
    b3_form : {"derived", "printed"}
        ``"printed"`` uses b3 exactly as eq (14) prints it; ``"derived"`` uses
        the sign obtained by solving eqs (8)-(9), which is the negative of it.

    Returns
    -------
    (tuple, tuple)
        ``(f1, f2, f3)`` and ``(b1, b2, b3)``.

    Notes
    -----
    Eqs (12) and (14) with ``D = 2 m1 + m2 - m2 cos(2 (theta1 - theta2))``.
    """
    m1, m2, l1, l2, g = p.m1, p.m2, p.l1, p.l2, p.g
    d = theta1 - theta2
    sd, cd = math.sin(d), math.cos(d)
    den = 2.0 * m1 + m2 - m2 * math.cos(2.0 * d)
    w1s, w2s = dtheta1 * dtheta1, dtheta2 * dtheta2
    f2 = (-g * (2.0 * m1 + m2) * math.sin(theta1) - g * m2 * math.sin(theta1 - 2.0 * theta2)
          - 2.0 * m2 * (l1 * w1s * cd + l2 * w2s) * sd) / (l1 * den)
    b2 = (-(2.0 * m1 + m2) * math.cos(theta1) + m2 * math.cos(theta1 - 2.0 * theta2)) / (l1 * den)
    f3 = 2.0 * (l1 * w1s * (m1 + m2) + l2 * m2 * w2s * cd + (m1 + m2) * g * math.cos(theta1)) * sd / (
        l2 * den)
    b3 = 2.0 * (m1 + m2) * sd * math.sin(theta1) / (l2 * den)
    if b3_form == "derived":
        b3 = -b3
    return (0.0, f2, f3), (1.0, b2, b3)


def control(state, p, k):
    """Trolley acceleration demanded by the backstepping law.

    Parameters
    ----------
    state : sequence of float
        Measured ``(x, dx, theta1, dtheta1, theta2, dtheta2)``.
    p : PlantParameters
        The controller's model of the plant.
    k : ControllerGains
        Gains K1, K2, targets, row weights and the b3 form.

    Returns
    -------
    float
        ``u`` [m/s2].

    Notes
    -----
    Errors, eq (16): ``e1 = X1 - Xd``, ``e2 = X2``. Backstepping errors, eqs
    (18)-(19): ``delta1 = e1``, ``delta2 = e2 + K1 e1``, so that ``delta1' = e2``
    and the desired ``e3d = -K1 e2 - K2 delta2``. Eq (20), ``f + b u = e3d``, is
    three equations in one unknown; eq (21) solves it by least squares. With row
    weights W this is ``u = (b' W b)^-1 b' W (e3d - f)``, which is eq (21) for W = I.
    """
    x, dx, theta1, dtheta1, theta2, dtheta2 = state
    (_, f2, f3), (_, b2, b3) = drift_and_input_gain(theta1, dtheta1, theta2, dtheta2, p, k.b3_form)
    # e3d_i = -K1_i e2_i - K2_i (e2_i + K1_i e1_i), one row each of x, theta1, theta2
    e3x = -k.K1_x * dx - k.K2_x * (dx + k.K1_x * (x - k.x_d))
    e31 = -k.K1_theta1 * dtheta1 - k.K2_theta1 * (dtheta1 + k.K1_theta1 * (theta1 - k.theta1_d))
    e32 = -k.K1_theta2 * dtheta2 - k.K2_theta2 * (dtheta2 + k.K1_theta2 * (theta2 - k.theta2_d))
    # f1 = 0, b1 = 1 (eq 12)
    num = k.w_x * e3x + k.w_theta1 * b2 * (e31 - f2) + k.w_theta2 * b3 * (e32 - f3)
    return num / (k.w_x + k.w_theta1 * b2 * b2 + k.w_theta2 * b3 * b3)


def law(p, k):
    """:func:`control` for fixed ``p`` and ``k``: the constants derived from them computed once.

    Returns a function of the measured state giving the same numbers as
    ``control(state, p, k)`` (the same arithmetic in the same order, eqs (12),
    (14), (16)-(21)), about twice as fast: the FMU's hot path.
    """
    m1, m2, l1, l2, g = p.m1, p.m2, p.l1, p.l2, p.g
    a = 2.0 * m1 + m2
    ga, gm2, two_m2 = -g * a, g * m2, 2.0 * m2  # eq (12), f2
    m12 = m1 + m2
    l2m2, m12g, two_m12 = l2 * m2, m12 * g, 2.0 * m12  # eq (14), f3 and b3
    derived = k.b3_form == "derived"
    k1x, k2x, k11, k21, k12, k22 = k.K1_x, k.K2_x, k.K1_theta1, k.K2_theta1, k.K1_theta2, k.K2_theta2
    nk1x, nk11, nk12 = -k1x, -k11, -k12
    x_d, theta1_d, theta2_d, w_x, w_1, w_2 = k.x_d, k.theta1_d, k.theta2_d, k.w_x, k.w_theta1, k.w_theta2
    sin, cos = math.sin, math.cos

    def u(state):
        x, dx, theta1, dtheta1, theta2, dtheta2 = state
        d = theta1 - theta2
        sd, cd = sin(d), cos(d)
        den = a - m2 * cos(2.0 * d)
        w1s, w2s = dtheta1 * dtheta1, dtheta2 * dtheta2
        f2 = (ga * sin(theta1) - gm2 * sin(theta1 - 2.0 * theta2) - two_m2 * (l1 * w1s * cd + l2 * w2s) * sd) / (
            l1 * den)
        b2 = (-a * cos(theta1) + m2 * cos(theta1 - 2.0 * theta2)) / (l1 * den)
        f3 = 2.0 * (l1 * w1s * m12 + l2m2 * w2s * cd + m12g * cos(theta1)) * sd / (l2 * den)
        b3 = two_m12 * sd * sin(theta1) / (l2 * den)
        if derived:
            b3 = -b3
        e3x = nk1x * dx - k2x * (dx + k1x * (x - x_d))
        e31 = nk11 * dtheta1 - k21 * (dtheta1 + k11 * (theta1 - theta1_d))
        e32 = nk12 * dtheta2 - k22 * (dtheta2 + k12 * (theta2 - theta2_d))
        num = w_x * e3x + w_1 * b2 * (e31 - f2) + w_2 * b3 * (e32 - f3)
        return num / (w_x + w_1 * b2 * b2 + w_2 * b3 * b3)

    return u


# --- the BacksteppingController component -------------------------------------------

_K = ControllerGains()  # defaults live in the dataclass
_COORDINATES = (("x", "trolley position", "trolley", "m"), ("theta1", "hook angle", "hook", "rad"),
                ("theta2", "payload angle", "payload", "rad"))  # name, its error, its row, unit

VARIABLES = controller_model() + (
    *(parameter(f"K1_{q}", getattr(_K, f"K1_{q}"), "1/s", f"K1 gain on {error} error, eq (18)")
      for q, error, _, _ in _COORDINATES),
    *(parameter(f"K2_{q}", getattr(_K, f"K2_{q}"), "1/s", f"K2 gain on {part} delta2, eq (19)")
      for q, _, part, _ in _COORDINATES),
    *(parameter(f"{q}_d", getattr(_K, f"{q}_d"), unit, f"target {error}") for q, error, _, unit in _COORDINATES),
    *(parameter(f"w_{q}", getattr(_K, f"w_{q}"), "1", f"least-squares weight of the {part} row of eq (20)")
      for q, _, part, _ in _COORDINATES),
    parameter("b3_form", _K.b3_form, None,
              "b3 of eq (14): 'derived' (corrected sign) or 'printed' (as in the paper)", "String"),
    *limits.parameters(u_max=limits.NO_LIMIT, v_max=limits.NO_LIMIT),  # the paper's law has none
    parameter("h", 1e-3, "s", "communication step (for the speed guard when v_max is finite)"),
) + MEASURED_STATE + (
    output("u", "m/s2", "demanded trolley acceleration, eq (21)"),
)
IN = positions(VARIABLES, "input")
RULES = (*positive("h"), *limits.RULES, *PLANT_RULES, *GAIN_RULES)  # checked in this order (rules.py)


def configure(values):
    """Validated ``(PlantParameters, ControllerGains, (u_max, v_max, h), law)`` from the parameter values."""
    check(RULES, values)
    bounds = (*limits.of(values), values["h"])
    gains = {name: value for name, value in values.items() if name not in PLANT_FIELDS + ("u_max", "v_max", "h")}
    p, k = plant_parameters(values), ControllerGains(**gains)
    return p, k, bounds, law(p, k)


def _output(config, state, inputs):
    _, _, (u_max, v_max, h), u = config
    if u_max == v_max == math.inf:  # limited() would return u itself
        return (u(inputs),)
    return (limits.limited(u(inputs), inputs[IN.dx], u_max, v_max, h),)


COMPONENT = Component(
    "BacksteppingController", "controller",
    "Backstepping anti-swing controller for a double-pendulum crane payload "
    "(least-squares eq 21); output: trolley acceleration u, direct feedthrough",
    VARIABLES, configure, _output, feedthrough=True, crane_model=CRANE_MODEL, native="backstepping.c", rules=RULES)
