"""Metrics and linear analysis on signals and systems with known answers."""

import math

import numpy as np
import pytest

from crane_fmu.analysis import linear, metrics
from crane_fmu.model.parameters import ControllerGains, PlantParameters

T = np.arange(0, 60, 0.01)


def test_dominant_frequencies_of_two_sines():
    signal = np.sin(2 * np.pi * 0.7 * T) + 0.3 * np.sin(2 * np.pi * 1.9 * T + 0.4)
    f = metrics.dominant_frequencies(T, signal)
    assert f[0] == pytest.approx(0.7, abs=2e-3) and f[1] == pytest.approx(1.9, abs=2e-3)


def test_weak_peaks_are_dropped():
    signal = np.sin(2 * np.pi * 0.7 * T) + 0.01 * np.sin(2 * np.pi * 1.9 * T)
    assert len(metrics.dominant_frequencies(T, signal)) == 1


def test_settling_time_of_an_exponential():
    band = 0.05
    t_settle = metrics.settling_time(T, [np.exp(-T)], band)
    assert t_settle == pytest.approx(math.log(1 / band), abs=0.01)
    assert metrics.settling_time(T, [np.exp(-T), np.zeros_like(T)], band) == t_settle
    assert metrics.settling_time(T, [np.cos(T)], 0.5) is None  # cos(59.99) = -0.95


def test_peak_and_rms():
    assert metrics.peak_abs(np.array([0.1, -2.0, 1.0])) == 2.0
    assert metrics.rms(np.sin(2 * np.pi * T[:6000])) == pytest.approx(1 / math.sqrt(2), rel=1e-3)


@pytest.mark.parametrize("signal, completed, outcome", [
    (0.2 * np.exp(-0.3 * T) * np.sin(5 * T), True, "converges"),
    (0.2 * np.sin(5 * T), True, "sustained oscillation"),
    (0.01 * np.exp(0.05 * T) * np.sin(5 * T), True, "diverges"),
    (0.2 * np.sin(5 * T), False, "diverges"),
    (2.0 * np.sin(5 * T), True, "diverges"),
    (np.full_like(T, 1e-4), True, "converges"),
])
def test_classify(signal, completed, outcome):
    assert metrics.classify(T, signal, 0.5 * signal, completed) == outcome


def test_natural_frequencies_match_the_closed_form():
    p = PlantParameters(m1=3.0, m2=7.0, l1=1.0, l2=0.25)
    m, l_sum, l_prod = p.m1 + p.m2, p.l1 + p.l2, p.l1 * p.l2
    root = math.sqrt(m * (m * l_sum ** 2 - 4 * p.m1 * l_prod))
    omega_sq = sorted(p.g * (m * l_sum + s * root) / (2 * p.m1 * l_prod) for s in (-1, 1))
    expected = [math.sqrt(w) / (2 * math.pi) for w in omega_sq]
    assert linear.natural_frequencies(p) == pytest.approx(expected, rel=1e-12)


def test_trolley_only_law_has_pd_poles_and_undamped_pendulum():
    """u from the x row alone: poles -K1_x, -K2_x and the free pendulum's +-j*omega."""
    p = PlantParameters()
    gains = ControllerGains(w_theta1=0.0, w_theta2=0.0)
    poles = linear.closed_loop_poles(p, gains)
    omegas = [2 * math.pi * f for f in linear.natural_frequencies(p)]
    expected = [-0.92, -0.84] + [s * 1j * w for w in omegas for s in (1, -1)]
    def key(z):
        return round(z.real, 6), z.imag

    assert sorted(poles, key=key) == pytest.approx(sorted(expected, key=key), abs=1e-5)


def test_the_theta2_row_and_b3_sign_do_not_change_the_linearisation():
    p = PlantParameters()
    jacobians = [linear.closed_loop_jacobian(p, ControllerGains(**kw))
                 for kw in ({}, {"b3_form": "printed"}, {"w_theta2": 0.0})]
    assert np.abs(jacobians[0] - jacobians[1]).max() < 1e-6
    assert np.abs(jacobians[0] - jacobians[2]).max() < 1e-6
