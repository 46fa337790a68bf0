"""The LqrController3D: the planar LQR on each axis of the crane in three dimensions (crane_fmu/model/lqr3d.py,
its C twin fmu_src/models/lqr3d.c).

Known answers: each axis' block of the spatial plant's linearisation at rest is the planar crane's model, so each
axis' gains are the planar LQR's; a move along x alone is the planar LQR's move on the planar plant; a move turned
by 90 degrees about the vertical turns the whole run. The native FMU gives the Python model's bits.
"""

import math
import random

import numpy as np
import pytest
from native_fmus import close, compare_to_python, open_native

from crane_fmu import components, systems
from crane_fmu.cosim import run
from crane_fmu.cosim.recorder import ArrayRecorder
from crane_fmu.model import lqr, lqr3d
from crane_fmu.model.parameters import plant_parameters

CONTROLLER = components.get("LqrController3D")
MODEL = ("m1", "m2", "l1", "l2", "g")


def _random_model(rng):
    return {"m1": rng.uniform(0.5, 20), "m2": rng.choice([0.0, rng.uniform(0.1, 20)]), "l1": rng.uniform(0.2, 5),
            "l2": rng.uniform(0.1, 3), "g": rng.uniform(1, 25)}


def _random_design(rng):
    p = {**_random_model(rng), "r": 10 ** rng.uniform(-3, 1), "h": 10 ** rng.uniform(-4, -1)}
    for name in lqr.WEIGHTS:
        p[name] = rng.choice([0.0, 10 ** rng.uniform(-2, 3)])
    p["q_x"] = 10 ** rng.uniform(-1, 3)  # x weighted: the pair stays detectable
    return p


@pytest.mark.quick
def test_each_axis_block_of_the_plants_linearisation_is_the_planar_crane():
    rng = random.Random(52)
    for _ in range(20):
        values = _random_model(rng)
        planar = lqr.continuous_model(plant_parameters(values))
        for axis in lqr3d.AXES:
            assert lqr3d.axis_model(values, axis) == planar


@pytest.mark.quick
def test_each_axis_has_the_planar_lqr_gains():
    rng = random.Random(53)
    for _ in range(10):
        values = _random_design(rng)
        gains = lqr.COMPONENT.check(values).gains
        assert CONTROLLER.check(values).gains == (gains, gains)


@pytest.mark.quick
def test_each_axis_demand_reads_only_its_own_states():
    """The x axis' demand is the planar LQR's of the x states whatever the y states are, and the other way."""
    rng = random.Random(54)
    config, planar = CONTROLLER.check({"u_max": math.inf, "v_max": math.inf}), lqr.COMPONENT.check(
        {"u_max": math.inf, "v_max": math.inf})
    names = CONTROLLER.names("input")
    for _ in range(20):
        inputs = [rng.uniform(-1, 1) for _ in names]
        ux, uy = CONTROLLER.output(config, None, inputs)
        for axis, u in zip("xy", (ux, uy)):
            pick = [inputs[names.index(n)] for n in lqr3d.axis_states(axis)]
            refs = [inputs[names.index(n + "_ref")] for n in lqr3d.axis_states(axis)]
            assert u == lqr.control(planar, pick, refs, inputs[names.index(f"dd{axis}_ref")])


def _native_outputs(path, version, parameters, rows):
    fmu, vr, set_, get = open_native(path, version, parameters)
    fmu.exitInitializationMode()
    names = CONTROLLER.names("input")
    out = []
    for row in rows:
        set_([vr[n] for n in names], row)
        out.append(get([vr["ux"], vr["uy"]]))
    close(fmu)
    return out


@pytest.mark.parametrize("version", [2, 3])
def test_native_equals_the_python_model_bit_for_bit(native, version):
    """12 random designs (limits on and off, offset_free 0, 1, 2) at 20 random inputs each (the estimated forces
    too): the same bits on Linux (1e-12 elsewhere)."""
    rng = random.Random(2052 + version)
    ours, theirs = [], []
    for n in range(12):
        parameters = {**_random_design(rng), "x_d": rng.uniform(-3, 3), "y_d": rng.uniform(-3, 3),
                      "u_max": rng.choice([math.inf, rng.uniform(0.1, 5)]),
                      "v_max": rng.choice([math.inf, rng.uniform(0.1, 2)])}
        parameters["offset_free"] = float(n % 3) if parameters["m2"] > 0 else 0.0
        config = CONTROLLER.check(parameters)
        rows = [[rng.uniform(-2, 2) for _ in CONTROLLER.names("input")] for _ in range(20)]
        ours += _native_outputs(native[version] / "LqrController3D.fmu", version, parameters, rows)
        theirs += [CONTROLLER.output(config, None, row) for row in rows]
    compare_to_python(ours, theirs)


