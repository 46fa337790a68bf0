"""The native (C) MpcController3D (fmu_src/models/mpc3d.c over mpc_axis.c) against the Python model
(crane_fmu/model/mpc3d.py), the specification: on Linux the same bits, through our master, on the board's S11-S14
and the mpc3d systems; its messages and refusals are the Python FMU's.

The planar MPC the two axes run is mpc_axis.c, the MpcController's (tests/test_native_mpc.py holds it to mpc.py);
what is new here is the pair of axes, the move's start of an axis on a path (the path's plan, path.plan, in C) and
the axis that holds its start position until then.
"""

import math
from dataclasses import replace

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from native_fmus import close, messages, open_native, python_folder, python_run_equal_to_native, steps_after_restore

from crane_fmu import components, systems
from crane_fmu.analysis import scenarios
from crane_fmu.compare import contenders

MPC3D = components.get("MpcController3D")


@pytest.mark.parametrize("version", [2, 3])
def test_native_model_description_has_the_python_fmus_variables(fmu_dir, native, version):
    def variables(path):
        return [(v.name, v.valueReference, v.causality, v.variability, v.initial, v.start, v.unit, v.description)
                for v in read_model_description(str(path)).modelVariables]

    path = native[version] / "MpcController3D.fmu"
    assert variables(path) == variables(python_folder(fmu_dir, version) / "MpcController3D.fmu")
    assert validate_fmu(str(path)) == []


# scenario, stop time [s]: each through what makes it (S13: the y axis' move starts at 2.864 s, within the run)
BOARD = {"S11": 3.0, "S12": 2.0, "S13": 3.5, "S14": 2.0}


@pytest.mark.parametrize("scenario", BOARD)
def test_on_the_boards_spatial_scenarios_the_native_mpc3d_is_the_python_one(fmu_dir, native, scenario):
    """The board's first case of S11-S14 (the MPC3D's own system of each: the diagonal move, the elliptic swing, the
    L path in its corridor, the move in the crosswind): every column bit for bit on Linux, both axes at work (the
    crosswind's y axis the least: 0.07 m/s2)."""
    contender = contenders(["MpcController3D"], fmu_dir, only=True)[0]
    system = replace(scenarios.systems_for(contender, scenario)[0].system, stop_time=BOARD[scenario])
    theirs = python_run_equal_to_native(system, fmu_dir, native, 2)
    assert np.max(np.abs(theirs["controller.ux"])) > 0.5 and np.max(np.abs(theirs["controller.uy"])) > 0.01
    if scenario == "S14":  # the wind's force estimated per axis and taken out (offset_free): that path in C too
        assert system.parameters["controller"]["offset_free"] == 2.0 and np.max(theirs["force_y.F2_hat"]) > 0.3


def test_on_the_path_the_y_axis_holds_until_its_move_starts_then_moves(fmu_dir, native):
    """mpc3d-path in FMI 3.0 over 4 s: the same bits; the y axis' move starts at the plan's t0 (path.plan, in C as
    in Python): before it the y axis' MPC holds y = 0 (its demand within the swing's small corrections), after it
    it drives at its limit."""
    system = replace(systems.get("mpc3d-path"), stop_time=4.0)
    theirs = python_run_equal_to_native(system, fmu_dir, native, 3)
    t0 = MPC3D.report(MPC3D.check(system.parameters["controller"]))["t0_y_s"]
    assert 2.0 < t0 < 3.5
    before, after = theirs["time"] < t0, theirs["time"] > t0 + 0.1
    assert np.max(np.abs(theirs["controller.uy"][before])) < 0.1
    assert np.max(np.abs(theirs["controller.uy"][after])) > 1.9


@pytest.mark.parametrize("name", ["mpc3d", "mpc3d-move"])
def test_the_mpc3d_systems_run_the_python_bits(fmu_dir, native, name):
    python_run_equal_to_native(replace(systems.get(name), stop_time=2.0), fmu_dir, native, 3)


def test_at_its_cap_the_native_mpc3d_warns_once_per_axis_as_the_python_fmu_does(fmu_dir, native):
    """One QP iteration allowed, a swing in both planes: each axis' solves stop at the cap, one warning each, named
    by its axis, the same words as the Python FMU's."""
    swing = {"theta1x": math.radians(30.0), "theta1y": math.radians(20.0)}
    steps = [(0.0, 1e-3, swing)] + [(k * 1e-3, 1e-3) for k in range(1, 120)]
    ours = messages(native[2] / "MpcController3D.fmu", {"max_iterations": 1.0}, steps)
    theirs = messages(fmu_dir / "MpcController3D.fmu", {"max_iterations": 1.0}, steps)
    assert ours == theirs
    assert ours[0][-1] == "end" and [line[:8] for line in ours[1]] == ["x axis: ", "y axis: "]


REFUSED = [{"corridor": -1.0}, {"corridor": math.inf}, {"x_via": math.nan}, {"horizon": 20.0}, {"u_max": 0.0},
           {"corridor": 0.3, "x_via": 1.0, "y_via": 1.0, "x_d": 2.0, "y_d": 2.0}]  # the last: x moves in two legs


