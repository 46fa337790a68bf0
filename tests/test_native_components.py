"""The native (C) TrajectoryPlanner, EnergyController, Gust and Sensor FMUs against their specification (and every
native component of HOST_CASES, the Wind too, in the C host on Linux and under Wine).

Built by the session's ``fmu_dir`` fixture into ``build/native`` beside the Python FMUs. The Python
models (crane_fmu/model/planner.py, energy.py, disturbances.py) are the specification: on Linux
(glibc's libm in both, the same operations in the same order) the native outputs are the Python ones
bit for bit.
"""

import os
import random
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu
from native_fmus import (
    close,
    compare_to_python,
    compiler,
    enumerations,
    item_value,
    messages,
    open_native,
    outputs_beside_python,
    python_folder,
    steps_after_restore,
)

from crane_fmu import components, systems
from crane_fmu.analysis.scenarios import Contender, systems_for
from crane_fmu.build_scripts.native import FOLDERS, HOST, source_path, variables_header
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cosim import System, run
from crane_fmu.model import planner

PLANNER, ENERGY = components.get("TrajectoryPlanner"), components.get("EnergyController")
GUST, SENSOR = components.get("Gust"), components.get("Sensor")
NAMES = ("TrajectoryPlanner", "EnergyController", "Gust", "Sensor")
SHAPERS = ("zv", "zvd", "ei", "none", "shortest")
LINUX = sys.platform.startswith("linux")  # glibc's libm in both models: the same bits
INF, NAN = float("inf"), float("nan")
CLEAN_ENV = {"PATH": "/usr/bin:/bin"}  # no venv, no pyenv: nothing of Python


# ---- one source: the Python FMU's variables; strict C --------------------------------------------------------------

def _variables(path):
    md = read_model_description(str(path))
    return [(v.name, v.valueReference, v.causality, v.variability, v.initial, v.start, v.unit, v.displayUnit,
             v.description) for v in md.modelVariables], md


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", NAMES)
def test_native_model_description_has_the_python_fmus_variables(fmu_dir, native, name, version):
    """Names, value references, causalities, start values, units, descriptions, outputs, default experiment."""
    ours, md = _variables(native[version] / f"{name}.fmu")
    theirs, py_md = _variables(python_folder(fmu_dir, version) / f"{name}.fmu")
    assert ours == theirs
    assert md.coSimulation.modelIdentifier == py_md.coSimulation.modelIdentifier == name
    assert (md.defaultExperiment.stopTime, md.defaultExperiment.stepSize) == \
        (py_md.defaultExperiment.stopTime, py_md.defaultExperiment.stepSize)
    assert [u.variable.name for u in md.outputs] == [u.variable.name for u in py_md.outputs]
    assert validate_fmu(str(native[version] / f"{name}.fmu")) == []
    with zipfile.ZipFile(native[version] / f"{name}.fmu") as z:
        header = z.read(f"sources/{name}_variables.h").decode()
    assert all(f"VR_{v.name} = {vr}," in header for vr, v in enumerate(components.get(name).variables))


