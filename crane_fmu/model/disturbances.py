"""What the test harness adds to a crane: a wind gust (the Gust component) and imperfect sensors (Sensor)."""

import math
from collections import namedtuple

from .component import Component
from .rules import check, finite, non_negative, one_of, positive, whole
from .tables import STATE, input_, output, parameter, state_variables

# The rules of a seed of the noise (noise()), and of a delay in whole communication steps.
SEED = whole("seed", "0 <= seed < 4294967296", "a whole number in [0, 2^32)")
DELAY_STEPS = whole("delay", "0 <= delay <= 100", "a whole number of steps in [0, 100]")

# --- Gust: horizontal force pulses on hook and payload -------------------------------------

GustConfig = namedtuple("GustConfig", "F1 F2 start duration")
GUST_RULES = (*finite("F1_peak", "F2_peak", "start"), *positive("duration"))


def _gust_configure(values):
    check(GUST_RULES, values)
    return GustConfig(values["F1_peak"], values["F2_peak"], values["start"], values["duration"])


def gust(c, t):
    """``(F1, F2)`` at time ``t``: a half-sine pulse ``peak sin(pi (t - start) / duration)`` while it lasts."""
    if not c.start <= t <= c.start + c.duration:
        return 0.0, 0.0
    shape = math.sin(math.pi * (t - c.start) / c.duration)
    return c.F1 * shape, c.F2 * shape


GUST = Component(
    "Gust", "disturbance", "A gust: half-sine pulses of horizontal force on hook (F1) and payload (F2)",
    (parameter("F1_peak", 0.0, "N", "peak force on the hook"),
     parameter("F2_peak", 20.0, "N", "peak force on the payload"),
     parameter("start", 1.5, "s", "when the gust begins"),
     parameter("duration", 0.5, "s", "how long it lasts"),
     output("F1", "N", "horizontal force on the hook"),
     output("F2", "N", "horizontal force on the payload")),
    _gust_configure, lambda config, state, inputs: gust(config, *state),
    initial_state=lambda config: (0.0,), update=lambda config, state, inputs, time, step: (time + step,),
    native="gust.c", rules=GUST_RULES)


# --- Sensor: noise and a one-step delay on the measured state ------------------------------

SIGMAS = ("sigma_x", "sigma_dx", "sigma_theta", "sigma_dtheta")
SensorConfig = namedtuple("SensorConfig", "sigmas seed delay")
SENSOR_RULES = (*non_negative(*SIGMAS), SEED, one_of("delay", (0.0, 1.0), "0 or 1 (communication steps)"))


def _sensor_configure(values):
    check(SENSOR_RULES, values)
    s = [values[n] for n in SIGMAS]
    return SensorConfig((s[0], s[1], s[2], s[3], s[2], s[3]), int(values["seed"]), values["delay"] == 1.0)


