"""A discrete Kalman filter of the crane from what a crane measures: the StateEstimator component.

A crane measures the trolley position (motor encoder) and the rope angle at the
trolley (``x_meas``, ``theta1_meas``), at best also the payload angle (a camera:
``theta2_meas``, used when ``camera = 1``). The filter estimates the whole state
``s = (x, dx, theta1, dtheta1, theta2, dtheta2)`` that every controller takes, from
those signals and the applied trolley acceleration ``u``. Like the LQR, it is
designed when initialisation ends from its own parameters: its model of the crane
(eqs (8)-(9) linearised about the hanging equilibrium, held over the step ``h``),
the measurement noise and the process noise.

Model. ``s_{k+1} = Ad s_k + Bd (u_k + a_k) + Gd w_k``, ``y_k = C s_{k-d} + v_k``:
``a_k`` is an unknown trolley acceleration (``sigma_u``: what the drive does other
than ``u``), ``w_k`` unknown angular accelerations of both swing angles
(``sigma_swing``: what the model gets wrong, wrong cable lengths and masses, the
terms dropped by the linearisation), ``v_k`` the sensors' noise (``sigma_x``,
``sigma_theta``), ``d`` the sensors' delay in whole steps (``delay``).

Disturbance. With ``sigma_force > 0`` the state has a seventh entry: a slowly varying
horizontal force ``F2`` on the payload (a random walk; wind, a push), in the model as the
plant's ``F2`` enters eqs (8)-(9) linearised (:func:`force_columns`); with a camera an eighth,
``F1`` on the hook (one force per measured angle: at rest a force shows only in the angles it
leans; the wind pushes both). The estimates are the outputs ``F2_hat`` and ``F1_hat``, which an
LQR takes for an offset-free target (:func:`crane_fmu.model.lqr.control`). With
``sigma_force = 0`` (the default) the filter is the six-state one, bit for bit, and both are 0.

Where the model is wrong. The filter does nothing special: no cable length from
``l1_now``. A wrong model is covered by the process noise,
which enters where ``u`` and the swing accelerations enter, so the filter keeps
trusting the measured ``x`` and ``theta1`` over its own prediction (the spirit of
loop-transfer recovery: fictitious noise at the input brings an observer-based
loop's margins towards the state-feedback loop's). The estimate of ``theta2`` is
then as good as the model's coupling between the two angles; the scoreboard's
mismatch grid (l1 +-10 %, l2 +-20 %, m2 +-50 %) measures what that costs (README).
``l1_now`` is taken so that systems connect it by name; it is not used.

Steps. The output at ``t_k`` is the prediction ``s_{k|k-1}`` from the measurements
up to ``t_{k-1}`` (no direct feedthrough, so a feedthrough controller that feeds
``u`` back makes no algebraic loop); a step corrects with the measurement held over
it, then predicts with the ``u`` held over it. Measurements ``d`` steps late are
corrected on their own time and predicted forward with the last ``d`` applied
inputs. The first step takes the first measurement as the state, the rates (and
``theta2`` without a camera) zero; until then the outputs are zero.
"""

import math
from collections import namedtuple

from . import linalg
from .component import Component
from .disturbances import DELAY_STEPS
from .lqr import continuous_model
from .parameters import PLANT_RULES, plant_parameters
from .rules import check, non_negative, one_of, positive, rule
from .tables import CRANE_MODEL, STATE, controller_model, input_, output, parameter, positions, state_variables

NOISES = ("sigma_x", "sigma_theta", "sigma_u", "sigma_swing")

Config = namedtuple("Config", "ad bd gain rows delay")
Config.__doc__ = ("The filter: ``Ad``, ``Bd`` (a column as a list), the gain ``M`` (6, or with the forces 7 or 8 x "
                  "measurements), the measured state positions and the sensors' delay in steps.")


def force_states(camera):
    """How many forces the filter estimates (with ``sigma_force > 0``): one per measured swing angle, as a force
    at rest shows only in the angles it leans: ``F2`` on the payload, and with a camera ``F1`` on the hook too."""
    return 2 if camera else 1


def measured_rows(camera):
    """The state positions the sensors measure: x and theta1, and theta2 with a camera."""
    return (0, 2, 4) if camera else (0, 2)