STRICT = ["-c", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wno-unused-parameter", "-Werror"]


@pytest.mark.parametrize("own_math", [False, True], ids=["libm", "portable"])
def test_the_model_files_compile_without_warnings_under_strict_flags(tmp_path, own_math):
    """ISO C99, -Wall -Wextra -Werror (less unused parameters), with the C library's math and the portable one."""
    flags = [*STRICT, "-DCRANE_OWN_MATH"] if own_math else STRICT
    for name in NAMES:
        (tmp_path / f"{name}_variables.h").write_text(variables_header(components.get(name)))
    for name in ("planner.c", "energy.c", "gust.c", "sensor.c", "component.c", "portable_math.c"):
        subprocess.run([compiler(), *flags, f"-I{tmp_path}", *(f"-I{folder}" for folder in FOLDERS),
                        str(source_path(name)), "-o", str(tmp_path / "m.o")], check=True)


# ---- TrajectoryPlanner: outputs at random parameters and times ---------------------------------------------------

def _planner_parameters(rng, i):
    m2 = rng.choice([0.0, rng.uniform(0.1, 20)])
    l1 = rng.uniform(0.2, 5)
    l2 = rng.uniform(0.1, 3)
    if m2 == 0:  # the linear model's modes coincide (a Python ZeroDivisionError) at l1 = l2: keep them apart
        l2 = l1 * rng.uniform(0.2, 0.8)
    return {"m1": rng.uniform(0.5, 20), "m2": m2, "l1": l1, "l2": l2, "g": rng.uniform(1, 25),
            "x0": rng.uniform(-3, 3), "x_d": rng.choice([rng.uniform(-3, 3), 0.0]), "t0": rng.uniform(-1, 2),
            "u_max": rng.uniform(0.1, 3), "v_max": rng.uniform(0.1, 2), "shaper": SHAPERS[i % 4]}


def _run_planner(path, version, parameters, rng, longest, ours, theirs):
    """The native planner's outputs (``ours``) and the Python model's (``theirs``) before initialisation ends (at time
    0) and after each of 40 steps of random length (1 ms or up to ``longest``)."""
    outputs = PLANNER.names("output")
    fmu, vr, _, get = open_native(path, version, parameters)
    config = PLANNER.check(parameters)
    ours.append(get([vr[n] for n in outputs]))
    theirs.append(PLANNER.output(config, (0.0,), ()))
    fmu.exitInitializationMode()
    t = 0.0
    for _ in range(40):
        h = rng.choice([1e-3, rng.uniform(1e-3, longest)])
        fmu.doStep(t, h)
        ours.append(get([vr[n] for n in outputs]))
        theirs.append(PLANNER.output(config, (t + h,), ()))
        t += h
    close(fmu)


@pytest.mark.parametrize("version", [2, 3])
def test_planner_outputs_equal_the_python_model_at_random_parameters_and_times(native, version):
    """80 parameter sets (every shaper, m2 = 0, no move) x 40 steps of random length: 22400 outputs."""
    rng = random.Random(2027)
    ours, theirs = [], []
    for i in range(80):
        parameters = _planner_parameters(rng, i)
        if i % 10 == 9:
            parameters["x_d"] = parameters["x0"]  # no move: x_ref stays at x0
        _run_planner(native[version] / "TrajectoryPlanner.fmu", version, parameters, rng, 0.6, ours, theirs)
    compare_to_python(ours, theirs)
    theirs = np.array(theirs)
    assert np.count_nonzero(theirs[:, 3]) > 1000 and np.count_nonzero(theirs[:, 2]) > 500  # moves and swing


@pytest.mark.parametrize("version", [2, 3])
def test_the_shortest_moves_outputs_equal_the_python_model_at_random_parameters_and_times(native, version):
    """The shaper ``shortest`` (the MPC's plan, mpc_axis.c's in C): 10 parameter sets (moves of up to 3 m, a random
    stretch for every other one, a swing to start from for every third, one regulation and one with no move) x 40
    steps of random length."""
    rng = random.Random(2052)
    ours, theirs = [], []
    for i in range(10):
        parameters = {**_planner_parameters(rng, i), "shaper": "shortest", "x0": rng.uniform(-1.5, 1.5),
                      "x_d": rng.uniform(-1.5, 1.5), "u_max": rng.uniform(1.0, 3.0), "v_max": rng.uniform(0.5, 2.0),
                      "stretch": 1.0 if i % 2 else rng.uniform(1.0, 1.3)}
        if i % 3 == 0:  # from a swing (a regulation when x_d = x0)
            parameters.update(theta1_0=rng.uniform(-0.2, 0.2), dtheta1_0=rng.uniform(-0.3, 0.3),
                              theta2_0=rng.uniform(-0.2, 0.2), dtheta2_0=rng.uniform(-0.3, 0.3))
        if i in (6, 9):
            parameters["x_d"] = parameters["x0"]
        _run_planner(native[version] / "TrajectoryPlanner.fmu", version, parameters, rng, 0.3, ours, theirs)
    compare_to_python(ours, theirs)
    theirs = np.array(theirs)
    assert np.count_nonzero(theirs[:, 3]) > 200 and len(set(theirs[:, 2])) > 50  # moves, swing, many held inputs


@pytest.mark.parametrize("version", [2, 3])
def test_a_plan_from_the_measured_swing_equals_the_plan_from_the_same_swing_as_parameters(native, version):
    """``plan_from = measured``: the swing read from the inputs ``theta1_now`` ... at the first step (before it, the
    outputs at time 0 from the inputs then) gives, in C and in Python, bit for bit the outputs the same swing gives as
    the parameters ``theta1_0`` ...; the inputs changed after the first step change nothing (the plan is made once).
    6 parameter sets (moves, regulations, stretches) x 40 steps of random length."""
    rng = random.Random(2063)
    outputs, measured = PLANNER.names("output"), planner.MEASURED
    ours, python, told = [], [], []
    for i in range(6):
        swing = (rng.uniform(-0.2, 0.2), rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2), rng.uniform(-0.3, 0.3))
        parameters = {**_planner_parameters(rng, i), "shaper": "shortest", "x0": rng.uniform(-1.5, 1.5),
                      "x_d": rng.uniform(-1.5, 1.5), "u_max": rng.uniform(1.0, 3.0), "v_max": rng.uniform(0.5, 2.0),
                      "stretch": 1.0 if i % 2 else rng.uniform(1.0, 1.3), "plan_from": "measured"}
        if i % 3 == 0:
            parameters["x_d"] = parameters["x0"]  # a regulation
        as_parameters = {**parameters, "plan_from": "parameters", **dict(zip(planner.START, swing))}
        fmu, vr, set_, get = open_native(native[version] / "TrajectoryPlanner.fmu", version, parameters)
        config, reference = PLANNER.check(parameters), PLANNER.check(as_parameters)
        assert config.measured is not None and reference.measured is None and reference.free is not None
        set_([vr[n] for n in measured], list(swing))
        state = PLANNER.initial_state(config)
        ours.append(get([vr[n] for n in outputs]))
        python.append(PLANNER.output(config, state, swing))
        told.append(PLANNER.output(reference, (0.0,), ()))
        fmu.exitInitializationMode()
        t, inputs = 0.0, swing
        for _ in range(40):
            h = rng.choice([1e-3, rng.uniform(1e-3, 0.3)])
            fmu.doStep(t, h)
            state = PLANNER.update(config, state, inputs, t, h)
            inputs = tuple(rng.uniform(-0.5, 0.5) for _ in measured)  # what the plant measures later: not read
            set_([vr[n] for n in measured], list(inputs))
            t += h
            ours.append(get([vr[n] for n in outputs]))
            python.append(PLANNER.output(config, state, inputs))
            told.append(PLANNER.output(reference, (t,), ()))
        close(fmu)
    assert python == told  # bit for bit
    compare_to_python(ours, told)
    told = np.array(told)
    assert np.count_nonzero(told[:, 3]) > 100 and len(set(told[:, 2])) > 30  # swing, many held inputs


