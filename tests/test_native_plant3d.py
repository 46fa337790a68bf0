"""The C of the spatial crane (plant3d_equations.c, plant3d_continuous.c) against its specification, the Python model.

Compiled as a library and called through ctypes: the RK4 step, the outputs, the derivatives and their directional
derivatives along every unit seed, the event indicators and the event updates, bit for bit on Linux (the same
operations in the same order, glibc's libm as CPython's, -ffp-contract=off). The FMUs: test_plant3d_fmus.py.
"""

import ctypes
import math
import random
import subprocess
import sys

import pytest
from helpers import spatial_plant_cases as cases

from crane_fmu.build_scripts.native import MODELS_DIR, NativeUnavailable, compilers
from crane_fmu.model import plant3d
from crane_fmu.model import plant3d_continuous as me
from crane_fmu.model import plant3d_equations as eq3

N, M, Z, P = len(me.STATES), len(me.INPUTS), len(me.INDICATORS), 25
D = ctypes.c_double


class _Params(ctypes.Structure):
    _fields_ = [(n, D) for n in ("m1", "m2", "l1", "l2", "g")]


class _Axis(ctypes.Structure):
    _fields_ = [(n, D) for n in ("u_max", "v_max", "tau", "low", "high")]


class _Plant(ctypes.Structure):
    _fields_ = [("p", _Params), ("c1", D), ("c2", D), ("x", _Axis), ("y", _Axis), ("l1_min", D), ("l1_max", D),
                ("dl1_max", D)]


class _Load(ctypes.Structure):
    _fields_ = [(n, D) for n in ("hoist", "f1x", "f1y", "f2x", "f2y", "c1", "c2")]


class _Mode(ctypes.Structure):
    _fields_ = [(n, ctypes.c_int) for n in ("speed_x", "speed_y", "cable", "hoist")]


class _Event(ctypes.Structure):
    _fields_ = [("rail_end", ctypes.c_int), ("rail_axis", ctypes.c_int), ("cable_reached", ctypes.c_int),
                ("cable_at", D), ("cable_rate", D)]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    if not sys.platform.startswith("linux"):
        pytest.skip("bit-equality with the Python model holds with glibc's libm (Linux)")
    try:
        cc = compilers()["linux"]
    except NativeUnavailable as exc:
        pytest.skip(f"a C compiler: {exc}")
    out = tmp_path_factory.mktemp("plant3d") / "libplant3d.so"
    subprocess.run([cc, "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-ffp-contract=off",
                    str(MODELS_DIR / "plant3d_continuous.c"), str(MODELS_DIR / "plant3d_equations.c"), "-o", str(out),
                    "-lm"], check=True)
    return ctypes.CDLL(str(out))


def _plant(config):
    p = config.params
    return _Plant(_Params(p.m1, p.m2, p.l1, p.l2, p.g), *config.damping, _Axis(*config.x_axis),
                  _Axis(*config.y_axis), config.l1_min, config.l1_max, config.dl1_max)


def _array(values, n=None):
    return (D * (n or len(values)))(*values)


def test_rk4_steps_and_outputs_are_the_python_models(lib):
    """200 steps of random states, inputs, hoisting, forces and damping: every value bit for bit."""
    rng = random.Random(8)
    for config, state, inputs, _ in cases(10):
        p = config.params
        ux, uy, hoist, *forces = inputs
        swing = state[:14]
        c_state = _array(swing)
        c_params = _Params(p.m1, p.m2, p.l1, p.l2, p.g)
        load = _Load(hoist * 0.1, *forces, *config.damping)
        dt = rng.choice((1e-3, 5e-4))
        for _ in range(200):
            swing = eq3.rk4_step(swing, ux, uy, dt, p, hoist * 0.1, (*forces, *config.damping))
            lib.spatial_rk4_step(c_state, D(ux), D(uy), D(dt), ctypes.byref(c_params), ctypes.byref(load))
        assert tuple(c_state) == swing
        out, dout = _array((), 9), _array((), 9)
        lib.spatial_outputs(c_state, ctypes.byref(c_params), out)
        assert tuple(out) == eq3.outputs(swing, p)
        seed = tuple(rng.uniform(-1, 1) for _ in range(14))
        lib.spatial_outputs_tangent(c_state, ctypes.byref(c_params), _array(seed), dout)
        assert tuple(dout) == eq3.outputs_tangent(swing, p, seed)


