"""The least peak swing in S4's gust (crane_fmu.analysis.gust_peak) on known answers: with the trolley held still its
linear program has one answer, the linearised crane's own response, here computed by scipy.signal.lsim."""

import math

import numpy as np
import scipy.signal

from crane_fmu.analysis import floor, gust_peak
from crane_fmu.model.parameters import PlantParameters

HELD = {"u_max": 0.0, "arrival_from": None, "residual_from": math.inf}  # no drive, no targets: one trajectory
STOP = 3.0


def _lsim_peak(state, forces, grid=gust_peak.GRID, stop=STOP):
    """The largest |theta1|, |theta2| [deg] at the grid's points of the linearised crane (u = 0) under ``forces``
    held over each grid interval, by scipy's continuous-time simulation."""
    a, _, e = floor.crane_model(PlantParameters())
    t = np.arange(len(forces) + 1) * grid
    held = np.vstack([forces, forces[-1:]])  # lsim holds each sample to the next (interp=False)
    _, _, x = scipy.signal.lsim((a, e, np.eye(6), np.zeros((6, 2))), held, t, X0=state, interp=False)
    return math.degrees(np.max(np.abs(x[:, [2, 4]])))


def _slow_swing(degrees):
    """``(state, w)``: the slow mode leaving the vertical (its shape's rates) with ``degrees`` of amplitude on the angle
    it moves most, and its angular frequency [rad/s]."""
    a, _, _ = floor.crane_model(PlantParameters())
    values, vectors = np.linalg.eig(a[2:, 2:])
    slow = np.argmin(np.abs(values))
    w = abs(values[slow].imag)
    shape = np.real(vectors[[0, 2], slow] / values[slow])  # the angles' shape (the eigenvector's angle rows)
    shape = shape / np.max(np.abs(shape)) * math.radians(degrees)
    return np.array([0.0, 0.0, 0.0, w * shape[0], 0.0, w * shape[1]]), w


def test_a_crane_held_still_in_the_gust_peaks_as_its_linear_response():
    """From a swing (which the push meets in its own direction or against it) with no drive, the gust's push gives
    the one trajectory the program may take: its peak is the linearised crane's, sampled at the same points (the
    gust's force averaged over each interval as the program's)."""
    count = int(round(STOP / gust_peak.GRID))
    forces = gust_peak.gust_forces(1.4, count)
    for degrees in (0.0, 3.0, -3.0):
        state, _ = _slow_swing(degrees)
        found = gust_peak.least_peak(state, 1.4, forces, stop=1.4 + STOP, **HELD)
        assert found.peak_deg > 1.0  # the push swings the load (a 10 N gust on 7 kg)
        assert math.isclose(found.peak_deg, _lsim_peak(state, forces), rel_tol=1e-6)


def test_a_free_swing_of_the_slow_mode_peaks_at_its_amplitude():
    """A swing in the slow mode from the vertical (the rates of the mode's shape) and no drive: its largest angle is
    the mode's amplitude on the angle it moves most, sampled on the grid within cos(w grid / 2) of it."""
    state, w = _slow_swing(10.0)
    count = int(round(STOP / gust_peak.GRID))
    found = gust_peak.least_peak(state, 0.0, np.zeros((count, 2)), stop=STOP, **HELD)
    assert 10.0 * math.cos(w * gust_peak.GRID / 2) <= found.peak_deg <= 10.0 + 1e-9
    assert math.isclose(found.peak_deg, _lsim_peak(state, np.zeros((count, 2))), rel_tol=1e-6)


def test_the_drive_takes_the_gusts_peak_down_and_no_plan_keeps_a_target_it_cannot_reach():
    """With the drive the least peak is below the held crane's; a trolley that must be 2 m away by 0.3 s cannot."""
    count = int(round(STOP / gust_peak.GRID))
    forces = gust_peak.gust_forces(1.4, count)
    held = gust_peak.least_peak(np.zeros(6), 1.4, forces, stop=1.4 + STOP, **HELD).peak_deg
    driven = gust_peak.least_peak(np.zeros(6), 1.4, forces, stop=1.4 + STOP, x_d=0.0, arrival_from=None,
                                  residual_from=math.inf)
    assert driven.peak_deg < 0.5 * held and np.max(np.abs(driven.u)) <= 2.0 + 1e-9
    assert gust_peak.least_peak(np.zeros(6), 1.4, forces, stop=1.4 + STOP, arrival_from=1.7,
                                residual_from=math.inf) is None
