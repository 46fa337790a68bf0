"""The native (C) CraneSensor, StateEstimator and HardHitController FMUs against their specification.

Built by the session's ``fmu_dir`` fixture into ``build/native`` beside the Python FMUs. The Python
models (crane_fmu/model/disturbances.py's CraneSensor, estimator.py, hard_hit.py) are the
specification: on Linux (glibc's libm in both, the same operations in the same order; the filter's
and the LQR's designs by linalg.c as by linalg.py) the native outputs are the Python ones bit for bit.
Their systems (``lqg``, ``lqg-transport``, ``hard-hit``) as one native FMU each are held to our master
over the native component FMUs in test_one_fmu.py (fmpy, the C host without Python, Wine); here to our
master over the Python FMUs.
"""

import math
import random
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu
from native_fmus import (
    close,
    compare_to_python,
    compiler,
    messages,
    open_native,
    outputs_beside_python,
    python_folder,
    steps_after_restore,
)

from crane_fmu import components, systems
from crane_fmu.build_scripts.native import FOLDERS, source_path, variables_header
from crane_fmu.build_scripts.one_fmu import one_fmu_name, plan
from crane_fmu.cosim import run
from crane_fmu.model import hard_hit

SENSOR, ESTIMATOR, HARD_HIT = (components.get(n) for n in ("CraneSensor", "StateEstimator", "HardHitController"))
NAMES = ("CraneSensor", "StateEstimator", "HardHitController")
SYSTEMS = ("lqg", "lqg-transport", "hard-hit")
LINUX = sys.platform.startswith("linux")  # glibc's libm in both models: the same bits
INF, NAN = float("inf"), float("nan")


# ---- one source: the Python FMU's variables; strict C --------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", NAMES)
def test_native_model_description_has_the_python_fmus_variables(fmu_dir, native, name, version):
    """Names, value references, causalities, start values, units, descriptions; fmpy's validation is clean."""
    def variables(path):
        return [(v.name, v.valueReference, v.causality, v.variability, v.initial, v.start, v.unit, v.description)
                for v in read_model_description(str(path)).modelVariables]

    assert variables(native[version] / f"{name}.fmu") == variables(python_folder(fmu_dir, version) / f"{name}.fmu")
    assert validate_fmu(str(native[version] / f"{name}.fmu")) == []