def _mix(z):
    """splitmix64: a well-mixed 64-bit integer from ``z``."""
    z = (z + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    return z ^ (z >> 31)


def noise(seed, k, channel):
    """A standard normal sample, a pure function of ``(seed, k, channel)`` (Box-Muller on splitmix64)."""
    a = _mix((seed << 40) ^ (k << 4) ^ channel)
    b = _mix(a)
    u1, u2 = ((a >> 11) + 0.5) / 2 ** 53, (b >> 11) / 2 ** 53
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def measure(c, k, true_state):
    """The measured state at sample ``k``: the true state plus independent normal noise."""
    return tuple(v + s * noise(c.seed, k, i) if s else v for i, (v, s) in enumerate(zip(true_state, c.sigmas)))


def _sensor_output(c, state, inputs):
    k, held = state
    if not c.delay or held is None:  # no delay, or the first sample: measure what is there now
        return measure(c, k, inputs)
    return held


def _sensor_update(c, state, inputs, time, step):
    k, _ = state
    return (k + 1, list(measure(c, k, inputs)))


SENSOR = Component(
    "Sensor", "sensor",
    "Measures the crane state with normal noise (fixed seed) and, optionally, one communication step late",
    (parameter("sigma_x", 1e-3, "m", "noise on the trolley position (standard deviation)"),
     parameter("sigma_dx", 5e-3, "m/s", "noise on the trolley velocity"),
     parameter("sigma_theta", math.radians(0.05), "rad", "noise on both swing angles"),
     parameter("sigma_dtheta", math.radians(0.2), "rad/s", "noise on both swing rates"),
     parameter("seed", 1.0, "1", "seed of the noise (a whole number): the same seed, the same noise"),
     parameter("delay", 1.0, "1", "1: the measurement reaches the output one communication step late; 0: at once"),
     ) + state_variables(input_, "true ") + state_variables(output, "measured ", suffix="_m"),
    _sensor_configure, _sensor_output, feedthrough=True,
    initial_state=lambda config: (0, None), update=_sensor_update, native="sensor.c", rules=SENSOR_RULES,
    depends_on={name + "_m": (name,) for name in STATE})  # each channel its own (at once: delay 0, first sample)


# --- CraneSensor: only what a crane measures, noisy and whole steps late -------------------

MEASURED = ("x", "theta1", "theta2")  # encoder, rope angle at the trolley, a camera on the payload
CraneSensorConfig = namedtuple("CraneSensorConfig", "sigmas seed delay")
CRANE_SENSOR_RULES = (*non_negative("sigma_x", "sigma_theta1", "sigma_theta2"), SEED, DELAY_STEPS)


def _crane_sensor_configure(values):
    check(CRANE_SENSOR_RULES, values)
    return CraneSensorConfig((values["sigma_x"], values["sigma_theta1"], values["sigma_theta2"]), int(values["seed"]),
                             int(values["delay"]))


def crane_measure(c, k, true_values):
    """``(x, theta1, theta2)`` measured at sample ``k``: the true values plus independent normal noise.

    The noise is :func:`noise` on channels 8-10, apart from :class:`Sensor`'s 0-5.
    """
    return tuple(v + s * noise(c.seed, k, 8 + i) if s else v for i, (v, s) in enumerate(zip(true_values, c.sigmas)))


def _crane_sensor_output(c, state, inputs):
    k, history = state
    if c.delay == 0 or not history:  # no delay, or the first sample: what is there now
        return crane_measure(c, k, inputs)
    return tuple(history[0])  # the sample delay steps ago (the first one until there is one that old)


def _crane_sensor_update(c, state, inputs, time, step):
    k, history = state
    if c.delay == 0:
        return (k + 1, [])
    return (k + 1, ([*history, list(crane_measure(c, k, inputs))])[-c.delay:])


CRANE_SENSOR = Component(
    "CraneSensor", "sensor",
    "What a crane measures: trolley position (encoder), hook angle (rope angle sensor) and payload angle (a "
    "camera), each with normal noise (fixed seed), whole communication steps late",
    (parameter("sigma_x", 1e-3, "m", "noise on the trolley position (standard deviation)"),
     parameter("sigma_theta1", math.radians(0.1), "rad", "noise on the hook angle (standard deviation)"),
     parameter("sigma_theta2", math.radians(0.1), "rad", "noise on the payload angle (standard deviation)"),
     parameter("seed", 1.0, "1", "seed of the noise (a whole number): the same seed, the same noise"),
     parameter("delay", 1.0, "1", "whole communication steps by which the outputs are late; 0: at once"),
     *state_variables(input_, "true ", MEASURED),
     output("x_meas", "m", "measured trolley position"),
     output("theta1_meas", "rad", "measured hook swing angle"),
     output("theta2_meas", "rad", "measured payload swing angle (a camera)")),
    _crane_sensor_configure, _crane_sensor_output, feedthrough=True,
    initial_state=lambda config: (0, []), update=_crane_sensor_update, native="crane_sensor.c",
    rules=CRANE_SENSOR_RULES,
    depends_on={name + "_meas": (name,) for name in MEASURED})  # each channel its own (at once: delay 0, first sample)
