"""The native (C) LqrController FMU against its specification, the Python controller.

Built by the session's ``fmu_dir`` fixture into ``build/native`` beside the Python FMUs. The
Python model (crane_fmu/model/lqr.py with linalg.py and limits.limited) is the specification:
the design inside the native FMU (ZOH, Riccati doubling, gains, the schedule over l1) repeats its
operations in its order, so on Linux (glibc's libm, as CPython's) it gives the same bits.
"""

import ctypes
import functools
import random
import sys

import numpy as np
import pytest
from native_fmus import close, messages, open_native

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import fmi3_dir
from crane_fmu.cosim import run
from crane_fmu.model import lqr
from crane_fmu.model.tables import STATE

CONTROLLER = components.get("LqrController")
NAME = "LqrController"
INF, NAN = float("inf"), float("nan")
LINUX = sys.platform.startswith("linux")  # glibc's libm in both, the same operations: the same bits


# ---- random parameters and inputs -------------------------------------------------------------------------------

def _random_design(rng, scheduled):
    """The plant model, weights (some zero), r and h; with a schedule over a random l1 range."""
    p = {"m1": rng.uniform(0.5, 20), "m2": rng.choice([0.0, rng.uniform(0.1, 20)]), "l1": rng.uniform(0.2, 5),
         "l2": rng.uniform(0.1, 3), "g": rng.uniform(1, 25), "r": 10 ** rng.uniform(-3, 1),
         "h": 10 ** rng.uniform(-4, -1)}
    for name in lqr.WEIGHTS:
        p[name] = rng.choice([0.0, 10 ** rng.uniform(-2, 3)])
    p["q_x"] = 10 ** rng.uniform(-1, 3)  # x weighted: the pair stays detectable
    if scheduled:
        p["l1_low"], p["l1_high"] = sorted((rng.uniform(0.2, 5), rng.uniform(0.2, 5)))
    return p


@functools.cache
def _python_config(items):
    return CONTROLLER.check(dict(items))


def _config(parameters):
    return _python_config(tuple(sorted(parameters.items())))


# ---- (a) the design: gains, and the schedule's ------------------------------------------------------------------

def _native_gains(set_, get, vr, l1_now=0.0):
    """K from u = -K (s - s_ref) at unit errors (no limits, references 0, x_d 0): u = -K_j exactly."""
    gains = []
    set_([vr["l1_now"]], [l1_now])
    for name in STATE:
        set_([vr[s] for s in STATE], [1.0 if s == name else 0.0 for s in STATE])
        gains.append(-get([vr["u"]])[0])
    return gains


def test_native_gains_equal_the_python_design_over_random_parameters(native):
    """24 designs (12 with a schedule of 21 designs each), read at 9 cable lengths each: 1e-10 relative (glibc: 0).

    The gains are read at l1_now = 0 (the design for l1) and, with a schedule, below, on and between its
    points and above it, against lqr.scheduled_gains() of the Python configuration.
    """
    rng = random.Random(2027)
    ours, theirs = [], []
    for i in range(24):
        parameters = {**_random_design(rng, scheduled=i % 2 == 1), "u_max": INF, "v_max": INF}
        config = _config(parameters)
        fmu, vr, set_, get = open_native(native[2] / f"{NAME}.fmu", 2, parameters)
        fmu.exitInitializationMode()
        ours.append(_native_gains(set_, get, vr))
        theirs.append(config.gains)
        if config.schedule:
            lengths = config.schedule[0]
            for l1 in (0.5 * lengths[0], lengths[0], lengths[7], rng.uniform(lengths[0], lengths[-1]),
                       0.5 * (lengths[12] + lengths[13]), lengths[-1], lengths[-1] + 1.0, 1e3):
                ours.append(_native_gains(set_, get, vr, l1))
                theirs.append(lqr.scheduled_gains(config, l1))
        close(fmu)
    ours, theirs = np.array(ours), np.array(theirs)
    assert ours.shape == (24 + 12 * 8, 6) and np.all(np.isfinite(theirs))
    assert np.all(np.abs(ours - theirs) <= 1e-10 * np.abs(theirs))
    if LINUX:
        assert np.array_equal(ours, theirs)