def force_columns(p):
    """``((e1, e2) of the payload, (e1, e2) of the hook)``: the swing accelerations [rad/s2] per newton of a
    horizontal force on the payload and on the hook, linearised.

    Eqs (8)-(9) as in :func:`crane_fmu.model.plant.linearisation` with the forces ``F1`` on the hook and ``F2`` on
    the payload (:func:`crane_fmu.model.plant_equations.angular_accelerations`: ``+(F1 + F2)`` in eq (8), ``+F2 / m2``
    in eq (9)): ``N q'' + K q = -n u + (1, 1/m2) F2 + (1, 0) F1``, so ``e = N^-1 (1, 1/m2)`` and ``N^-1 (1, 0)``.
    """
    m12 = p.m1 + p.m2
    a, b, c, d = m12 * p.l1, p.m2 * p.l2, p.l1, p.l2
    det = a * d - b * c
    inv = ((d / det, -b / det), (-c / det, a / det))  # N^-1
    return [inv[i][0] + inv[i][1] / p.m2 for i in range(2)], [inv[i][0] for i in range(2)]


def noise_model(p, h, sigma_u, sigma_swing, sigma_force=0.0, forces=1):
    """``(Ad, Bd, Qd)``: the crane held over ``h`` and the process noise covariance.

    ``Qd = Gd diag(sigma_u^2, sigma_swing^2, sigma_swing^2) Gd'``, ``Gd`` the zero-order-hold
    input matrix of the unknown accelerations (the trolley's enters as ``u`` does; each
    angle's on its rate). With ``sigma_force > 0`` the state has ``forces`` more entries: the
    horizontal force ``F2`` on the payload and (``forces = 2``) ``F1`` on the hook, each a random
    walk, ``F' = w`` (``sigma_force^2`` the variance of ``w``, held over each step), entering the
    swing rates by :func:`force_columns`.
    """
    a, b = continuous_model(p)
    g = [[b[i][0], 1.0 if i == 3 else 0.0, 1.0 if i == 5 else 0.0] for i in range(6)]
    variances = (sigma_u ** 2, sigma_swing ** 2, sigma_swing ** 2)
    if sigma_force > 0:
        columns = force_columns(p)[:forces]
        n = 6 + forces
        a = [row + [e[0] if i == 3 else e[1] if i == 5 else 0.0 for e in columns] for i, row in enumerate(a)]
        a += [[0.0] * n for _ in columns]
        g = [row + [0.0] * forces for row in g] + [[0.0] * (3 + k) + [1.0] + [0.0] * (forces - 1 - k)
                                                   for k in range(forces)]
        variances += (sigma_force ** 2,) * forces
    ad, gd = linalg.zoh(a, g, h)
    bd = [row[:1] for row in gd]
    m = len(variances)
    qd = [[linalg.dot([gi[k] * variances[k] for k in range(m)], gj) for gj in gd] for gi in gd]
    return ad, bd, qd


def design(p, h, sigma_x, sigma_theta, sigma_u, sigma_swing, camera=False, sigma_force=0.0):
    """``(P, M)``: the steady predicted covariance and the filter gain.

    ``P`` solves the filter Riccati equation ``P = Ad P Ad' - Ad P C' (C P C' + R)^-1 C P Ad' + Qd``
    (the dual of the LQR's: :func:`linalg.dare` of ``Ad'``, ``C'``); ``M = P C' (C P C' + R)^-1``
    corrects a prediction: ``s_{k|k} = s_{k|k-1} + M (y_k - C s_{k|k-1})``.
    """
    ad, _, qd = noise_model(p, h, sigma_u, sigma_swing, sigma_force, force_states(camera))
    rows = measured_rows(camera)
    c = [[1.0 if j == i else 0.0 for j in range(len(ad))] for i in rows]
    sigmas = (sigma_x, sigma_theta, sigma_theta)[:len(rows)]
    r = [[s ** 2 if i == j else 0.0 for j in range(len(rows))] for i, s in enumerate(sigmas)]
    big_p = linalg.dare(linalg.transpose(ad), linalg.transpose(c), qd, r)
    pct = [[row[j] for j in rows] for row in big_p]  # P C'
    innovation = [[big_p[i][j] + r[a][b] for b, j in enumerate(rows)] for a, i in enumerate(rows)]  # C P C' + R
    gain = linalg.transpose(linalg.solve(innovation, linalg.transpose(pct)))  # innovation symmetric
    return big_p, gain


FORCE = "sigma_force > 0"
RULES = (*PLANT_RULES, *positive("h", *NOISES), *non_negative("sigma_force"),
         rule("m2 > 0", "m2 must be > 0 when sigma_force > 0 (a force on a payload of no mass), got {m2}",
              when=FORCE), one_of("camera", (0.0, 1.0), "0 (x and theta1 measured) or 1 "
                                                                              "(theta2 too)"), DELAY_STEPS)


