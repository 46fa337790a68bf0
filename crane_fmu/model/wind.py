"""Turbulent wind on the crane (the Wind component): a mean speed plus Dryden turbulence, as drag on hook and payload.

The longitudinal Dryden turbulence ``w`` (MIL-F-8785C) has the one-sided power spectral density

    S(f) = 4 sigma^2 T / (1 + (2 pi f T)^2),   T = L / U,

the output of the first-order shaping filter ``T w' = -w + sigma sqrt(2 T) n`` driven by unit white noise
``n``: a Gauss-Markov process of variance ``sigma^2`` and autocovariance ``sigma^2 exp(-|tau| / T)``.
Sampled at the communication step ``h`` it is exactly the first-order autoregression

    w_(k+1) = a w_k + sigma sqrt(1 - a^2) n_k,   a = exp(-h / T),

(the filter's zero-order-hold discretisation with the noise's covariance integrated over the step), held
over each step. ``w_0`` is drawn from the stationary distribution, so the wind is stationary from its first
sample. The noise is :func:`.disturbances.noise` of the seed and the sample's index (channel
:data:`CHANNEL`): the same seed, the same wind, in Python and in C.

The drag on a body of area ``A`` moving horizontally at ``v`` in the wind ``U + w`` is
``0.5 rho Cd A (U + w - v) |U + w - v|`` along x, on the hook (``A1``) and the payload (``A2``), whose
velocities follow from the plant's state and the cable lengths (eqs (4)-(5) differentiated).
"""

import math
from collections import namedtuple

from .component import Component
from .disturbances import SEED, noise
from .rules import check, finite, non_negative, positive, rule
from .tables import STATE, input_, output, parameter, state_variables

CHANNEL = 16  # the noise channel of the wind, apart from the sensors' 0-5 and 8-10
# MIL-F-8785C's low-altitude model at h = 10 m (32.8 ft) for a 10 m/s wind taken as its 20-ft wind W20:
# sigma = 0.1 W20 / (0.177 + 0.000823 h)^0.4 and L = h / (0.177 + 0.000823 h)^1.2 [ft]
_H_FT = 10.0 / 0.3048
SIGMA_MODERATE = 0.1 * 10.0 / (0.177 + 0.000823 * _H_FT) ** 0.4  # 1.89 m/s: 19 % of the mean
LENGTH_SCALE = _H_FT / (0.177 + 0.000823 * _H_FT) ** 1.2 * 0.3048  # 67.3 m

WindConfig = namedtuple("WindConfig", "mean sigma time_constant drag1 drag2 l1 l2 seed")


RULES = (*finite("U_mean", "l1", "l2"), *non_negative("sigma", "rho", "Cd", "A1", "A2"), *positive("L"),
         rule("U_mean != 0", "U_mean must not be 0 while sigma > 0: Dryden turbulence is carried by a mean wind (its "
              "time constant is L / |U_mean|)", when="sigma > 0"),
         SEED)  # checked in this order (rules.py)


def _configure(values):
    check(RULES, values)
    seed = values["seed"]
    half = 0.5 * values["rho"] * values["Cd"]
    time_constant = values["L"] / abs(values["U_mean"]) if values["U_mean"] else math.inf
    return WindConfig(values["U_mean"], values["sigma"], time_constant, half * values["A1"], half * values["A2"],
                      values["l1"], values["l2"], int(seed))


def turbulence_step(c, w, k, h):
    """The turbulence at sample ``k + 1`` from ``w`` at sample ``k``, ``h`` [s] later (the exact AR(1) above)."""
    a = math.exp(-h / c.time_constant)
    return a * w + c.sigma * math.sqrt(1.0 - a * a) * noise(c.seed, k + 1, CHANNEL)


def drag(half_rho_cd_area, wind, velocity):
    """The drag force [N] on a body moving at ``velocity`` [m/s] in ``wind`` [m/s] (both along x)."""
    relative = wind - velocity
    return half_rho_cd_area * relative * abs(relative)


def _output(c, state, inputs):
    dx, theta1, dtheta1, theta2, dtheta2 = inputs
    speed = c.mean + state[TURBULENCE]
    v1 = dx + c.l1 * math.cos(theta1) * dtheta1  # the hook's horizontal velocity, d/dt of eq (4)
    v2 = v1 + c.l2 * math.cos(theta2) * dtheta2  # the payload's, d/dt of eq (5)
    return drag(c.drag1, speed, v1), drag(c.drag2, speed, v2), speed


TURBULENCE = 1  # the state is (the sample number, the turbulence [m/s] there)


def _initial_state(c):
    return (0, c.sigma * noise(c.seed, 0, CHANNEL))  # drawn from the stationary distribution: no transient


def _update(c, state, inputs, time, step):
    k, w = state
    return (k + 1, turbulence_step(c, w, k, step))


COMPONENT = Component(
    "Wind", "disturbance",
    "Turbulent wind along the trolley's rail: a mean speed plus Dryden turbulence (exact discrete shaping "
    "filter, seeded), as drag forces on hook (F1) and payload (F2)",
    (parameter("U_mean", 10.0, "m/s", "mean wind speed along x (negative: against the move)"),
     parameter("sigma", SIGMA_MODERATE, "m/s", "turbulence: standard deviation of the wind speed (default: moderate, "
               "MIL-F-8785C low-altitude model at 10 m for a 10 m/s wind)"),
     parameter("L", LENGTH_SCALE, "m", "turbulence length scale (MIL-F-8785C low-altitude model at 10 m)"),
     parameter("rho", 1.225, "kg/m3", "air density"),
     parameter("Cd", 1.05, "1", "drag coefficient of hook and payload (a cube broadside)"),
     parameter("A1", 0.005, "m2", "hook's area facing the wind"),
     parameter("A2", 0.01, "m2", "payload's area facing the wind"),
     parameter("l1", 1.0, "m", "main cable length, trolley to hook (for the hook's velocity)"),
     parameter("l2", 0.5, "m", "lower cable length, hook to payload (for the payload's velocity)"),
     parameter("seed", 1.0, "1", "seed of the turbulence (a whole number): the same seed, the same wind"),
     *state_variables(input_, names=STATE[1:]),  # dx .. dtheta2
     output("F1", "N", "drag on the hook along x"),
     output("F2", "N", "drag on the payload along x"),
     output("wind", "m/s", "wind speed along x: U_mean plus the turbulence")),
    _configure, _output, feedthrough=True, initial_state=_initial_state, update=_update,
    depends_on={"F1": ("dx", "theta1", "dtheta1"), "F2": ("dx", "theta1", "dtheta1", "theta2", "dtheta2")},
    crane_model=("l1", "l2"), native="wind.c", rules=RULES)
