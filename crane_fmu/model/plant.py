"""Double-pendulum payload under an accelerated trolley, eqs (4)-(9).

The state is ``(x, dx, theta1, dtheta1, theta2, dtheta2)`` in SI units; the
input is the trolley acceleration ``u = x''`` [m/s2]. Angles are measured from
the downward vertical, positive in +x direction (Fig. 3).
"""

import math
from collections import namedtuple

from .component import Component, Discard
from .parameters import plant_parameters, positive
from .tables import PLANT_MODEL, input_, output, parameter


def angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p):
    """Solve the Lagrange equations (8) and (9) for the angular accelerations.

    Parameters
    ----------
    theta1, dtheta1, theta2, dtheta2 : float
        Swing angles [rad] and rates [rad/s].
    u : float
        Trolley acceleration [m/s2].
    p : PlantParameters
        Masses, cable lengths and gravity.

    Returns
    -------
    (float, float)
        ``(ddtheta1, ddtheta2)`` [rad/s2].

    Notes
    -----
    Eq (8) divided by l1 and eq (9) divided by ``l2 m2`` form the linear system::

        (m1+m2) l1 dd1 + m2 l2 cos(d) dd2 = -(m1+m2)(u cos th1 + g sin th1) - m2 l2 w2^2 sin d
        l1 cos(d) dd1  +    l2        dd2 = -u cos th2 - g sin th2 + l1 w1^2 sin d

    with ``d = theta1 - theta2``. Its determinant ``l1 l2 (m1 + m2 sin^2 d)`` is
    positive for m1 > 0, and dividing (9) by m2 keeps the case m2 = 0 regular.
    """
    m1m2 = p.m1 + p.m2
    l1, l2, g = p.l1, p.l2, p.g
    s1, c1 = math.sin(theta1), math.cos(theta1)
    s2, c2 = math.sin(theta2), math.cos(theta2)
    d = theta1 - theta2
    sd, cd = math.sin(d), math.cos(d)
    r1 = -m1m2 * (u * c1 + g * s1) - p.m2 * l2 * dtheta2 * dtheta2 * sd
    r2 = -u * c2 - g * s2 + l1 * dtheta1 * dtheta1 * sd
    a, b = m1m2 * l1, p.m2 * l2 * cd
    c, e = l1 * cd, l2
    det = a * e - b * c
    return (e * r1 - b * r2) / det, (a * r2 - c * r1) / det


def derivative(state, u, p):
    """Time derivative of the plant state for a held trolley acceleration ``u``.

    Notes
    -----
    ``x'' = u`` by definition of the input (eq 12: f1 = 0, b1 = 1); the angular
    accelerations come from eqs (8)-(9), see :func:`angular_accelerations`.
    """
    _, dx, theta1, dtheta1, theta2, dtheta2 = state
    dd1, dd2 = angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p)
    return (dx, u, dtheta1, dd1, dtheta2, dd2)


def rk4_step(state, u, dt, p):
    """Advance ``state`` by ``dt`` with one classical Runge-Kutta 4 step, u held."""
    x, v, a1, w1, a2, w2 = state
    h2 = 0.5 * dt
    k1 = angular_accelerations(a1, w1, a2, w2, u, p)
    k2 = angular_accelerations(a1 + h2 * w1, w1 + h2 * k1[0], a2 + h2 * w2, w2 + h2 * k1[1], u, p)
    w1b, w2b = w1 + h2 * k1[0], w2 + h2 * k1[1]
    w1c, w2c = w1 + h2 * k2[0], w2 + h2 * k2[1]
    k3 = angular_accelerations(a1 + h2 * w1b, w1c, a2 + h2 * w2b, w2c, u, p)
    w1d, w2d = w1 + dt * k3[0], w2 + dt * k3[1]
    k4 = angular_accelerations(a1 + dt * w1c, w1d, a2 + dt * w2c, w2d, u, p)
    s = dt / 6.0
    # x'' = u is constant over the step, so RK4 integrates x exactly.
    return (
        x + dt * v + h2 * dt * u,
        v + dt * u,
        a1 + s * (w1 + 2.0 * w1b + 2.0 * w1c + w1d),
        w1 + s * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        a2 + s * (w2 + 2.0 * w2b + 2.0 * w2c + w2d),
        w2 + s * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
    )


def linearisation(p):
    """The swing dynamics linearised about the hanging equilibrium: ``q'' = -W q - w u``, ``q = (theta1, theta2)``.

    Returns
    -------
    (W, w)
        ``W`` (2x2, lists of rows) [1/s2] and ``w`` (2) [rad/m].

    Notes
    -----
    Eqs (8)-(9) divided as in :func:`angular_accelerations`, with ``sin q = q``,
    ``cos q = 1`` and the quadratic rate terms dropped, give ``N q'' + K q = -n u`` with
    ``N = [[(m1+m2) l1, m2 l2], [l1, l2]]``, ``K = diag((m1+m2) g, g)``,
    ``n = (m1+m2, 1)``; ``det N = m1 l1 l2 > 0``.
    """
    m12 = p.m1 + p.m2
    a, b, c, d = m12 * p.l1, p.m2 * p.l2, p.l1, p.l2
    det = a * d - b * c
    inv = ((d / det, -b / det), (-c / det, a / det))  # N^-1
    big_w = [[inv[i][0] * m12 * p.g, inv[i][1] * p.g] for i in range(2)]
    small_w = [inv[i][0] * m12 + inv[i][1] for i in range(2)]
    return big_w, small_w


