"""The C of the plant for Model Exchange (plant_continuous.c) against its specification, plant_continuous.py.

Compiled as a library and called through ctypes: the derivatives, their directional derivatives along
every unit seed, the outputs and theirs, the event indicators and the event updates, bit for bit on
Linux (the same operations in the same order, glibc's libm as CPython's, -ffp-contract=off).
"""

import ctypes
import subprocess
import sys

import pytest
from helpers import continuous_plant_cases  # the same random cases as the Python model's tests

from crane_fmu.build_scripts.native import MODELS_DIR, NativeUnavailable, compilers
from crane_fmu.model import plant
from crane_fmu.model import plant_continuous as me
from crane_fmu.model.plant_continuous import FREE, Mode

N, M, Z, P = len(me.STATES), len(me.INPUTS), len(me.INDICATORS), 14
D = ctypes.POINTER(ctypes.c_double)


class _Params(ctypes.Structure):
    _fields_ = [(n, ctypes.c_double) for n in ("m1", "m2", "l1", "l2", "g")]


class _Plant(ctypes.Structure):
    _fields_ = [("p", _Params)] + [(n, ctypes.c_double) for n in (
        "c1", "c2", "u_max", "v_max", "tau", "x_min", "x_max", "l1_min", "l1_max", "dl1_max")]


class _Mode(ctypes.Structure):
    _fields_ = [(n, ctypes.c_int) for n in ("speed", "cable", "hoist")]


class _Event(ctypes.Structure):
    _fields_ = [("rail_end", ctypes.c_int), ("cable_reached", ctypes.c_int), ("cable_at", ctypes.c_double),
                ("cable_rate", ctypes.c_double)]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    if not sys.platform.startswith("linux"):
        pytest.skip("bit-equality with the Python model holds with glibc's libm (Linux)")
    try:
        cc = compilers()["linux"]
    except NativeUnavailable as exc:
        pytest.skip(f"a C compiler: {exc}")
    out = tmp_path_factory.mktemp("continuous") / "libplant_continuous.so"
    subprocess.run([cc, "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-ffp-contract=off",
                    str(MODELS_DIR / "plant_continuous.c"), str(MODELS_DIR / "plant_equations.c"), "-o", str(out),
                    "-lm"],
                   check=True)
    return ctypes.CDLL(str(out))


def _plant(config):
    p = config.params
    return _Plant(_Params(p.m1, p.m2, p.l1, p.l2, p.g), *config.damping, config.u_max, config.v_max, config.tau,
                  config.x_min, config.x_max, config.l1_min, config.l1_max, config.dl1_max)


def _array(values, n=None):
    return (ctypes.c_double * (n or len(values)))(*values)


def test_derivatives_and_their_directional_derivatives_are_the_python_models(lib):
    for config, state, inputs, mode in continuous_plant_cases():
        c, s, i = _plant(config), _array(state), _array(inputs)
        m = _Mode(*mode)
        for k in range(N + M):
            seed = (tuple(float(j == k) for j in range(N)), tuple(float(N + j == k) for j in range(M)))
            f, df = _array((), N), _array((), N)
            assert lib.plant_derivatives(ctypes.byref(c), s, i, m, _array(seed[0]), _array(seed[1]), f, df) == 0
            want, want_d = me.derivatives(config, state, inputs, mode, seed)
            assert (tuple(f), tuple(df)) == (want, want_d), (k, mode)
            out, dout = _array((), P), _array((), P)
            lib.plant_continuous_outputs(ctypes.byref(c), s, i, m, _array(seed[0]), _array(seed[1]), out, dout)
            want, want_d = me.output_values(config, state, inputs, mode, seed)
            assert (tuple(out), tuple(dout)) == (want, want_d), (k, mode)
        z = _array((), Z)
        lib.plant_event_indicators(ctypes.byref(c), s, i, m, z)
        assert tuple(z) == me.event_indicators(config, state, inputs, mode)


def test_refusals_are_the_python_models(lib):
    config = plant.COMPONENT.check({"m2": 0.0})
    f = _array((), N)
    assert lib.plant_derivatives(ctypes.byref(_plant(config)), _array(me.initial(config)), _array((0, 0, 0, 1.0)),
                                 _Mode(0, 0, 0), None, None, f, None) == 1
    config = plant.COMPONENT.check({})
    state = me.initial(config)[:6] + (0.0, 0.0, 0.0)  # a cable of no length
    assert lib.plant_derivatives(ctypes.byref(_plant(config)), _array(state), _array((0, 0, 0, 0)), _Mode(0, 0, 0),
                                 None, None, f, None) == 2


@pytest.mark.parametrize("values, state, inputs, mode", [
    ({"v_max": 0.5}, (0.5, 0.5000001, 0.1, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), (1.0, 0, 0, 0), FREE),
    ({"v_max": 0.5}, (0.5, 0.5, 0.1, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), (-1.0, 0, 0, 0), Mode(1, 0, 0)),
    ({"v_max": 0.5, "tau": 0.3}, (0.5, -0.5, 0.1, 0.0, 0.0, 0.0, 1.0, 0.0, -0.2), (1.0, 0, 0, 0), FREE),
    ({"l1_max": 1.5}, (0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.5000001, 0.2, 0.0), (0.0, 0.1, 0, 0), FREE),
    ({"l1_max": 1.5}, (0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.5, 0.0, 0.0), (0.0, -0.1, 0, 0), Mode(0, 1, 0)),
    ({"l1_min": 0.5}, (0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.4999, -0.3, 0.0), (0.0, 0.1, 0, 0), FREE),
    ({"dl1_max": 0.2}, (0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.2, 0.2, 0.0), (0.0, 0.1, 0, 0), FREE),
    ({"x_max": 2.0}, (2.0, 0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), (0.0, 0, 0, 0), FREE),
    ({"x_max": 2.0}, (2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), (0.5, 0, 0, 0), FREE),
    ({"x_min": -1.0}, (-1.0000001, -0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), (0.0, 0, 0, 0), FREE),
    ({"x_max": 2.0}, (2.0, -0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), (1.0, 0, 0, 0), FREE),
])
def test_event_updates_are_the_python_models(lib, values, state, inputs, mode):
    config = plant.COMPONENT.check(values)
    want = me.event_update(config, state, inputs, mode, 1.0)
    s, m, event = _array(state), _Mode(*mode), _Event()
    lib.plant_event_update(ctypes.byref(_plant(config)), s, _array(inputs), ctypes.byref(m), ctypes.byref(event))
    assert bool(event.rail_end) == (want.terminate is not None)
    if want.terminate:
        assert ("x_max" if event.rail_end > 0 else "x_min") in want.terminate
        return
    assert tuple(s) == want.state and (m.speed, m.cable, m.hoist) == tuple(want.mode)
    assert bool(event.cable_reached) == bool(want.messages)
