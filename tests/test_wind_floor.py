"""What physics allows in S10's turbulent wind (issue 51 item 1): the least residual swing of a controller that knows
the wind in advance, on known answers, checked against an independent simulation of its plan; about the mean wind's
equilibrium (why S10's arrival is the load's) and about the load's lean (S10's measure): its targets within physics
in every case of the board's design."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from crane_fmu.analysis import floor, planar_scenarios, wind_floor
from crane_fmu.analysis.wind_equilibrium import wind_deflection
from crane_fmu.model.parameters import PlantParameters

CASES = wind_floor.cases()
SECTION_V = {"l1": 1.0, "l2": 0.5, "m1": 3.0, "m2": 7.0}


def _steady(**changes):
    """S10's task on the Section V crane in the mean wind without turbulence."""
    case = wind_floor.WindCase(SECTION_V, {"seed": 1.0, "sigma": 0.0}, 2.0, 10.0,
                               planar_scenarios.residual_from(10.0, planar_scenarios.PLAN, SECTION_V), 6.4)
    return case._replace(**changes)


@pytest.mark.parametrize("arrival", wind_floor.ARRIVALS)
def test_in_a_steady_wind_the_load_can_be_brought_to_rest_at_the_equilibrium(arrival):
    """Without turbulence the drag is constant: a controller can end the move at rest where the wind holds the
    cables, so nothing is left about the equilibrium (the trolley at the target, the load 14.5 mm downwind): zero
    to the interior point method's tolerance (the linearised crane's rest, F / (m g), and the statics', its arctan,
    differ by 2e-5 deg, which a trolley creeping at 1e-6 m/s2 takes away)."""
    assert wind_floor.least_residual(_steady(), arrival) == pytest.approx(0.0, abs=1e-5)


def test_no_controller_arrives_before_the_drive_can_move_the_load():
    """Known answer: a 2 m move at 1 m/s and 2 m/s2 needs 2.5 s; an arrival target at 2 s is infeasible, at 4 s not."""
    assert wind_floor.least_residual(_steady(arrival_from=2.0, residual_from=2.0)) is None
    assert wind_floor.least_residual(_steady(arrival_from=4.0, residual_from=4.0)) is not None


def test_bad_arrival_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"arrival must be one of \('load', 'trolley', None\), got 'hook'"):
        wind_floor.least_residual(_steady(), "hook")


def test_the_plan_simulated_independently_keeps_its_bounds():
    """The plan of S10's case #54 (the design's hardest, seed 1987023707) integrated by scipy's DOP853 on the
    linearised crane under the same held drag: the angles within the plan's residual of the equilibrium in the
    residual window, the load in its band there and from the arrival target on, the speed within 1 m/s."""
    case = CASES[53]
    found = wind_floor.plan(case)
    p = dataclasses.replace(PlantParameters(), **case.plant)
    a, b, e = floor.crane_model(p)
    forces = wind_floor.still_drag(case.wind, case.stop_time)
    grid, state, states = wind_floor.GRID, np.zeros(6), [np.zeros(6)]
    for u, f in zip(found.u, forces):
        state = solve_ivp(lambda t, s, u=u, f=f: a @ s + b * u + e @ f, (0.0, grid), state, method="DOP853",
                          rtol=1e-11, atol=1e-13).y[:, -1]
        states.append(state)
    states, t = np.array(states), np.arange(len(states)) * grid + 1e-9
    equilibrium = np.degrees(wind_deflection(case.plant, case.wind))
    swing = np.abs(np.degrees(states[:, [2, 4]]) - equilibrium)
    load = states[:, 0] + p.l1 * states[:, 2] + p.l2 * states[:, 4] - case.x_d
    window, arrived = t >= case.residual_from, t >= case.arrival_from
    assert swing[window].max() <= found.residual_deg + 1e-6
    assert swing[arrived].max() <= 0.5 + 1e-6
    assert np.abs(load[window | arrived]).max() <= planar_scenarios.LOAD_BAND_M + 1e-7
    assert np.abs(states[:, 1]).max() <= 1.0 + 1e-7 and np.abs(found.u).max() <= 2.0 + 1e-9
    assert found.residual_deg < planar_scenarios.WIND_CUT_DEG