# ---- closed loops on the native FMUs (each equal to its Python FMU: the tests of the native components) ----------

STOP = 6.0


def _run(system, fmu_dir):
    recorder = ArrayRecorder()
    run(systems.prepare(system, stop_time=STOP), fmu_dir, recorder=recorder)
    return recorder.columns()


def _move(x_d, y_d):
    """lqr3d-move's system moving to (x_d, y_d)."""
    base = systems.get("lqr3d-move")
    return base.with_parameters({"planner": {"x_d": x_d}, "planner_y": {"x_d": y_d}})


def test_a_move_along_x_alone_is_the_planar_lqr_move(native):
    """The planar `transport` (planar plant, planner, LQR) and the spatial move to (2 m, 0): the same run within
    1e-12 (the spatial plant is the planar one to that, tests/test_plant3d.py), nothing along y."""
    planar = _run(systems.get("transport"), native[2])
    spatial = _run(_move(2.0, 0.0), native[2])
    for theirs, ours in (("x", "x"), ("dx", "dx"), ("theta1", "theta1x"), ("theta2", "theta2x"), ("x2", "x2")):
        assert np.max(np.abs(spatial[f"plant.{ours}"] - planar[f"plant.{theirs}"])) <= 1e-12, ours
    assert np.max(np.abs(spatial["controller.ux"] - planar["controller.u"])) <= 1e-9
    assert np.max(np.abs(planar["plant.x"])) > 1.9  # it moved
    for name in ("y", "theta1y", "theta2y", "y2"):
        assert not np.any(spatial[f"plant.{name}"]), name
    assert not np.any(spatial["controller.uy"])


def test_a_move_turned_by_90_degrees_turns_the_run(native):
    """(2, 1.5) m and the same turned by 90 degrees about the vertical, (-1.5, 2) m: the trolley, hook and load
    positions of the one are those of the other turned, (x, y) -> (-y, x), to the third order of the swing.

    The two angles of a cable (``a`` in the x-z plane, ``b`` out of it) are not those of the turned cable beyond
    the first order (``sin a cos b`` against ``sin b``), and the controller reads them: the runs part by at most
    about ``(l1 + l2) theta^3``, theta the largest swing."""
    one, turned = _run(_move(2.0, 1.5), native[2]), _run(_move(-1.5, 2.0), native[2])
    worst = 0.0
    for x, y in (("x", "y"), ("x1", "y1"), ("x2", "y2")):
        worst = max(worst, np.max(np.abs(turned[f"plant.{x}"] + one[f"plant.{y}"])),
                    np.max(np.abs(turned[f"plant.{y}"] - one[f"plant.{x}"])))
    peak = float(np.max(np.abs(one["plant.swing2"])))
    assert peak > math.radians(5)  # a swing to turn
    assert worst <= 1.5 * peak ** 3


def test_a_move_mirrored_across_the_x_z_plane_mirrors_the_run(native):
    """(2, 1.5) m and (2, -1.5) m: exactly mirrored, y -> -y (the out-of-plane angles change sign, b -> -b, which the
    angles' coordinates keep exact)."""
    one, mirrored = _run(_move(2.0, 1.5), native[2]), _run(_move(2.0, -1.5), native[2])
    for name in ("x", "x1", "x2", "theta1x", "theta2x", "z2"):
        assert np.max(np.abs(mirrored[f"plant.{name}"] - one[f"plant.{name}"])) <= 1e-12, name
    for name in ("y", "y1", "y2", "theta1y", "theta2y"):
        assert np.max(np.abs(mirrored[f"plant.{name}"] + one[f"plant.{name}"])) <= 1e-12, name
    assert np.max(np.abs(one["plant.y2"])) > 1.4