STRICT = ["-c", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wno-unused-parameter", "-Werror"]


@pytest.mark.parametrize("own_math", [False, True], ids=["libm", "portable"])
def test_the_model_files_compile_without_warnings_under_strict_flags(tmp_path, own_math):
    """ISO C99, -Wall -Wextra -Werror (less unused parameters), with the C library's math and the portable one."""
    flags = [*STRICT, "-DCRANE_OWN_MATH"] if own_math else STRICT
    for name in NAMES:
        (tmp_path / f"{name}_variables.h").write_text(variables_header(components.get(name)))
    for name in ("crane_sensor.c", "estimator.c", "hard_hit.c", "lqr_design.c"):
        subprocess.run([compiler(), *flags, f"-I{tmp_path}", *(f"-I{folder}" for folder in FOLDERS),
                        str(source_path(name)), "-o", str(tmp_path / "m.o")], check=True)


# ---- stateful components over random steps: the Python component's output and update -----------------------------

def _sensor_parameters(rng, i):
    sigmas = [rng.choice([0.0, rng.uniform(0, 0.5), rng.uniform(0, 1e-3)]) for _ in range(3)]
    return {**dict(zip(("sigma_x", "sigma_theta1", "sigma_theta2"), sigmas)),
            "seed": float(rng.choice([0, 1, 2 ** 32 - 1, rng.randrange(2 ** 32)])), "delay": float((0, 1, 2, 7)[i % 4])}


def _estimator_parameters(rng, i):
    return {"m1": rng.uniform(0.5, 20), "m2": rng.uniform(0.1, 20), "l1": rng.uniform(0.2, 5),
            "l2": rng.uniform(0.1, 3), "g": rng.uniform(1, 25), "h": 10 ** rng.uniform(-4, -1.5),
            "sigma_x": 10 ** rng.uniform(-4, -1), "sigma_theta": 10 ** rng.uniform(-4, -1),
            "sigma_u": 10 ** rng.uniform(-2, 1), "sigma_swing": 10 ** rng.uniform(-1, 1.5),
            "camera": float(i % 2), "delay": float((0, 1, 3)[i % 3]),
            "sigma_force": (0.0, 10 ** rng.uniform(-1, 2.5))[(i // 2) % 2]}  # the force's state off and on


def _random_inputs(rng, n):
    return [rng.uniform(-2, 2) for _ in range(n)]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("component,random_parameters", [(SENSOR, _sensor_parameters),
                                                         (ESTIMATOR, _estimator_parameters)],
                         ids=["CraneSensor", "StateEstimator"])
def test_outputs_equal_the_python_model_over_random_steps(native, version, component, random_parameters):
    """12 parameter sets (delays 0 to 7 steps, a camera or none) x 60 steps of random length and inputs."""
    rng = random.Random(2036)
    n_inputs, outputs = len(component.names("input")), component.names("output")
    ours, theirs = outputs_beside_python(native[version] / f"{component.model_identifier}.fmu", version, component,
                                         (random_parameters(rng, i) for i in range(12)), 60,
                                         lambda rng: _random_inputs(rng, n_inputs), rng, 0.2)
    compare_to_python(ours, theirs)
    assert np.count_nonzero(np.array(theirs)) > len(theirs) * len(outputs) / 2


def _hard_hit_parameters(rng, i):
    p = {"m1": rng.uniform(0.5, 20), "m2": rng.choice([0.0, rng.uniform(0.1, 20)]), "l1": rng.uniform(0.2, 5),
         "l2": rng.uniform(0.1, 3), "g": rng.uniform(1, 25), "r": 10 ** rng.uniform(-3, 0),
         "r_far": 10 ** rng.uniform(-2, 1), "q_x_far": 10 ** rng.uniform(-1, 2), "h": 10 ** rng.uniform(-4, -1.5),
         "x_d": rng.uniform(-3, 3), "u_max": (INF, rng.uniform(0.5, 3))[i % 2],
         "v_max": (INF, rng.uniform(0.3, 2))[i % 2]}
    p["theta_near"] = rng.uniform(0.02, 0.5)
    p["theta_far"] = rng.uniform(p["theta_near"] + 0.01, 1.5)
    return p


@pytest.mark.parametrize("version", [2, 3])
def test_hard_hit_output_equals_the_python_model_at_random_inputs_and_parameters(native, version):
    """20 parameter sets (m2 = 0 too, limits on and off) x 40 inputs: near rest, far out and between (the blend)."""
    rng = random.Random(2037)
    inputs = HARD_HIT.names("input")
    ours, theirs, weights = [], [], []
    for i in range(20):
        parameters = _hard_hit_parameters(rng, i)
        fmu, vr, set_, get = open_native(native[version] / "HardHitController.fmu", version, parameters)
        config = HARD_HIT.check(parameters)
        for j in range(40):
            scale = (1e-3, 0.3, 1.0)[j % 3]
            values = [v * scale for v in _random_inputs(rng, len(inputs))]
            set_([vr[n] for n in inputs], values)
            ours.append(get([vr["u"]])[0])
            theirs.append(HARD_HIT.output(config, None, tuple(values))[0])
            weights.append(hard_hit.blend(config, values[:6]))
            if j == 0:
                fmu.exitInitializationMode()
        close(fmu)
    compare_to_python(ours, theirs)
    weights = np.array(weights)
    assert min(np.count_nonzero(weights == 0), np.count_nonzero(weights == 1),
               np.count_nonzero((weights > 0) & (weights < 1))) > 20  # each design alone, and blended


# ---- refusals: the Python FMU's rules and messages ----------------------------------------------------------------

REFUSED = {
    "CraneSensor": [{"sigma_x": -1e-3}, {"sigma_theta1": NAN}, {"sigma_theta2": INF}, {"seed": -1.0},
                    {"seed": 1.5}, {"seed": 2.0 ** 32}, {"delay": 101.0}, {"delay": 0.5}, {"delay": NAN},
                    {"delay": -1.0}],
    "StateEstimator": [{"m1": -1.0}, {"l2": INF}, {"h": 0.0}, {"sigma_x": 0.0}, {"sigma_theta": NAN},
                       {"sigma_u": -1.0}, {"sigma_swing": INF}, {"camera": 0.5}, {"camera": NAN}, {"delay": 1.5},
                       {"delay": 101.0}, {"delay": -INF}, {"h": -1.0, "camera": 2.0}],
    "HardHitController": [{"m2": -1.0}, {"q_x": -1.0}, {"q_dtheta2": INF}, {"q_x_far": NAN}, {"r": 0.0},
                          {"r_far": -1.0}, {"h": INF}, {"theta_near": 0.0}, {"theta_far": 0.1},
                          {"theta_far": math.pi / 2}, {"theta_far": NAN}, {"x_d": INF}, {"u_max": 0.0},
                          {"v_max": NAN}],
}
CASES = [(name, settings) for name, cases in REFUSED.items() for settings in cases]


@pytest.mark.parametrize("name,settings", CASES, ids=lambda c: c if isinstance(c, str) else ",".join(
    f"{k}={v!r}" for k, v in c.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, name, settings):
    ours = messages(native[2] / f"{name}.fmu", settings)
    theirs = messages(fmu_dir / f"{name}.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


def test_a_blend_python_cannot_compute_is_the_python_fmus_error(fmu_dir, native):
    """theta_far one ulp above theta_near passes the rules, but both energies are equal: the blend divides by 0."""
    settings = {"theta_near": 0.2, "theta_far": math.nextafter(0.2, 1.0)}
    ours = messages(native[2] / "HardHitController.fmu", settings, read=["u"])
    theirs = messages(fmu_dir / "HardHitController.fmu", settings, read=["u"])
    assert ours == theirs == (["get: 3", "end"], ["fmi2GetReal: ZeroDivisionError: float division by zero"])


# ---- FMU state ----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name,parameters", [("CraneSensor", {"seed": 7.0, "delay": 3.0}),
                                             ("StateEstimator", {"delay": 2.0, "camera": 1.0})])
def test_fmu_state_saved_serialised_and_restored_repeats_the_steps_exactly(native, name, parameters, version):
    """The sensor's state is its sample count and the samples it holds, the estimator's its prediction and inputs."""
    fmu, vr, set_, get = open_native(native[version] / f"{name}.fmu", version, parameters)
    fmu.exitInitializationMode()
    component = components.get(name)
    outputs, inputs = [vr[n] for n in component.names("output")], [vr[n] for n in component.names("input")]

    def steps(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            set_(inputs, [np.sin(k * 0.01 + i) for i in range(len(inputs))])
            fmu.doStep(k * 1e-2, 1e-2)
            rows.append(get(outputs))
        return rows

    steps(0, 50)
    first, again, third = steps_after_restore(fmu, version, steps, 50, 50)
    close(fmu)
    assert first == again == third
    assert len({round(r[0], 6) for r in first}) > 30  # the outputs move over those steps


# ---- the systems: native component FMUs and the one native FMU against the Python FMUs ----------------------------

def _short(name):
    return replace(systems.get(name), stop_time=4.0)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", SYSTEMS)
def test_the_system_on_native_fmus_and_as_one_native_fmu_equals_the_python_fmus(fmu_dir, native, version, name):
    """4 s at 1 ms through our master: the native component FMUs, and the one-FMU in fmpy, give the run on the Python
    FMUs (1e-9; bit for bit on Linux)."""
    system = _short(name)
    theirs = run(system, python_folder(fmu_dir, version)).columns()
    ours = run(system, native[version]).columns()
    assert list(ours) == list(theirs) and len(theirs["time"]) == 4001
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    links = plan(system).links
    outputs = {v.name: "{}.{}".format(*links[v.name][0]) for v in plan(system).variables if v.causality == "output"}
    one = simulate_fmu(str(native[version] / f"{one_fmu_name(name)}.fmu"), stop_time=system.stop_time,
                       step_size=system.step, output_interval=system.step, output=list(outputs))
    worst_one = max(float(np.max(np.abs(one[own] - theirs[column]))) for own, column in outputs.items())
    assert worst <= 1e-9 and worst_one <= 1e-9
    if LINUX:
        assert worst == worst_one == 0.0
    assert np.max(np.abs(theirs["controller.u"])) > 0.5  # the controller acts
    if "sensor.x_meas" in theirs:  # and the estimator sees noise
        assert np.max(np.abs(theirs["sensor.x_meas"] - theirs["plant.x"])) > 1e-3