@pytest.mark.parametrize("chunk", range(4))
def test_about_the_mean_equilibrium_the_targets_are_within_physics_in_every_case(chunk):
    """In each of the board's 64 cases a controller that knows the wind in advance meets S10's arrival and load
    targets and leaves less than the residual target about the mean wind's equilibrium (S10's measure before the
    lean: within physics, but not for a controller that does not know the wind, :func:`wind_floor.receding`)."""
    for number in range(16 * chunk, 16 * chunk + 16):
        least = wind_floor.least_residual(CASES[number])
        assert least is not None and least < planar_scenarios.WIND_CUT_DEG, f"#{number + 1:02d}: {least}"


@pytest.mark.parametrize("chunk", range(4))
def test_s10s_targets_as_measured_are_within_physics_in_every_case(chunk):
    """No empty target: in each of the board's 64 cases the plan of least swing about the load's lean, run on the
    board's 1 ms step under the 1 ms drag, meets all three of S10's targets as the board measures them."""
    for number in range(16 * chunk, 16 * chunk + 16):
        left = wind_floor.lean_witness(CASES[number])
        assert left is not None, f"#{number + 1:02d}: infeasible"
        assert left.residual_deg <= planar_scenarios.WIND_CUT_DEG, f"#{number + 1:02d}: {left}"
        assert left.load_error_m <= planar_scenarios.LOAD_BAND_M and left.arrived, f"#{number + 1:02d}: {left}"


def test_in_a_steady_wind_nothing_is_left_about_the_lean():
    """Known answer: at rest at the equilibrium the lean is the equilibrium; the program finds a plan that leaves no
    swing about it (to the interior point method's tolerance), with the lean measured on S10's run."""
    found = wind_floor.plan(_steady(stop_time=planar_scenarios.WIND_RUN_S), grid=0.02, about="lean")
    assert found.residual_deg == pytest.approx(0.0, abs=1e-5)


def test_a_bad_reference_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"about must be 'equilibrium' or 'lean', got 'vertical'"):
        wind_floor.plan(_steady(), about="vertical")


@pytest.mark.parametrize("number", [1, 21, 32, 43, 48, 54, 61])
def test_a_trolley_held_within_5_mm_misses_s10_in_these_cases(number):
    """Why S10's arrival is measured on the load: with S2's trolley band the targets are out of reach in the cases its
    text names, whatever a controller does (the arrival infeasible, or the least residual above the target)."""
    least = wind_floor.least_residual(CASES[number - 1], "trolley")
    assert least is None or least > planar_scenarios.WIND_CUT_DEG


@pytest.mark.parametrize("number", [43, 54])
def test_the_mean_winds_load_band_leaves_more_than_the_residual_target_in_these_cases(number):
    """Why the load's band is taken in the design gust: with the mean wind's offset alone (34.6 mm) the residual
    target and the band cannot both be met in the cases the text names."""
    mean_band = round(0.005 + sum(length * math.sin(angle) for length, angle in zip(
        (1.1, 0.6), wind_deflection({"m1": 2.4, "m2": 3.5}))), 4)
    assert mean_band == 0.0346
    assert wind_floor.least_residual(CASES[number - 1], load_band=mean_band) > planar_scenarios.WIND_CUT_DEG


def test_in_a_steady_wind_the_receding_strategy_keeps_the_load_at_rest():
    """Without turbulence its forecast is the wind itself: from rest at the equilibrium nothing is left about it, and
    the load stays within its band (where in it, the program is free to choose: only the swing is minimised)."""
    r = wind_floor.receding(_steady())
    assert r.residual_deg == pytest.approx(0.0, abs=1e-5) and r.arrived
    assert r.load_error_m <= planar_scenarios.LOAD_BAND_M
