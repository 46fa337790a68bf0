"""What a crane measures: the CraneSensor, the StateEstimator's design against scipy, and the LQG systems' targets."""

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.signal import cont2discrete

from crane_fmu import systems
from crane_fmu.analysis import metrics
from crane_fmu.analysis.planar_scenarios import MISMATCH, residual_from
from crane_fmu.cosim import ArrayRecorder, run
from crane_fmu.model import disturbances, estimator, lqr
from crane_fmu.model.parameters import PlantParameters


def _scipy_filter(p, h, sigma_x, sigma_theta, sigma_u, sigma_swing, camera):
    """The filter Riccati equation and gain from scipy: ``solve_discrete_are`` of the dual pair ``(Ad', C')``.

    The process noise enters through the zero-order hold of ``G = [B, e_dtheta1, e_dtheta2]`` (scipy's
    cont2discrete), with the variances written here.
    """
    a, b = map(np.array, lqr.continuous_model(p))
    g = np.hstack([b, np.eye(6)[:, [3]], np.eye(6)[:, [5]]])
    ad, gd, *_ = cont2discrete((a, g, np.eye(6), np.zeros((6, 3))), h)
    qd = gd @ np.diag([sigma_u ** 2, sigma_swing ** 2, sigma_swing ** 2]) @ gd.T
    rows = [0, 2, 4] if camera else [0, 2]
    c = np.eye(6)[rows]
    r = np.diag([sigma_x ** 2, sigma_theta ** 2, sigma_theta ** 2][:len(rows)])
    big_p = scipy.linalg.solve_discrete_are(ad.T, c.T, qd, r)
    return big_p, big_p @ c.T @ np.linalg.inv(c @ big_p @ c.T + r), ad, c


@pytest.mark.quick
@pytest.mark.parametrize("p, h, noises, camera", [
    (PlantParameters(), 1e-3, (1e-3, math.radians(0.1), 0.5, 2.0), False),  # the documented defaults
    (PlantParameters(l1=1.5, m2=3.0), 1e-3, (2e-3, 0.003, 0.1, 0.5), False),
    (PlantParameters(l2=0.6), 1e-2, (1e-3, 0.002, 1.0, 10.0), True),
    (PlantParameters(), 5e-2, (5e-3, 0.01, 2.0, 1.0), False),
])
def test_estimator_design_equals_scipy_riccati(p, h, noises, camera):
    """Our ZOH and doubling DARE on the dual pair against scipy's: the covariance and the gain to 1e-9 relative."""
    big_p, gain = map(np.array, estimator.design(p, h, *noises, camera))
    expected_p, expected_gain, ad, c = _scipy_filter(p, h, *noises, camera)
    assert np.abs(big_p - expected_p).max() < 1e-9 * np.abs(expected_p).max()
    assert np.abs(gain - expected_gain).max() < 1e-9 * np.abs(expected_gain).max()
    assert np.abs(np.linalg.eigvals(ad - ad @ gain @ c)).max() < 1  # the error dynamics it designs are stable


@pytest.mark.quick
def test_estimator_step_is_the_kalman_filter():
    """One step corrects with the measurement and predicts with u: ``Ad (s + M (y - C s)) + Bd u`` (no delay)."""
    values = {**estimator.COMPONENT.defaults(), "delay": 0.0}
    config = estimator.configure(values)
    s = [0.01, -0.02, 0.03, 0.1, -0.02, 0.2]
    state = (1.0, s, [], s)
    y, u = (0.012, 0.028, 0.0), 0.7
    got = estimator.update(config, state, (*y, u, 1.0), 0.0, 1e-3)
    _, gain, ad, c = _scipy_filter(PlantParameters(), 1e-3, *(values[n] for n in estimator.NOISES), False)
    bd = np.array(config.bd)
    expected = ad @ (np.array(s) + gain @ (np.array(y[:2]) - c @ np.array(s))) + bd * u
    assert np.abs(np.array(got[3]) - expected).max() < 1e-12
    assert got[3] == got[1]  # no delay: the output is the prediction itself


@pytest.mark.quick
def test_estimator_with_delay_predicts_forward_with_the_inputs_applied_since():
    """Measurements d steps late: corrected on their own time, then d predictions with the inputs applied since."""
    config = estimator.configure({**estimator.COMPONENT.defaults(), "delay": 2.0})
    s, history = [0.0, 0.1, 0.02, 0.0, 0.01, 0.0], [0.3, -0.4]
    _, z, kept, out = estimator.update(config, (1.0, s, history, s), (0.0, 0.02, 0.0, 0.5, 1.0), 0.0, 1e-3)
    ad, bd = np.array(config.ad), np.array(config.bd)
    filtered = np.array(s) + np.array(config.gain) @ (np.array([0.0, 0.02]) - np.array([s[0], s[2]]))
    z_expected = ad @ filtered + bd * 0.3
    assert np.abs(np.array(z) - z_expected).max() < 1e-12 and kept == [-0.4, 0.5]
    assert np.abs(np.array(out) - (ad @ (ad @ z_expected + bd * -0.4) + bd * 0.5)).max() < 1e-12