@pytest.mark.parametrize("version", [2, 3])
def test_the_shaper_enumeration_is_read_back_and_changes_the_plan(native, version):
    """The shaper is an Enumeration (none 1, zv 2, zvd 3, ei 4, shortest 5): got and set as an Integer (FMI 3.0:
    Int64), not a String."""
    fmu, vr, set_, get = open_native(native[version] / "TrajectoryPlanner.fmu", version, {"x_d": 2.0})
    ref = vr["shaper"]
    get_int, set_int = (fmu.getInteger, fmu.setInteger) if version == 2 else (fmu.getInt64, fmu.setInt64)
    assert list(get_int([ref])) == [2]
    set_int([ref], [4])
    assert list(get_int([ref])) == [4]
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1.0)
    ei, zv = (PLANNER.output(PLANNER.check({"x_d": 2.0, "shaper": k}), (1.0,), ()) for k in ("ei", "zv"))
    assert list(get([vr["x_ref"], vr["theta1_ref"]])) == [ei[0], ei[3]] and ei[0] != zv[0]
    with pytest.raises(FMICallException):  # a fixed parameter once initialisation has ended
        set_int([ref], [2])
    fmu.freeInstance()
    fmu, *_ = open_native(native[version] / "TrajectoryPlanner.fmu", version)
    with pytest.raises(FMICallException):  # a String it is not
        fmu.setString([ref], ["zv"])
    fmu.freeInstance()


@pytest.mark.parametrize("value", [0, 6, -1, 2 ** 31 - 1])
def test_a_shaper_value_no_item_has_is_refused_when_set_like_the_python_fmu(fmu_dir, native, value):
    """One line naming the value and every item's value and name, from both FMUs, at the fmi2SetInteger."""
    ours = messages(native[2] / "TrajectoryPlanner.fmu", {"x_d": 2.0, "shaper": value})
    theirs = messages(fmu_dir / "TrajectoryPlanner.fmu", {"x_d": 2.0, "shaper": value})
    assert ours == theirs
    assert ours[0][-2] == "set shaper: 3"
    assert ours[1][-1] == ("fmi2SetInteger: shaper must be one of 1 (none), 2 (zv), 3 (zvd), 4 (ei), 5 (shortest), "
                           f"got {value}")