def test_derivatives_and_their_directional_derivatives_are_the_python_models(lib):
    for config, state, inputs, mode in cases():
        c, s, i, m = _plant(config), _array(state), _array(inputs), _Mode(*mode)
        for k in range(N + M):
            seed = (tuple(float(j == k) for j in range(N)), tuple(float(N + j == k) for j in range(M)))
            f, df = _array((), N), _array((), N)
            assert lib.plant3_derivatives(ctypes.byref(c), s, i, m, _array(seed[0]), _array(seed[1]), f, df) == 0
            assert (tuple(f), tuple(df)) == me.derivatives(config, state, inputs, mode, seed), (k, mode)
            out, dout = _array((), P), _array((), P)
            lib.plant3_outputs(ctypes.byref(c), s, i, m, _array(seed[0]), _array(seed[1]), out, dout)
            assert (tuple(out), tuple(dout)) == me.output_values(config, state, inputs, mode, seed), (k, mode)
        z = _array((), Z)
        lib.plant3_event_indicators(ctypes.byref(c), s, i, m, z)
        assert tuple(z) == me.event_indicators(config, state, inputs, mode)


def test_refusals_are_the_python_models(lib):
    config = plant3d.COMPONENT.check({"m2": 0.0})
    f = _array((), N)
    assert lib.plant3_derivatives(ctypes.byref(_plant(config)), _array(me.initial(config)),
                                  _array((0, 0, 0, 0, 0, 0, 1.0)), _Mode(0, 0, 0, 0), None, None, f, None) == 1
    config = plant3d.COMPONENT.check({})
    state = me.initial(config)[:12] + (0.0, 0.0, 0.0, 0.0)  # a cable of no length
    assert lib.plant3_derivatives(ctypes.byref(_plant(config)), _array(state), _array((0,) * 7), _Mode(0, 0, 0, 0),
                                  None, None, f, None) == 2


_REST = (0.0,) * 8 + (1.0, 0.0, 0.0, 0.0)  # angles, l1, dl1, drives


@pytest.mark.parametrize("values, state, inputs, mode", [
    ({"vx_max": 0.5}, (0.5, 0.5000001, 0.0, 0.0) + _REST, (1.0, 0, 0, 0, 0, 0, 0), me.FREE),
    ({"vy_max": 0.5}, (0.5, 0.0, 0.1, -0.5000001) + _REST, (0, -1.0, 0, 0, 0, 0, 0), me.FREE),
    ({"vy_max": 0.5}, (0.5, 0.0, 0.1, 0.5) + _REST, (0, -1.0, 0, 0, 0, 0, 0), me.Mode(0, 1, 0, 0)),
    ({"vx_max": 0.5, "tau_x": 0.3}, (0.5, -0.5, 0.0, 0.0) + _REST[:-2] + (-0.2, 0.0), (1.0, 0, 0, 0, 0, 0, 0),
     me.FREE),
    ({"l1_max": 1.5}, (0.5, 0.0, 0.0, 0.0) + (0.0,) * 8 + (1.5000001, 0.2, 0.0, 0.0), (0, 0, 0.1, 0, 0, 0, 0),
     me.FREE),
    ({"l1_min": 0.5}, (0.5, 0.0, 0.0, 0.0) + (0.0,) * 8 + (0.4999, -0.3, 0.0, 0.0), (0, 0, 0.1, 0, 0, 0, 0),
     me.FREE),
    ({"dl1_max": 0.2}, (0.5, 0.0, 0.0, 0.0) + (0.0,) * 8 + (1.2, 0.2, 0.0, 0.0), (0, 0, 0.1, 0, 0, 0, 0), me.FREE),
    ({"x_max": 2.0}, (2.0, 0.1, 0.0, 0.0) + _REST, (0,) * 7, me.FREE),
    ({"y_min": -1.0}, (0.0, 0.0, -1.0000001, -0.1) + _REST, (0,) * 7, me.FREE),
    ({"y_max": 2.0}, (0.0, 0.0, 2.0, 0.0) + _REST, (0, 0.5, 0, 0, 0, 0, 0), me.FREE),
    ({"y_max": 2.0}, (0.0, 0.0, 2.0, -0.1) + _REST, (0, 1.0, 0, 0, 0, 0, 0), me.FREE),
])
def test_event_updates_are_the_python_models(lib, values, state, inputs, mode):
    config = plant3d.COMPONENT.check(values)
    want = me.event_update(config, state, inputs, mode, 1.0)
    s, m, event = _array(state), _Mode(*mode), _Event()
    lib.plant3_event_update(ctypes.byref(_plant(config)), s, _array(inputs), ctypes.byref(m), ctypes.byref(event))
    assert bool(event.rail_end) == (want.terminate is not None)
    if want.terminate:
        axis = "y" if event.rail_axis else "x"
        assert f"{axis}_{'max' if event.rail_end > 0 else 'min'}" in want.terminate
        return
    assert tuple(s) == want.state and (m.speed_x, m.speed_y, m.cable, m.hoist) == tuple(want.mode)
    assert bool(event.cable_reached) == bool(want.messages)
    assert not math.isnan(sum(s))