def test_the_default_design_is_the_python_fmus_report(native):
    """At the defaults: the K_ figures crane-fmu info prints, and the schedule's end designs of hoist-transport."""
    fmu, vr, set_, get = open_native(native[3] / f"{NAME}.fmu", 3, {"u_max": INF, "v_max": INF})
    fmu.exitInitializationMode()
    report = lqr.report(CONTROLLER.check({}))
    assert _native_gains(set_, get, vr) == [report["K_" + s] for s in STATE]
    close(fmu)
    parameters = systems.bind(systems.get("hoist-transport")).parameters["controller"]
    config = CONTROLLER.check(parameters)
    fmu, vr, set_, get = open_native(native[3] / f"{NAME}.fmu", 3, {**parameters, "u_max": INF, "v_max": INF})
    fmu.exitInitializationMode()
    for length, gains in zip(*config.schedule):
        assert _native_gains(set_, get, vr, length) == pytest.approx(gains, rel=1e-10)
    close(fmu)


# ---- (b) outputs at random inputs and parameters ----------------------------------------------------------------

def _random_parameters(rng, i):
    p = _random_design(rng, scheduled=i % 2 == 1)
    p["x_d"] = rng.uniform(-5, 5)
    p["u_max"] = (INF, rng.uniform(0.05, 3))[(i // 2) % 2]
    p["v_max"] = (INF, rng.uniform(0.05, 2))[(i // 4) % 2]
    p["offset_free"] = float(i % 3) if p["m2"] > 0 else 0.0  # the force's target: off, the load, the trolley
    return p


def _random_inputs(rng, parameters):
    inputs = {"x": rng.uniform(-5, 5), "dx": rng.uniform(-3, 3), "theta1": rng.uniform(-1.5, 1.5),
              "dtheta1": rng.uniform(-5, 5), "theta2": rng.uniform(-1.5, 1.5), "dtheta2": rng.uniform(-5, 5)}
    for name, scale in zip(lqr.REFERENCE, (5, 2, 0.3, 1, 0.3, 1)):
        inputs[name] = rng.choice([0.0, rng.uniform(-scale, scale)])
    inputs["ddx_ref"] = rng.choice([0.0, rng.uniform(-2, 2)])
    low, high = parameters.get("l1_low", 0.2), parameters.get("l1_high", 5.0)
    inputs["l1_now"] = rng.choice([0.0, rng.uniform(low, high), rng.uniform(0.5 * low, 2 * high), -1.0])
    inputs["F2_hat"] = rng.choice([0.0, rng.uniform(-30, 30)])
    inputs["F1_hat"] = rng.choice([0.0, rng.uniform(-30, 30)])
    return inputs


@pytest.mark.parametrize("version", [2, 3])
def test_native_outputs_equal_the_python_model_at_random_inputs_and_parameters(native, version):
    """2000 points: 40 parameter sets (schedule on and off, finite and infinite limits) x 50 inputs each.

    Inputs: the state, the references, ddx_ref, and l1_now unmeasured (0, or negative), inside the
    schedule's range or beyond it. 1e-12 relative to max(|u|, 1); on Linux bit for bit.
    """
    rng = random.Random(27)
    ours, theirs, limited = [], [], 0
    for i in range(40):
        parameters = _random_parameters(rng, i)
        config = _config(parameters)
        fmu, vr, set_, get = open_native(native[version] / f"{NAME}.fmu", version, parameters)
        fmu.exitInitializationMode()
        for _ in range(50):
            inputs = _random_inputs(rng, parameters)
            set_([vr[k] for k in inputs], list(inputs.values()))
            ours.append(get([vr["u"]])[0])
            values = tuple(inputs[n] for n in CONTROLLER.names("input"))
            theirs.append(CONTROLLER.output(config, None, values)[0])
            limited += theirs[-1] != CONTROLLER.output(config._replace(u_max=INF, v_max=INF), None, values)[0]
        close(fmu)
    ours, theirs = np.array(ours), np.array(theirs)
    assert len(ours) == 2000 and np.all(np.isfinite(theirs))
    assert limited > 200  # the limits do act on many points
    assert np.max(np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1.0)) <= 1e-12
    if LINUX:
        assert np.array_equal(ours, theirs)


def test_before_initialisation_ends_the_output_follows_the_parameters(fmu_dir, native):
    """u read in initialisation mode after each parameter change: the Python FMU's values."""
    changes = [{"u_max": INF, "v_max": INF}, {"q_theta1": 10.0}, {"h": 0.01, "x_d": 1.0},
               {"l1_low": 0.5, "l1_high": 2.0}, {"u_max": 5.0}]
    readings = {}
    for label, path in (("native", native[2] / f"{NAME}.fmu"), ("python", fmu_dir / f"{NAME}.fmu")):
        fmu, vr, set_, get = open_native(path, 2, {"theta1": 0.1, "dtheta2": -0.3, "l1_now": 1.2})
        readings[label] = []
        for change in changes:
            set_([vr[k] for k in change], list(change.values()))
            readings[label].append(get([vr["u"]])[0])
        fmu.exitInitializationMode()
        readings[label].append(get([vr["u"]])[0])
        close(fmu)
    assert readings["native"] == readings["python"]
    assert len(set(readings["python"])) >= 4  # the changes do change u


def test_an_fmu_state_carries_the_design_and_the_schedule(native):
    """A state serialised after a scheduled design, set into an instance designed otherwise: the first one's outputs."""
    parameters = {"l1_low": 0.5, "l1_high": 3.0, "q_theta2": 200.0, "u_max": INF, "v_max": INF}
    first, vr, set_, get = open_native(native[2] / f"{NAME}.fmu", 2, parameters)
    first.exitInitializationMode()
    expected = _native_gains(set_, get, vr, 1.7)
    state = first.getFMUstate()
    serialized = first.serializeFMUstate(state)
    first.freeFMUstate(state)
    second, _, set2, get2 = open_native(native[2] / f"{NAME}.fmu", 2)
    second.exitInitializationMode()
    assert _native_gains(set2, get2, vr, 1.7) != expected
    state = second.deSerializeFMUstate(serialized)
    second.setFMUstate(state)
    assert _native_gains(set2, get2, vr, 1.7) == expected
    second.freeFMUstate(state)
    for fmu in (first, second):
        close(fmu)


# ---- (c) refusals: the Python FMU's rules and messages ----------------------------------------------------------

REFUSED = [{"m1": -1.0}, {"m1": INF}, {"m2": -0.5}, {"l1": NAN}, {"l2": INF}, {"g": 0.0}, {"q_x": -1.0},
           {"q_dx": NAN}, {"q_theta1": INF}, {"q_dtheta2": -1e-300}, {"r": 0.0}, {"r": -INF}, {"h": 0.0},
           {"h": NAN}, {"x_d": INF}, {"u_max": 0.0}, {"u_max": -INF}, {"v_max": NAN},
           {"l1_low": -1.0, "l1_high": 2.0}, {"l1_high": 1.0}, {"l1_low": NAN}, {"l1_low": 1.0},
           {"l1_low": 1.0, "l1_high": 1.0}, {"l1_low": 1.0, "l1_high": INF}, {"l1_low": 2.0, "l1_high": NAN},
           {"h": -1.0, "m1": -1.0, "q_x": -1.0}, {"r": 0.0, "q_theta2": NAN}, {"u_max": 0.0, "l1_low": -1.0},
           # the design's own failures: the Python exception's type and text
           {"m1": 1e-300}, {"r": 1e300}, {"h": 1e300}, {"h": 1e308}, {"l1_low": 1e-300, "l1_high": 1.0}]


@pytest.mark.parametrize("settings", REFUSED, ids=lambda s: ",".join(f"{k}={v!r}" for k, v in s.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, settings):
    ours = messages(native[2] / f"{NAME}.fmu", settings)
    theirs = messages(fmu_dir / f"{NAME}.fmu", settings)
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


def test_a_schedule_narrower_than_a_rounding_fails_when_read_as_python_does(fmu_dir, native):
    """l1_high one ulp above l1_low: the designs are made, the interpolation divides by zero at the first read."""
    settings = {"l1_low": 1.0, "l1_high": 1.0000000000000002, "l1_now": 1.0}
    ours = messages(native[2] / f"{NAME}.fmu", settings, read_at_end=["u"])
    assert ours == messages(fmu_dir / f"{NAME}.fmu", settings, read_at_end=["u"])
    assert ours == (["get u: 3", "end"], ["fmi2GetReal: ZeroDivisionError: float division by zero"])


@pytest.mark.parametrize("step", [NAN, -1e-3, 0.0, INF])
def test_an_unusable_step_is_the_python_fmus_error(fmu_dir, native, step):
    ours = messages(native[2] / f"{NAME}.fmu", {}, [(0.0, 1e-3), (1e-3, step)])
    theirs = messages(fmu_dir / f"{NAME}.fmu", {}, [(0.0, 1e-3), (1e-3, step)])
    assert ours == theirs
    assert ours[0][-2] == "step 0.001: 3"


# ---- (d) closed loops through our master ------------------------------------------------------------------------

def _python_dir(fmu_dir, version):
    return fmu_dir if version == 2 else fmi3_dir(fmu_dir)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", ["lqr", "transport", "hoist-transport"])
def test_closed_loops_with_the_native_lqr_equal_the_python_fmus_runs(fmu_dir, native, name, version):
    """Every output of every instance at every step within 1e-9 (glibc: 0).

    ``lqr``: native plant and LQR; ``transport``: the same with the Python TrajectoryPlanner;
    ``hoist-transport``: the gains scheduled on the measured cable length as it goes from 2 m to 1 m.
    """
    system = systems.bind(systems.get(name))
    ours, theirs = run(system, native[version]).columns(), run(system, _python_dir(fmu_dir, version)).columns()
    assert list(ours) == list(theirs)
    assert len(ours["time"]) == len(theirs["time"]) == round(system.stop_time / system.step) + 1
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    assert worst <= 1e-9
    if LINUX:
        assert worst == 0.0
    assert np.max(np.abs(theirs["controller.u"])) > 0.1  # the controller does act


# ---- linalg.c on its own ----------------------------------------------------------------------------------------

def _la_max():
    import re

    from crane_fmu.build_scripts.native import MODELS_DIR

    return int(re.search(r"#define LA_MAX (\d+)", (MODELS_DIR / "linalg.h").read_text()).group(1))


class _Matrix(ctypes.Structure):
    _fields_ = [("rows", ctypes.c_int), ("cols", ctypes.c_int), ("v", (ctypes.c_double * _la_max()) * _la_max())]


@pytest.fixture(scope="module")
def linalg_c(tmp_path_factory):
    """fmu_src/models/linalg.c as a shared library (CRANE_OWN_MATH, no libm linked: it needs none)."""
    import shutil
    import subprocess

    from crane_fmu.build_scripts.native import MODELS_DIR

    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler")
    out = tmp_path_factory.mktemp("linalg") / "linalg.so"
    subprocess.run([compiler, "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-ffp-contract=off", "-DCRANE_OWN_MATH",
                    str(MODELS_DIR / "linalg.c"), "-o", str(out)], check=True)
    library = ctypes.CDLL(str(out))
    library.la_ceil_log2.restype, library.la_ceil_log2.argtypes = ctypes.c_int, [ctypes.c_double]
    library.la_expm.restype = ctypes.c_char_p
    library.la_expm.argtypes = [_Matrix, ctypes.POINTER(_Matrix)]
    return library


def test_ceil_log2_without_libm_is_pythons_ceil_of_log2(linalg_c):
    """Every power of two in range and the 400 doubles above and below each; 20,000 random y: math.ceil(math.log2)."""
    import math

    rng = random.Random(3)
    ys = [rng.uniform(1.0, 4.0) for _ in range(10_000)] + [math.exp(rng.uniform(0, 709)) for _ in range(10_000)]
    for k in range(1024):
        below = above = math.ldexp(1.0, k)
        ys.append(above)
        for _ in range(400):
            above, below = math.nextafter(above, INF), math.nextafter(below, 0.0)
            ys += [above, below]
    ys = [y for y in ys if 1.0 < y < INF]
    assert [linalg_c.la_ceil_log2(y) for y in ys] == [math.ceil(math.log2(y)) for y in ys]


def test_expm_equals_linalg_py_bit_for_bit(linalg_c):
    """Random 7x7 and 9x9 matrices (the LQR's and the estimator's ZOH) of entries up to about 30 (0 to 9 squarings):
    linalg.expm's bits."""
    from crane_fmu.model import linalg

    rng = random.Random(4)
    for k in range(200):
        n, scale = (7, 9)[k % 2], 10 ** rng.uniform(-3, 1.5)
        a = [[rng.gauss(0, scale) if rng.random() < 0.6 else 0.0 for _ in range(n)] for _ in range(n)]
        matrix, out = _Matrix(n, n), _Matrix()
        for i in range(n):
            for j in range(n):
                matrix.v[i][j] = a[i][j]
        assert linalg_c.la_expm(matrix, ctypes.byref(out)) is None
        assert [[out.v[i][j] for j in range(n)] for i in range(n)] == linalg.expm(a)