# ---- EnergyController: outputs at random inputs and parameters ---------------------------------------------------

def _energy_parameters(rng, i):
    return {"m1": rng.uniform(0.5, 20), "m2": rng.choice([0.0, rng.uniform(0.1, 20)]), "l1": rng.uniform(0.2, 5),
            "l2": rng.uniform(0.1, 3), "g": rng.uniform(1, 25), "k_c": rng.uniform(0.01, 2),
            "k_p": rng.uniform(0.01, 5), "k_d": rng.uniform(0.1, 20), "x_d": rng.uniform(-5, 5),
            "h": rng.uniform(1e-4, 0.05), "u_max": rng.uniform(0.05, 3), "v_max": (INF, rng.uniform(0.05, 2))[i % 2]}


def _random_state(rng):
    return [rng.uniform(-5, 5), rng.uniform(-3, 3), rng.uniform(-1.5, 1.5), rng.uniform(-5, 5),
            rng.uniform(-1.5, 1.5), rng.uniform(-5, 5)]


@pytest.mark.parametrize("version", [2, 3])
def test_energy_output_equals_the_python_model_at_random_inputs_and_parameters(native, version):
    """2000 points: 40 parameter sets (finite and infinite v_max) x 50 inputs; near zero too, where tanh is linear."""
    rng = random.Random(2028)
    inputs = ENERGY.names("input")
    ours, theirs, limited = [], [], 0
    for i in range(40):
        parameters = _energy_parameters(rng, i)
        fmu, vr, set_, get = open_native(native[version] / "EnergyController.fmu", version, parameters)
        config = ENERGY.check(parameters)
        for j in range(50):
            state = _random_state(rng)
            if j % 5 == 0:
                state = [v * 1e-6 for v in state]
                state[0] += parameters["x_d"]
            set_([vr[n] for n in inputs], state)
            ours.append(get([vr["u"]])[0])
            theirs.append(ENERGY.output(config, None, tuple(state))[0])
            limited += theirs[-1] != ENERGY.output(config._replace(v_max=INF), None, tuple(state))[0]
            if j == 0:
                fmu.exitInitializationMode()
        close(fmu)
    compare_to_python(ours, theirs)
    assert limited > 100  # the speed guard acts on many points


# ---- Gust and Sensor: outputs over random steps, against the Python component's output and update --------------

def _gust_parameters(rng, i):
    return {"F1_peak": rng.uniform(-50, 50), "F2_peak": rng.choice([0.0, rng.uniform(-50, 50)]),
            "start": rng.uniform(-1, 3), "duration": rng.uniform(0.01, 3)}


def _sensor_parameters(rng, i):
    sigmas = [rng.choice([0.0, rng.uniform(0, 0.5), rng.uniform(0, 1e-3)]) for _ in range(4)]
    return {**dict(zip(("sigma_x", "sigma_dx", "sigma_theta", "sigma_dtheta"), sigmas)),
            "seed": float(rng.choice([0, 1, 2 ** 32 - 1, rng.randrange(2 ** 32)])), "delay": float(i % 2)}


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("component,random_parameters", [(GUST, _gust_parameters), (SENSOR, _sensor_parameters)],
                         ids=["Gust", "Sensor"])
def test_disturbance_outputs_equal_the_python_model_over_random_steps(native, version, component, random_parameters):
    """30 parameter sets x 100 steps of random length (Gust: its pulse; Sensor: noise, seed, both delays)."""
    rng = random.Random(2029)
    n_inputs = len(component.names("input"))
    ours, theirs = outputs_beside_python(native[version] / f"{component.model_identifier}.fmu", version, component,
                                         (random_parameters(rng, i) for i in range(30)), 100,
                                         lambda rng: _random_state(rng)[:n_inputs], rng, 0.2)
    compare_to_python(ours, theirs)
    assert np.count_nonzero(np.array(theirs)) > 1000


# ---- refusals: the Python FMU's rules and messages ----------------------------------------------------------------