@pytest.mark.parametrize("settings", REFUSED, ids=lambda c: ",".join(f"{k}={v!r}" for k, v in c.items()))
def test_every_parameter_refusal_has_the_python_fmus_message(fmu_dir, native, settings):
    ours = messages(native[2] / "MpcController3D.fmu", settings)
    theirs = messages(fmu_dir / "MpcController3D.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


PATH = {"x_d": 3.0, "y_d": 2.0, "x_via": 3.0, "y_via": 0.0, "corridor": 0.3}  # mpc3d-path's: y starts at 2.864 s


@pytest.mark.parametrize("version", [2, 3])
def test_a_restored_fmu_state_repeats_the_steps_after_it(native, version):
    """Saved on the path before the y axis' move starts (both axes' plans and solutions, the time in the state),
    restored, restored from its serialised copy: the steps after it, across the y axis' start, repeat, and are the
    Python model's."""
    fmu, vr, set_, get = open_native(native[version] / "MpcController3D.fmu", version, PATH)
    fmu.exitInitializationMode()
    inputs, outputs = [vr[n] for n in MPC3D.names("input")], [vr[n] for n in MPC3D.names("output")]

    def steps(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            set_(inputs, [0.02 * math.sin(k * 0.01 + i) for i in range(len(inputs))])
            fmu.doStep(k * 1e-2, 1e-2)
            rows.append(get(outputs))
        return rows

    steps(0, 250)
    first, again, third = steps_after_restore(fmu, version, steps, 250, 80)
    close(fmu)
    assert first == again == third
    assert first == _python_rows(PATH, 330)[250:]  # and they are the Python model's


def _python_rows(parameters, n):
    """The Python model's outputs after each of n steps of 10 ms with the inputs of the test above."""
    config = MPC3D.check(parameters)
    state, rows = MPC3D.initial_state(config), []
    for k in range(n):
        inputs = tuple(0.02 * math.sin(k * 0.01 + i) for i in range(len(MPC3D.names("input"))))
        state = MPC3D.update(config, state, inputs, k * 1e-2, 1e-2)
        state = getattr(state, "state", state)
        rows.append(list(MPC3D.output(config, state, inputs)))
    return rows


SHORT_PATH = {**PATH, "x_d": 0.4, "x_via": 0.4, "y_d": 1.0}  # an L path whose y leg starts early (0.123 s)


def _rows_at(parameters, times, step, native_path=None, version=2):
    """The outputs after each step of ``step`` from each of ``times``, inputs as above: the Python model's, or the
    native FMU's at ``native_path``."""
    inputs = [tuple(0.02 * math.sin(k * 0.01 + i) for i in range(len(MPC3D.names("input")))) for k in range(len(times))]
    if native_path is None:
        config = MPC3D.check(parameters)
        state, rows = MPC3D.initial_state(config), []
        for t, u in zip(times, inputs):
            state = MPC3D.update(config, state, u, t, step)
            state = getattr(state, "state", state)
            rows.append(list(MPC3D.output(config, state, u)))
        return rows
    fmu, vr, set_, get = open_native(native_path, version, parameters)
    fmu.exitInitializationMode()
    rows = []
    for t, u in zip(times, inputs):
        set_([vr[n] for n in MPC3D.names("input")], list(u))
        fmu.doStep(t, step)
        rows.append(get([vr[n] for n in MPC3D.names("output")]))
    close(fmu)
    return rows


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("drift", [-2e-13, 2e-13])
def test_a_hosts_rounding_of_its_time_starts_the_y_axis_move_in_the_same_step(native, version, drift):
    """A host that adds up its steps (OMSimulator) hands a time up to about 1e-13 s off the grid k h (4.5029999999998385
    at k = 4503): driven at ``k h + drift`` across the y axis' start t0 (on the 1 ms grid), the Python model's rows and
    the native FMU's are the Python model's at ``k h``, bit for bit: the move starts in the step that ends at t0 either
    way (the planner's rounding margin). Without it a time 2e-13 short of t0 started the move one step late:
    mpc3d-path's last row in OMSimulator differed from our master's by 8.6e-8 (issue 50)."""
    h = 1e-3
    t0 = MPC3D.report(MPC3D.check(SHORT_PATH))["t0_y_s"]
    n = round(t0 / h)
    assert 50 < n < 500 and abs(n * h - t0) < 1e-12  # a start on the grid, within a short run
    exact = _rows_at(SHORT_PATH, [k * h for k in range(n + 10)], h)
    drifted = [k * h + drift for k in range(n + 10)]
    assert _rows_at(SHORT_PATH, drifted, h) == exact
    assert _rows_at(SHORT_PATH, drifted, h, native[version] / "MpcController3D.fmu", version) == exact
    late = _rows_at(SHORT_PATH, [k * h - 1e-6 for k in range(n + 10)], h)  # beyond the margin: a step late
    assert late[:n - 1] == exact[:n - 1] and late[n - 1:] != exact[n - 1:]