MAX_SUBSTEPS = 10_000_000  # per communication step: about a minute of computing


def substeps(step, max_substep):
    """Number of equal RK4 sub-steps no longer than ``max_substep`` covering ``step``.

    Raises
    ------
    ValueError
        If the step is not positive and finite, or needs more than
        :data:`MAX_SUBSTEPS` sub-steps (a host must never hang in doStep).
    """
    if not (step > 0 and math.isfinite(step)):
        raise ValueError(f"communication step must be > 0 and finite, got {step!r}")
    # The 1e-9 slack keeps h = 1 ms with max_substep = 1 ms at one sub-step
    # despite rounding in h.
    n = step / max_substep - 1e-9
    if not n <= MAX_SUBSTEPS:
        raise ValueError(f"communication step {step!r} s needs more than {MAX_SUBSTEPS} RK4 sub-steps of at most "
                         f"max_substep = {max_substep!r} s")
    return max(1, math.ceil(n))


def advance(state, u, step, max_substep, p):
    """Integrate the plant over one communication step with u held (zero-order hold)."""
    n = substeps(step, max_substep)
    dt = step / n
    for _ in range(n):
        state = rk4_step(state, u, dt, p)
    return state


def energy(state, p):
    """Kinetic plus potential energy of hook and payload [J], eqs (6)-(7)."""
    return outputs(state, p)[10]


OUTPUTS = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2", "x1", "y1", "x2", "y2", "energy")


def outputs(state, p):
    """The state, hook and payload positions and the energy, in the order of :data:`OUTPUTS`.

    Notes
    -----
    Positions from eqs (4)-(5); kinetic energy eq (6) plus potential energy
    eq (7). The trolley's own mass is not part of the model, so with ``u = 0``
    (constant trolley velocity) this energy is conserved.
    """
    x, dx, theta1, dtheta1, theta2, dtheta2 = state
    s1, c1, s2, c2 = math.sin(theta1), math.cos(theta1), math.sin(theta2), math.cos(theta2)
    x1, y1 = x + p.l1 * s1, -p.l1 * c1
    x2, y2 = x1 + p.l2 * s2, y1 - p.l2 * c2
    vx1, vy1 = dx + p.l1 * dtheta1 * c1, p.l1 * dtheta1 * s1
    vx2, vy2 = vx1 + p.l2 * dtheta2 * c2, vy1 + p.l2 * dtheta2 * s2
    kinetic = 0.5 * (p.m1 * (vx1 * vx1 + vy1 * vy1) + p.m2 * (vx2 * vx2 + vy2 * vy2))
    return (x, dx, theta1, dtheta1, theta2, dtheta2, x1, y1, x2, y2,
            kinetic + p.g * (p.m1 * y1 + p.m2 * y2))


# --- the CranePlant component -------------------------------------------------------

VARIABLES = PLANT_MODEL + (
    parameter("x0", 0.0, "m", "initial trolley position"),
    parameter("dx0", 0.0, "m/s", "initial trolley velocity"),
    parameter("theta1_0", math.pi / 18, "rad", "initial hook swing angle"),
    parameter("dtheta1_0", 0.0, "rad/s", "initial hook swing rate"),
    parameter("theta2_0", 0.0, "rad", "initial payload swing angle"),
    parameter("dtheta2_0", 0.0, "rad/s", "initial payload swing rate"),
    parameter("max_substep", 1e-3, "s", "longest RK4 sub-step inside doStep"),
    input_("u", "m/s2", "trolley acceleration (held over each step)"),
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
)

Config = namedtuple("Config", "params max_substep state0")


def setup(values):
    """Validated :class:`Config` from the CranePlant parameter values."""
    positive("max_substep", values["max_substep"])
    state0 = tuple(values[name] for name in ("x0", "dx0", "theta1_0", "dtheta1_0", "theta2_0", "dtheta2_0"))
    return Config(plant_parameters(values), values["max_substep"], state0)


def update(config, state, inputs, time, step):
    """The state after one communication step with ``u`` held; :class:`Discard` if it becomes non-finite."""
    (u,) = inputs
    n = substeps(step, config.max_substep)  # ValueError for an unusable step
    dt, p = step / n, config.params
    try:
        for _ in range(n):
            state = rk4_step(state, u, dt, p)
        finite = all(map(math.isfinite, state))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        finite = False
    if not finite:
        raise Discard(f"plant state became non-finite in the step from t={time!r} s (u={u!r} m/s2); "
                      "the step is discarded")
    return state


COMPONENT = Component(
    "CranePlant", "plant",
    "Overhead crane with a double-pendulum payload (hook m1 on cable l1, payload m2 on cable l2); "
    "input: trolley acceleration u; fixed-step RK4 inside doStep",
    VARIABLES, setup, lambda config, state, inputs: outputs(state, config.params),
    initial_state=lambda config: config.state0, update=update, default_experiment=(0.0, 20.0, 0.01))