REFUSED = {
    "TrajectoryPlanner": [{"m1": -1.0}, {"m2": NAN}, {"l1": 0.0}, {"l2": INF}, {"g": -INF}, {"u_max": 0.0},
                          {"v_max": NAN}, {"u_max": INF}, {"v_max": INF}, {"x0": NAN}, {"x_d": INF}, {"t0": -INF},
                          {"u_max": -1.0, "shaper": "zvd", "x0": NAN},
                          {"m2": 0.0, "l1": 1.0, "l2": 1.0},  # modes coincide: Python's ZeroDivisionError
                          {"m2": 0.0, "l1": 1.0, "l2": 1.0 + 1e-15}],  # sqrt of a rounded negative: its ValueError
    "EnergyController": [{"m1": 0.0}, {"m2": -0.5}, {"l1": NAN}, {"g": INF}, {"k_c": 0.0}, {"k_p": -1.0},
                         {"k_d": INF}, {"h": NAN}, {"x_d": -INF}, {"u_max": 0.0}, {"v_max": -1.0}, {"u_max": INF},
                         {"k_c": -1.0, "u_max": INF}],
    "Gust": [{"F1_peak": NAN}, {"F2_peak": INF}, {"start": -INF}, {"duration": 0.0}, {"duration": -1.0},
             {"duration": INF}],
    "Sensor": [{"sigma_x": -1e-3}, {"sigma_dx": NAN}, {"sigma_theta": INF}, {"sigma_dtheta": -0.5},
               {"seed": -1.0}, {"seed": 1.5}, {"seed": 2.0 ** 32}, {"seed": NAN}, {"seed": INF}, {"delay": 2.0},
               {"delay": 0.5}, {"delay": NAN}],
}
CASES = [(name, settings) for name, cases in REFUSED.items() for settings in cases]


