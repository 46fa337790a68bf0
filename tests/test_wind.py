"""The Wind component: Dryden turbulence with known statistics, and the drag it puts on hook and payload.

Known answers, each with the sampling error it allows: the variance of the wind speed is sigma^2, its power
spectrum the Dryden spectrum 4 sigma^2 T / (1 + (2 pi f T)^2) with T = L / U, and it is stationary from its
first sample (an ensemble over seeds has the same variance at every sample, the first one included).
"""

import math

import numpy as np
import pytest
import scipy.signal

from crane_fmu.cosim import ArrayRecorder, System, run
from crane_fmu.model import wind

COMPONENT = wind.COMPONENT
STILL = (0.0, 0.0, 0.0, 0.0, 0.0)  # dx, theta1, dtheta1, theta2, dtheta2: bodies at rest


@pytest.fixture(scope="module")
def fast_wind():
    """200 000 samples of the turbulence of :data:`FAST` at :data:`H`."""
    return _speeds(200_000, H, **FAST) - FAST["U_mean"]


def _speeds(steps, h, seed=1, **values):
    """The wind speed at samples 0..steps of the model's own functions, the inputs at rest."""
    c = COMPONENT.check({"seed": float(seed), **values})
    state, speeds = COMPONENT.initial_state(c), []
    for k in range(steps + 1):
        speeds.append(COMPONENT.output(c, state, STILL)[2])
        state = COMPONENT.update(c, state, STILL, k * h, h)
    return np.array(speeds)


# A short time constant (T = L / U = 0.1 s) so that a test of seconds holds many independent stretches.
FAST = {"U_mean": 10.0, "L": 1.0, "sigma": 2.0}
H = 0.01


def test_the_variance_is_the_dryden_variance(fast_wind):
    """200 000 samples of the AR(1) with a = exp(-h / T) = exp(-0.1): the sample variance's standard error is
    sigma^2 sqrt(2 (1 + a^2) / (N (1 - a^2))) = 1.4 % of sigma^2; allowed: 4 of them, and a mean within 4 standard
    errors sigma sqrt((1 + a) / (N (1 - a)))."""
    w = fast_wind
    a, n, var = math.exp(-H / 0.1), len(w), FAST["sigma"] ** 2
    assert abs(w.var() - var) <= 4 * var * math.sqrt(2 * (1 + a * a) / (n * (1 - a * a)))
    assert abs(w.mean()) <= 4 * FAST["sigma"] * math.sqrt((1 + a) / (n * (1 - a)))
    lag1 = np.mean(w[1:] * w[:-1]) / w.var()
    assert lag1 == pytest.approx(a, abs=0.01)  # the autocorrelation of the exact discretisation


def test_the_power_spectrum_is_the_dryden_spectrum(fast_wind):
    """Welch's estimate (segments of 4096 samples, 97 of them) against 4 sigma^2 T / (1 + (2 pi f T)^2) from
    0.05 Hz to 10 Hz (a fifth of Nyquist, where the sampled spectrum has not folded): the log-PSDs correlate
    >= 0.95 and their mean ratio is 1 within 10 % (each Welch point has a standard error of about 1/sqrt(97))."""
    w = fast_wind
    f, measured = scipy.signal.welch(w, fs=1 / H, nperseg=4096)
    band = (f >= 0.05) & (f <= 10.0)
    t = FAST["L"] / FAST["U_mean"]
    dryden = 4 * FAST["sigma"] ** 2 * t / (1 + (2 * math.pi * f[band] * t) ** 2)
    assert np.corrcoef(np.log(measured[band]), np.log(dryden))[0, 1] >= 0.95
    assert abs(np.mean(np.log(measured[band] / dryden))) <= 0.1


def test_the_wind_is_stationary_from_its_first_sample():
    """An ensemble of 4000 seeds of the default wind (moderate turbulence, T = 6.7 s): the variance at the first
    sample, after one step of 1 ms and after 2 s more (a third of T, one exact step) is sigma^2 each within 4
    standard errors (sigma^2 sqrt(2 / 4000)), and the mean U_mean within 4 sigma / sqrt(4000); a wind started
    from its mean would have no variance at the first sample."""
    c0 = COMPONENT.check({})
    ensemble = []
    for seed in range(4000):
        c = COMPONENT.check({"seed": float(seed)})
        state = COMPONENT.initial_state(c)
        speeds = [COMPONENT.output(c, state, STILL)[2]]
        for h in (1e-3, 2.0):
            state = COMPONENT.update(c, state, STILL, 0.0, h)
            speeds.append(COMPONENT.output(c, state, STILL)[2])
        ensemble.append(speeds)
    for column in np.array(ensemble).T:
        assert abs(column.var() - c0.sigma ** 2) <= 4 * c0.sigma ** 2 * math.sqrt(2 / 4000)
        assert abs(column.mean() - c0.mean) <= 4 * c0.sigma / math.sqrt(4000)