def configure(values):
    """Validated parameters and the filter designed from them."""
    check(RULES, values)
    p = plant_parameters(values)
    delay = values["delay"]
    camera = values["camera"] == 1.0
    sigma_force = values["sigma_force"]
    ad, bd, _ = noise_model(p, values["h"], values["sigma_u"], values["sigma_swing"], sigma_force,
                            force_states(camera))
    _, gain = design(p, values["h"], *(values[n] for n in NOISES), camera, sigma_force)
    return Config(ad=ad, bd=[row[0] for row in bd], gain=gain, rows=measured_rows(camera), delay=int(delay))


def _predict(c, s, u):
    return [linalg.dot(row, s) + b * u for row, b in zip(c.ad, c.bd)]


ESTIMATE = 3  # the state's last entry: the estimate the outputs show


def initial_state(config):
    """``(started, filtered-time prediction, the last delay inputs u, the output estimate)``."""
    zero = [0.0] * len(config.ad)
    return (0.0, zero, [0.0] * config.delay, zero)


def update(c, state, inputs, time, step):
    """Correct with the measurement held over the step, predict with ``u``; the estimate for the next step."""
    started, s, history, _ = state
    y = [inputs[IN.x_meas], inputs[IN.theta1_meas], inputs[IN.theta2_meas]]
    if not started:  # the first measurement is the state; the rates (and an unmeasured theta2, the forces) zero
        s = [y[0], 0.0, y[1], 0.0, y[2] if len(c.rows) == 3 else 0.0, 0.0] + [0.0] * (len(c.ad) - 6)
    else:
        innovation = [y[i] - s[row] for i, row in enumerate(c.rows)]
        s = [v + linalg.dot(m, innovation) for v, m in zip(s, c.gain)]
    applied = list(history) + [inputs[IN.u]]  # u_{k-d} .. u_k
    s = _predict(c, s, applied[0])
    estimate = s
    for u in applied[1:]:  # measurements d steps late: forward with the inputs applied since
        estimate = _predict(c, estimate, u)
    return (1.0, s, applied[1:], estimate)


VARIABLES = controller_model("estimator") + (
    parameter("h", 1e-3, "s", "communication step the discrete filter is for"),
    parameter("sigma_x", 1e-3, "m", "trolley position sensor noise (standard deviation)"),
    parameter("sigma_theta", math.radians(0.1), "rad", "swing angle sensor noise (standard deviation)"),
    parameter("sigma_u", 0.5, "m/s2", "process noise: unknown trolley acceleration, held over each step"),
    parameter("sigma_swing", 2.0, "rad/s2", "process noise: unknown angular acceleration of each swing angle"),
    parameter("camera", 0.0, "1", "1: theta2_meas is measured (a camera sees the payload) and used; 0: ignored"),
    parameter("delay", 1.0, "1", "whole communication steps by which the measurements are late"),
    parameter("sigma_force", 0.0, "N/s", "process noise: rate of change of the horizontal force on the payload (and "
                                         "with camera = 1 on the hook), random walks held over each step; 0: no "
                                         "force state, F2_hat = F1_hat = 0"),
    input_("x_meas", "m", "measured trolley position"),
    input_("theta1_meas", "rad", "measured hook swing angle"),
    input_("theta2_meas", "rad", "measured payload swing angle (used when camera = 1)"),
    input_("u", "m/s2", "trolley acceleration applied (the controller's output)"),
    input_("l1_now", "m", "measured main cable length (taken, not used: see the module's notes)"),
) + state_variables(output, "estimated ") + (
    output("F2_hat", "N", "estimated horizontal force on the payload (0 when sigma_force = 0)"),
    output("F1_hat", "N", "estimated horizontal force on the hook (0 when sigma_force = 0 or camera = 0)"),)
IN = positions(VARIABLES, "input")


def _output(config, state, inputs):
    """The estimated state, ``F2_hat`` and ``F1_hat`` (0 where the filter has no such state)."""
    estimate = state[ESTIMATE]
    return (*estimate[:6], *(estimate[k] if len(estimate) > k else 0.0 for k in (6, 7)))


def report(config):
    """The filter gains, for ``crane-fmu info``."""
    names = ("x", "theta1", "theta2")[:len(config.rows)]
    return {f"M_{s}_{m}": config.gain[i][j] for i, s in enumerate((*STATE, "F2", "F1")[:len(config.gain)])
            for j, m in enumerate(names)}


COMPONENT = Component(
    "StateEstimator", "estimator",
    "Discrete Kalman filter of the crane linearised about rest, designed from its parameters at initialisation: "
    "the controllers' inputs x, dx, theta1, dtheta1, theta2, dtheta2 from x_meas, theta1_meas (theta2_meas) and u",
    VARIABLES, configure, _output,
    initial_state=initial_state, update=update, report=report,
    crane_model=CRANE_MODEL, native="estimator.c", rules=RULES)