@pytest.mark.parametrize("name,settings", CASES, ids=lambda c: c if isinstance(c, str) else ",".join(
    f"{k}={v!r}" for k, v in c.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, name, settings):
    ours = messages(native[2] / f"{name}.fmu", settings)
    theirs = messages(fmu_dir / f"{name}.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("step", [NAN, -1e-3, 0.0, INF])
def test_an_unusable_step_is_the_python_fmus_error(fmu_dir, native, name, step):
    ours = messages(native[2] / f"{name}.fmu", {}, [(0.0, 1e-3), (1e-3, step)])
    theirs = messages(fmu_dir / f"{name}.fmu", {}, [(0.0, 1e-3), (1e-3, step)])
    assert ours == theirs
    assert ours[0][-2] == "step 0.001: 3"


def test_an_output_python_cannot_compute_is_the_python_fmus_error(fmu_dir, native):
    """u_max = 5e-324 passes the rules, but (E4) then divides by a = u_max / 2 = 0: Python's ZeroDivisionError."""
    ours = messages(native[2] / "EnergyController.fmu", {"u_max": 5e-324}, read=["u"])
    theirs = messages(fmu_dir / "EnergyController.fmu", {"u_max": 5e-324}, read=["u"])
    assert ours == theirs == (["get: 3", "end"], ["fmi2GetReal: ZeroDivisionError: float division by zero"])


# ---- FMU state ----------------------------------------------------------------------------------------------------

STATEFUL = {  # component: parameters, and whether its outputs take inputs (the Sensor's)
    "TrajectoryPlanner": {"x_d": 2.0, "shaper": "zvd"},
    "Gust": {"start": 1.6, "duration": 0.8},
    "Sensor": {"seed": 7.0, "delay": 1.0},
}


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", STATEFUL)
def test_fmu_state_saved_serialised_and_restored_repeats_the_steps_exactly(native, name, version):
    """The planner's and the gust's state is their time, the sensor's its sample count and held sample."""
    fmu, vr, set_, get = open_native(native[version] / f"{name}.fmu", version, STATEFUL[name])
    fmu.exitInitializationMode()
    component = components.get(name)
    outputs, inputs = [vr[n] for n in component.names("output")], [vr[n] for n in component.names("input")]

    def steps(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            if inputs:
                set_(inputs, [np.sin(k * 0.01 + i) for i in range(len(inputs))])
            fmu.doStep(k * 1e-2, 1e-2)
            rows.append(get(outputs))
        return rows

    steps(0, 150)
    first, again, third = steps_after_restore(fmu, version, steps, 150, 100)
    close(fmu)
    assert first == again == third
    assert len({round(r[-1], 6) for r in first}) > 30  # the outputs move over those steps


# ---- closed loops and whole runs: native against Python FMUs, through our master ---------------------------------

def _is_native(path):
    """Whether an FMU is one of the native ones (a generated variable header among its sources)."""
    with zipfile.ZipFile(path) as z:
        return any(n.startswith("sources/") and n.endswith("_variables.h") for n in z.namelist())


def _runs_agree(system, native_folder, python_fmus, exact=LINUX):
    """Every recorded output of both runs within 1e-9 over the whole run (``exact``: equal); the recorded run."""
    ours, theirs = run(system, native_folder).columns(), run(system, python_fmus).columns()
    assert list(ours) == list(theirs)
    assert len(ours["time"]) == len(theirs["time"]) == round(system.stop_time / system.step) + 1
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    assert worst <= 1e-9
    if exact:
        assert worst == 0.0
    return theirs


@pytest.mark.parametrize("version", [2, 3])
def test_the_energy_system_on_native_fmus_equals_the_python_fmus(fmu_dir, native, version):
    """20 s at 1 ms: the native plant and EnergyController against both Python FMUs."""
    theirs = _runs_agree(systems.get("energy"), native[version], python_folder(fmu_dir, version))
    assert np.max(np.abs(theirs["controller.u"])) > 0.1  # the controller does act


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("system", ["transport", "hoist-transport"])
def test_the_transport_systems_with_the_native_planner_equal_the_python_fmus(fmu_dir, native, version, system):
    """10 s of the ZV move, 12 s of the ZVD move with a second planner as the hoist, both at 1 ms and tracked by the
    LQR (Python or native, whichever build/native holds; bit for bit on Linux with the Python LQR)."""
    lqr_native = _is_native(native[version] / "LqrController.fmu")  # its design may differ in a last bit
    theirs = _runs_agree(systems.bind(systems.get(system)), native[version], python_folder(fmu_dir, version),
                         exact=LINUX and not lqr_native)
    assert abs(theirs["planner.x_ref"][-1] - 2.0) < 1e-12 and np.max(np.abs(theirs["planner.theta1_ref"])) > 1e-3


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("shaper", SHAPERS)
def test_the_planner_alone_over_its_run_equals_the_python_fmu(fmu_dir, native, version, shaper):
    """A 3 m move back (x0 = 1, x_d = -2) from t0 = 0.25 s, 15 s at 1 ms, each shaper."""
    system = System(f"planner-{shaper}", {"planner": "TrajectoryPlanner"},
                    parameters={"planner": {"x0": 1.0, "x_d": -2.0, "t0": 0.25, "shaper": shaper}}, stop_time=15.0)
    theirs = _runs_agree(system, native[version], python_folder(fmu_dir, version))
    assert theirs["planner.x_ref"][-1] == -2.0 and np.min(theirs["planner.dx_ref"]) < -0.5


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("scenario", ["S4", "S5"])
def test_the_scoreboards_gust_and_sensor_cases_on_native_fmus_equal_the_python_fmus(fmu_dir, native, version,
                                                                                     scenario):
    """The EnergyController's S4 (a gust on the payload) and S5 (noisy, one step late) runs: all native vs Python."""
    contender = Contender("EnergyController", "EnergyController", ENERGY.names("input"), ENERGY.names("parameter"))
    (_, system, step, stop_time, _, _), = systems_for(contender, scenario)
    assert (step, stop_time) == (system.step, system.stop_time)
    theirs = _runs_agree(system, native[version], python_folder(fmu_dir, version))
    if scenario == "S4":
        assert np.max(theirs["gust.F2"]) == pytest.approx(10.0, rel=1e-5)
    else:
        assert np.max(np.abs(theirs["sensor.x_m"] - theirs["plant.x"])) > 1e-4


# ---- a C host with no Python, on Linux and under Wine (the portable math itself: test_portable_math.py) ----------

HOST_CASES = {  # component: (parameters and inputs set by the host, steps of 1 ms)
    "TrajectoryPlanner": ({"x_d": 2.0, "t0": 0.1}, 5000),
    "Gust": ({"F1_peak": 3.0, "start": 0.2, "duration": 0.3}, 1000),
    "EnergyController": ({"x": 0.3, "dx": -0.2, "theta1": 0.1, "dtheta1": 0.4, "theta2": -0.2, "dtheta2": 0.5}, 3),
    "Sensor": ({"x": 0.3, "theta2": -0.2, "sigma_dx": 0.0}, 1000),
    "Wind": ({"dx": 0.3, "theta1": 0.1, "dtheta1": -0.4, "theta2": -0.2, "dtheta2": 0.5, "seed": 7.0}, 1000),
    "CranePlant3D": ({"theta1y_0": 0.3, "dtheta2x_0": 0.5, "ux": 0.4, "uy": -0.3, "F2y": 2.0, "c1": 0.1, "hoist": 0.1,
                      "tau_y": 0.1}, 2000),
}


def _python_rows(component, settings, steps, h):
    """The rows the host prints, ``[t, outputs]`` after k steps from t = (k - 1) h, by the Python model."""
    parameters = {k: v for k, v in settings.items() if k in component.names("parameter")}
    inputs = tuple(settings.get(n, v.start) for n, v in ((v.name, v) for v in component.variables
                                                         if v.causality == "input"))
    config = component.check(parameters)
    state = component.initial_state(config) if component.stateful else None
    rows = []
    for k in range(steps + 1):
        rows.append([k * h, *component.output(config, state, inputs)])
        if component.stateful:
            state = component.update(config, state, inputs, k * h, h)
    return np.array(rows)


def _host_arguments(path, settings, steps, h):
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    enums = enumerations(md)
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    return [md.coSimulation.modelIdentifier, md.guid, steps, h,
            *[f"{vr[k]}i={item_value(enums[k], v)}" if k in enums else f"{vr[k]}s={v}" if isinstance(v, str) else
              f"{vr[k]}={v!r}" for k, v in settings.items()], *outputs]


@pytest.fixture(scope="module")
def unpacked(native, tmp_path_factory):
    """``{name: folder}`` of the native FMI 2.0 FMUs of HOST_CASES, unzipped."""
    folders = {}
    for name in HOST_CASES:
        folders[name] = tmp_path_factory.mktemp(name)
        with zipfile.ZipFile(native[2] / f"{name}.fmu") as z:
            z.extractall(folders[name])
    return folders


def _run_host(command, *args, cwd=None, env=None):
    done = subprocess.run([*command, *map(str, args)], capture_output=True, text=True, cwd=cwd, env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return np.array([[float(x) for x in line.split(",")] for line in done.stdout.replace("\r", "").splitlines()])


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    host = tmp_path_factory.mktemp("host") / "host"
    subprocess.run([compiler(), "-O2", "-Wall", "-Werror", "-ffp-contract=off", f"-I{fmi_headers()}", str(HOST), "-o",
                    str(host), "-ldl", "-lpthread", "-lm"], check=True)
    return host


@pytest.mark.parametrize("name", HOST_CASES)
def test_the_c_host_without_python_gives_the_python_models_outputs(native, unpacked, host, name):
    """host.c's ``outputs`` (no Python in the process): the Python model's rows bit for bit (glibc)."""
    settings, steps = HOST_CASES[name]
    _, guid, *rest = _host_arguments(native[2] / f"{name}.fmu", settings, steps, 1e-3)
    rows = _run_host([str(host), "outputs"], unpacked[name] / "binaries" / "linux64" / f"{name}.so", guid, *rest,
                     env=CLEAN_ENV)
    expected = _python_rows(components.get(name), settings, steps, 1e-3)
    assert rows.shape == expected.shape and np.count_nonzero(expected[:, 1:]) > steps / 4
    assert np.array_equal(rows.view(np.int64), expected.view(np.int64))


@pytest.fixture(scope="module")
def wine(unpacked, windows_host, wine_env, tmp_path_factory):
    """``(wine command, folder with host.exe and the DLLs of HOST_CASES, environment)``."""
    folder = tmp_path_factory.mktemp("windows")
    shutil.copy(windows_host, folder)
    for name, unzipped in unpacked.items():
        shutil.copy(unzipped / "binaries" / "win64" / f"{name}.dll", folder)
    return ["wine", str(folder / "host.exe")], folder, wine_env


OTHER_SHAPERS = [s for s in SHAPERS if s != PLANNER.defaults()["shaper"]]


@pytest.mark.parametrize("shaper", OTHER_SHAPERS)
def test_the_planners_other_shapers_in_the_c_host_and_under_wine_give_the_python_models_outputs(native, unpacked, host,
                                                                                              wine, shaper):
    """The host sets the Enumeration ``shaper`` (fmi2SetInteger): Linux's rows bit for bit, the Windows DLL's to 1e-12
    relative."""
    command, folder, env = wine
    settings = {**HOST_CASES["TrajectoryPlanner"][0], "shaper": shaper}
    _, guid, *rest = _host_arguments(native[2] / "TrajectoryPlanner.fmu", settings, 5000, 1e-3)
    expected = _python_rows(PLANNER, settings, 5000, 1e-3)
    default = _python_rows(PLANNER, HOST_CASES["TrajectoryPlanner"][0], 5000, 1e-3)
    assert not np.array_equal(expected, default), "the shaper changes the plan"
    linux = _run_host([str(host), "outputs"], unpacked["TrajectoryPlanner"] / "binaries" / "linux64" /
                      "TrajectoryPlanner.so", guid, *rest, env=CLEAN_ENV)
    assert np.array_equal(linux.view(np.int64), expected.view(np.int64))
    windows = _run_host([*command, "outputs"], "TrajectoryPlanner.dll", guid, *rest, cwd=folder, env=env)
    assert windows.shape == expected.shape
    assert np.max(np.abs(windows - expected) / np.maximum(np.abs(expected), 1.0)) <= 1e-12


@pytest.mark.parametrize("name", HOST_CASES)
def test_the_windows_dlls_under_wine_give_the_python_models_outputs(native, wine, name):
    """The Windows build (portable sin, cos, tanh, log): the Python model's rows to 1e-12 relative."""
    command, folder, env = wine
    settings, steps = HOST_CASES[name]
    _, guid, *rest = _host_arguments(native[2] / f"{name}.fmu", settings, steps, 1e-3)
    rows = _run_host([*command, "outputs"], f"{name}.dll", guid, *rest, cwd=folder, env=env)
    expected = _python_rows(components.get(name), settings, steps, 1e-3)
    assert rows.shape == expected.shape
    assert np.max(np.abs(rows - expected) / np.maximum(np.abs(expected), 1.0)) <= 1e-12


@pytest.mark.parametrize("name", HOST_CASES)
def test_the_same_math_source_on_linux_gives_the_windows_bits(native, unpacked, wine, host, name, tmp_path):
    """The FMU's sources compiled on Linux with CRANE_OWN_MATH (as its buildDescription says): Wine's rows exactly."""
    command, folder, env = wine
    settings, steps = HOST_CASES[name]
    _, guid, *rest = _host_arguments(native[2] / f"{name}.fmu", settings, steps, 1e-3)
    sources = unpacked[name] / "sources"
    library = tmp_path / f"{name}.so"
    subprocess.run([compiler(), "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-ffp-contract=off", "-DCRANE_OWN_MATH",
                    f"-I{sources}", f"-I{fmi_headers()}", *map(str, sorted(sources.glob("*.c"))), "-o", str(library),
                    "-lm"],  # sqrt: the C library's also with the portable math
                   check=True)
    linux = _run_host([str(host), "outputs"], library, guid, *rest)
    windows = _run_host([*command, "outputs"], f"{name}.dll", guid, *rest, cwd=folder, env=env)
    assert np.array_equal(linux.view(np.int64), windows.view(np.int64))


@pytest.mark.parametrize("version", [2, 3])
def test_the_planners_source_fmu_compiles_with_fmpy_and_runs(native, version, tmp_path, monkeypatch):
    """fmpy's build_platform_binary (CMake) on the sources alone; fmpy simulates its move like the built FMU's."""
    from fmpy.build import build_platform_binary

    if shutil.which("cmake") is None and not (Path(sys.executable).parent / "cmake").exists():
        pytest.skip("no cmake")
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(native[version] / "TrajectoryPlanner.fmu") as z:
        z.extractall(folder)
    shutil.rmtree(folder / "binaries")
    monkeypatch.setenv("PATH", str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"])  # the venv's cmake
    (tmp_path / "cmake").mkdir()
    build_platform_binary(folder, build_dir=tmp_path / "cmake")
    ei = enumerations(read_model_description(str(native[version] / "TrajectoryPlanner.fmu")))["shaper"]["ei"]
    settings = dict(start_values={"x_d": 2.0, "shaper": ei}, output_interval=1e-3, stop_time=10.0)  # fmpy: a value
    result = fmpy.simulate_fmu(str(folder), **settings)
    reference = fmpy.simulate_fmu(str(native[version] / "TrajectoryPlanner.fmu"), **settings)
    assert result["x_ref"][-1] == 2.0 and np.max(result["dx_ref"]) > 0.5
    # FMI 2.0 sources use the C library's libm (here glibc: the same bits); FMI 3.0 ones the portable math
    for name in ("x_ref", "theta1_ref", "theta2_ref"):
        assert np.max(np.abs(result[name] - reference[name])) <= 1e-12