def test_the_defaults_are_moderate_turbulence_at_10_m():
    """MIL-F-8785C low altitude, h = 32.8 ft, W20 = 10 m/s: sigma = 1.0 / 0.204^0.4, L = 32.8 / 0.204^1.2 ft."""
    h = 10 / 0.3048
    assert wind.SIGMA_MODERATE == pytest.approx(1.0 / (0.177 + 0.000823 * h) ** 0.4, rel=1e-12)
    assert (wind.SIGMA_MODERATE, wind.LENGTH_SCALE) == pytest.approx((1.889, 67.37), rel=1e-3)
    assert COMPONENT.defaults()["U_mean"] == 10.0


def test_the_same_seed_gives_the_same_wind_and_another_seed_another():
    assert np.array_equal(_speeds(500, H, seed=7, **FAST), _speeds(500, H, seed=7, **FAST))
    assert not np.allclose(_speeds(500, H, seed=7, **FAST), _speeds(500, H, seed=8, **FAST))


def test_drag_on_hook_and_payload():
    """0.5 rho Cd A v_rel |v_rel|, by hand: rho = 1.2, Cd = 1, A1 = 0.5, A2 = 0.25, no turbulence, U = 10 m/s.
    Bodies at rest: F1 = 0.3 * 100 = 30 N, F2 = 15 N. Trolley at 4 m/s, the hook swinging at 2 rad/s through
    theta1 = 60 deg (l1 = 1 m: the hook at 4 + cos(60 deg) 2 = 5 m/s), the payload at theta2 = 0 with
    -20 rad/s (l2 = 0.5 m: at 5 - 10 = -5 m/s): F1 = 0.3 * 25 = 7.5 N, F2 = 0.15 * 15^2 = 33.75 N. A body
    faster than the wind is pushed back."""
    c = COMPONENT.check({"sigma": 0.0, "rho": 1.2, "Cd": 1.0, "A1": 0.5, "A2": 0.25, "l1": 1.0, "l2": 0.5})
    state = COMPONENT.initial_state(c)
    assert COMPONENT.output(c, state, STILL) == pytest.approx((30.0, 15.0, 10.0), rel=1e-12)
    moving = (4.0, math.radians(60), 2.0, 0.0, -20.0)
    assert COMPONENT.output(c, state, moving) == pytest.approx((7.5, 33.75, 10.0), rel=1e-12)
    assert COMPONENT.output(c, state, (12.0, 0, 0, 0, 0))[:2] == pytest.approx((-0.3 * 4, -0.15 * 4), rel=1e-12)


@pytest.mark.parametrize("values, message", [
    ({"sigma": -1.0}, "sigma must be >= 0 and finite, got -1.0"),
    ({"L": 0.0}, "L must be > 0 and finite, got 0.0"),
    ({"U_mean": 0.0}, "U_mean must not be 0 while sigma > 0: Dryden turbulence is carried by a mean wind (its time "
                      "constant is L / |U_mean|)"),
    ({"seed": 1.5}, "seed must be a whole number in [0, 2^32), got 1.5"),
    ({"A2": math.inf}, "A2 must be >= 0 and finite, got inf"),
])
def test_parameter_rules(values, message):
    with pytest.raises(ValueError) as info:
        COMPONENT.check(values)
    assert str(info.value) == message


def test_the_fmu_gives_the_model_and_pushes_the_payload(fmu_dir):
    """The built Wind FMU on the plant (by name), 2 s at 1 ms: its wind speed is the model's, sample by sample,
    and its drag swings the payload downwind (F2 > 0 on average, theta2 > 0 at the end of a steady push)."""
    system = System("wind", {"plant": "CranePlant", "wind": "Wind"}, parameters={"plant": {"theta1_0": 0.0},
                                                                                 "wind": {"seed": 3.0}},
                    stop_time=2.0)
    c = run(system, fmu_dir, recorder=ArrayRecorder()).columns()
    assert np.array_equal(c["wind.wind"], _speeds(2000, 1e-3, seed=3))
    assert np.mean(c["wind.F2"]) > 0 and c["plant.theta2"][-1] > 0