@pytest.mark.quick
@pytest.mark.parametrize("values, message", [
    ({"sigma_x": 0.0}, "sigma_x must be > 0 and finite, got 0.0"),
    ({"sigma_swing": math.inf}, "sigma_swing must be > 0 and finite, got inf"),
    ({"camera": 0.5}, "camera must be 0 (x and theta1 measured) or 1 (theta2 too), got 0.5"),
    ({"delay": 1.5}, "delay must be a whole number of steps in [0, 100], got 1.5"),
    ({"h": -1.0}, "h must be > 0 and finite, got -1.0"),
    ({"l2": 0.0}, "l2 must be > 0 and finite, got 0.0"),
])
def test_estimator_parameter_rules(values, message):
    with pytest.raises(ValueError) as info:
        estimator.COMPONENT.check(values)
    assert str(info.value) == message


@pytest.mark.quick
def test_crane_sensor_noise_and_delay():
    """Documented defaults: 1 mm and 0.1 deg standard deviation, seed 1, one step late; a delay of d whole steps
    gives at step k the sample of step k - d (the first sample until there is one that old)."""
    component = disturbances.CRANE_SENSOR
    config = component.check({})
    assert config.sigmas == (1e-3, math.radians(0.1), math.radians(0.1)) and config.seed == 1 and config.delay == 1
    for delay in (0, 1, 3):
        c = component.check({"delay": float(delay)})
        state, seen, truth = component.initial_state(c), [], []
        for k in range(4000):
            true = (0.001 * k, 0.1 * math.sin(k), -0.05)
            truth.append(true)
            seen.append(component.output(c, state, true))
            state = component.update(c, state, true, k * 1e-3, 1e-3)
        error = np.array(seen[delay:]) - np.array(truth[:len(truth) - delay])
        assert np.allclose(error.std(axis=0), c.sigmas, rtol=0.05)  # 4000 samples: ~1.1 % standard error
        assert np.abs(error.mean(axis=0)).max() < 4 * max(c.sigmas) / math.sqrt(len(error))
        assert all(seen[k] == seen[0] for k in range(delay))  # before: the first sample
    again = component.check({})
    assert component.output(again, (7, []), (0.0, 0.0, 0.0)) == component.output(config, (7, []), (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"^delay must be a whole number of steps in \[0, 100\], got -1.0$"):
        component.check({"delay": -1.0})


def _figures(columns, x_d, window=None):
    swing = (columns["plant.theta1"], columns["plant.theta2"])
    return metrics.move_metrics(columns["time"], columns["plant.x"], columns["plant.dx"], swing,
                                columns["controller.u"], x_d, window)


def test_lqg_regulation_meets_the_issue_targets(fmu_dir):
    """Issue 28 (Section V plant, |u| <= 2, |v| <= 1, h = 1 ms, x and theta1 measured with the default noise):
    from 10 deg both TRUE angles within 0.5 deg by 3.5 s and within 0.1 deg by 5.0 s, within the limits."""
    c = run(systems.get("lqg"), fmu_dir, recorder=ArrayRecorder(), stop_time=10.0).columns()
    m = _figures(c, 0.0)
    assert m["settling_0.5deg_s"] is not None and m["settling_0.5deg_s"] <= 3.5, m
    assert m["settling_0.1deg_s"] is not None and m["settling_0.1deg_s"] <= 5.0, m
    assert m["peak_abs_u"] <= 2.0 and m["peak_abs_v"] <= 1.0 + 1e-9
    assert "estimator.theta2" in c and "sensor.theta1_meas" in c  # the controller saw estimates, not the plant


def test_lqg_transport_meets_the_issue_targets(fmu_dir):
    """Issue 28: the 2 m move arrives (5 mm, 0.5 deg) by 4.0 s with at most 0.1 deg of residual swing (from one
    slow period after the planned move's end, as the scoreboard measures it)."""
    system = systems.get("lqg-transport")
    c = run(system, fmu_dir, recorder=ArrayRecorder()).columns()
    m = _figures(c, 2.0, residual_from(system.stop_time, system.parameters["planner"]))
    assert m["arrival_s"] is not None and m["arrival_s"] <= 4.0, m
    assert m["residual_deg"] <= 0.1, m


def test_lqg_transport_on_the_mismatch_grid(native):
    """On the 27 plants of ``crane-fmu targets`` (l1 +-10 %, l2 +-20 %, m2 +-50 %), unknown to estimator and
    controller, every plant arrives and the worst residual swing (measured as the scoreboard does, from one slow
    period of the plant after the planned move's end) is within 1 deg. The scoreboard's S9 asks more (0.1 deg: the
    swing stopped), which this loop misses with light payloads; the board shows it. Run on the native FMUs, which
    test_native_estimation.py holds to the Python FMUs in this system (27 runs in a tenth of the time)."""
    system = systems.get("lqg-transport")
    worst = 0.0
    for plant in MISMATCH:
        c = run(system.with_parameters({"plant": plant}), native[2], recorder=ArrayRecorder()).columns()
        m = _figures(c, 2.0, residual_from(system.stop_time, system.parameters["planner"], plant))
        assert m["arrival_s"] is not None, plant
        worst = max(worst, m["residual_deg"])
    assert worst <= 1.0
