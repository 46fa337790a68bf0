"""The native (C) BacksteppingController FMU against its specification, the Python controller.

Built by the session's ``fmu_dir`` fixture into ``build/native`` beside the Python FMUs. The
Python model (crane_fmu/model/backstepping.py with limits.limited) is the specification.
"""

import random
import sys

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from native_fmus import close, messages, open_native

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import fmi3_dir
from crane_fmu.cosim import run

CONTROLLER = components.get("BacksteppingController")
NAME = "BacksteppingController"
INF, NAN = float("inf"), float("nan")


# ---- outputs at random inputs and parameters ----------------------------------------------------------------------

def _random_parameters(rng, i):
    p = {"m1": rng.uniform(0.5, 20), "m2": rng.choice([0.0, rng.uniform(0.1, 20)]), "l1": rng.uniform(0.2, 5),
         "l2": rng.uniform(0.1, 3), "g": rng.uniform(1, 25)}
    for name in ("K1_x", "K1_theta1", "K1_theta2", "K2_x", "K2_theta1", "K2_theta2"):
        p[name] = rng.uniform(-2, 10)
    p.update(x_d=rng.uniform(-5, 5), theta1_d=rng.uniform(-0.3, 0.3), theta2_d=rng.uniform(-0.3, 0.3))
    p.update(w_x=rng.uniform(0.01, 5), w_theta1=rng.choice([0.0, rng.uniform(0, 5)]),
             w_theta2=rng.choice([0.0, rng.uniform(0, 5)]))
    p["b3_form"] = ("derived", "printed")[i % 2]
    p["u_max"] = (INF, rng.uniform(0.05, 3))[(i // 2) % 2]
    p["v_max"] = (INF, rng.uniform(0.05, 2))[(i // 4) % 2]
    p["h"] = rng.uniform(1e-4, 0.05)
    return p


def _random_inputs(rng):
    return {"x": rng.uniform(-5, 5), "dx": rng.uniform(-3, 3), "theta1": rng.uniform(-1.5, 1.5),
            "dtheta1": rng.uniform(-5, 5), "theta2": rng.uniform(-1.5, 1.5), "dtheta2": rng.uniform(-5, 5)}


def _python_u(parameters, inputs):
    config = CONTROLLER.check(parameters)
    return CONTROLLER.output(config, None, tuple(inputs[n] for n in CONTROLLER.names("input")))[0]


@pytest.mark.parametrize("version", [2, 3])
def test_native_outputs_equal_the_python_model_at_random_inputs_and_parameters(native, version):
    """2000 points: 40 parameter sets (both b3 forms, row weights, finite and infinite limits) x 50 inputs each."""
    rng = random.Random(27)
    ours, theirs, limited = [], [], 0
    for i in range(40):
        parameters = _random_parameters(rng, i)
        fmu, vr, set_, get = open_native(native[version] / f"{NAME}.fmu", version, parameters)
        fmu.exitInitializationMode()
        for _ in range(50):
            inputs = _random_inputs(rng)
            set_([vr[k] for k in inputs], list(inputs.values()))
            ours.append(get([vr["u"]])[0])
            theirs.append(_python_u(parameters, inputs))
            config = CONTROLLER.check(parameters)
            raw = config[3](tuple(inputs.values()))
            limited += raw != theirs[-1]
        close(fmu)
    ours, theirs = np.array(ours), np.array(theirs)
    assert len(ours) == 2000 and np.all(np.isfinite(theirs))
    assert limited > 200  # the limits do act on many points
    scale = np.maximum(np.abs(theirs), 1.0)
    assert np.max(np.abs(ours - theirs) / scale) <= 1e-12
    if sys.platform.startswith("linux"):  # glibc's libm in both, the same operations: the same bits
        assert np.array_equal(ours, theirs)


def test_the_b3_form_string_is_read_back_and_changes_the_law(native):
    fmu, vr, set_, get = open_native(native[2] / f"{NAME}.fmu", 2)
    assert fmu.getString([vr["b3_form"]]) == [b"derived"]
    set_([vr[n] for n in ("theta1", "dtheta2")], [0.2, -0.4])
    derived = get([vr["u"]])[0]
    fmu.setString([vr["b3_form"]], ["printed"])
    assert fmu.getString([vr["b3_form"]]) == [b"printed"]
    printed = get([vr["u"]])[0]
    assert derived != printed
    values = {**CONTROLLER.defaults(), "b3_form": "printed"}
    assert printed == _python_u(values, {**dict.fromkeys(CONTROLLER.names("input"), 0.0), "theta1": 0.2,
                                         "dtheta2": -0.4})
    fmu.exitInitializationMode()
    with pytest.raises(FMICallException):  # a fixed parameter once initialisation has ended
        fmu.setString([vr["b3_form"]], ["derived"])
    fmu.freeInstance()


# ---- refusals: the Python FMU's rules and messages ----------------------------------------------------------------

REFUSED = [{"h": 0.0}, {"h": INF}, {"h": NAN}, {"u_max": 0.0}, {"u_max": -INF}, {"v_max": NAN}, {"m1": -1.0},
           {"m2": -0.5}, {"l1": NAN}, {"l2": INF}, {"g": 0.0}, {"K1_x": INF}, {"K2_theta1": NAN},
           {"K1_theta2": -INF}, {"x_d": INF}, {"theta2_d": NAN}, {"w_x": 0.0}, {"w_x": -1.0}, {"w_theta1": -0.5},
           {"w_theta2": INF}, {"b3_form": "sideways"}, {"b3_form": ""}, {"b3_form": "Derived"},
           {"b3_form": "it's"}, {"b3_form": 'say "no"\n\t\\'}, {"h": -1.0, "m1": -1.0, "b3_form": "x"}]


@pytest.mark.parametrize("settings", REFUSED, ids=lambda s: ",".join(f"{k}={v!r}" for k, v in s.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, settings):
    ours = messages(native[2] / f"{NAME}.fmu", settings)
    theirs = messages(fmu_dir / f"{NAME}.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


@pytest.mark.parametrize("step", [NAN, -1e-3, 0.0, INF])
def test_an_unusable_step_is_the_python_fmus_error(fmu_dir, native, step):
    ours = messages(native[2] / f"{NAME}.fmu", {}, [(0.0, 1e-3), (1e-3, step)])
    theirs = messages(fmu_dir / f"{NAME}.fmu", {}, [(0.0, 1e-3), (1e-3, step)])
    assert ours == theirs
    assert ours[0][-2] == "step 0.001: 3"


# ---- the paper system on both native FMUs -----------------------------------------------------------------------

def test_the_paper_system_on_both_native_fmus_equals_the_python_pair(fmu_dir, native):
    """20 s at 1 ms through our master: every output of both instances within 1e-9 (glibc: 0)."""
    system = systems.get("paper")
    ours, theirs = run(system, native[2]).columns(), run(system, fmu_dir).columns()
    assert list(ours) == list(theirs)
    assert len(ours["time"]) == len(theirs["time"]) == 20_001
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    assert worst <= 1e-9
    if sys.platform.startswith("linux"):
        assert worst == 0.0
    assert np.max(np.abs(theirs["controller.u"])) > 0.1  # the controller does act


@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_simulates_the_native_pair_like_the_python_pair(fmu_dir, native, version):
    """The paper system's plant and controller in fmpy (its own master), native against Python: 1e-9 (glibc: 0)."""
    results = {}
    for label, folder in (("native", native[version]), ("python", fmu_dir if version == 2 else fmi3_dir(fmu_dir))):
        results[label] = _fmpy_pair(folder, version)
    ours, theirs = results["native"], results["python"]
    assert ours.shape == theirs.shape == (5001, 7)
    assert np.max(np.abs(ours - theirs)) <= 1e-9
    assert np.max(np.abs(theirs[:, 6])) > 0.1


def _fmpy_pair(folder, version):
    """5 s of the plant and the controller, Gauss-Seidel by hand in fmpy: the state and u at every step."""
    plant, pvr, pset, pget = open_native(folder / "CranePlant.fmu", version, instance_name="CranePlant")
    ctrl, cvr, cset, cget = open_native(folder / f"{NAME}.fmu", version, instance_name=NAME)
    states = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
    cset([cvr["x_d"]], [1.0])
    plant.exitInitializationMode()
    ctrl.exitInitializationMode()
    p_out, c_in = [pvr[n] for n in states], [cvr[n] for n in states]
    rows, h = [], 1e-3
    for k in range(5001):
        state = pget(p_out)
        cset(c_in, state)
        u = cget([cvr["u"]])[0]
        rows.append([*state, u])
        if k == 5000:
            break
        pset([pvr["u"]], [u])
        plant.doStep(k * h, h)
        ctrl.doStep(k * h, h)
    for fmu in (plant, ctrl):
        close(fmu)
    return np.array(rows)

