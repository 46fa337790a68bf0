"""The built FMUs, loaded by fmpy: description, physics, control law, closed loop."""

import math
import random
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from crane_fmu import components
from crane_fmu.analysis.reference import sampled_closed_loop
from crane_fmu.cosim import open_instance, simulate
from crane_fmu.model import backstepping as controller
from crane_fmu.model import plant, tables
from crane_fmu.model.parameters import ControllerGains, PlantParameters

STATE = list(tables.STATE)
PAPER_X0 = (0.0, 0.0, math.pi / 18, 0.0, 0.0, 0.0)


def _states(columns):
    return np.column_stack([columns["plant." + s] for s in STATE])


@pytest.mark.parametrize("name", ["CranePlant", "BacksteppingController",
                                  "TrivialPlant", "TrivialController"])
def test_fmpy_validate_finds_no_problem(fmu_dir, name):
    assert validate_fmu(str(fmu_dir / f"{name}.fmu")) == []


@pytest.mark.parametrize("name", ["CranePlant", "BacksteppingController"])
def test_model_description_matches_the_table(fmu_dir, name):
    md = read_model_description(str(fmu_dir / f"{name}.fmu"))
    table = components.get(name).variables
    assert [v.name for v in md.modelVariables] == [v.name for v in table]
    units = {u.name: u for u in md.unitDefinitions}
    for var, row in zip(md.modelVariables, table):
        assert var.description == row.description
        assert var.causality == row.causality
        if row.type == "Real":
            assert var.unit == row.unit
            assert var.displayUnit == tables.DISPLAY_UNITS.get(row.unit)
            assert row.unit in units
            if row.start is not None:
                assert float(var.start) == row.start  # starts round-trip exactly (9.8, not 9.800000000000001)
    assert units["rad"].displayUnits[0].name == "deg"
    assert units["rad"].displayUnits[0].factor == pytest.approx(180 / math.pi, rel=1e-15)


def test_only_the_controller_is_direct_feedthrough(fmu_dir):
    plant_md = read_model_description(str(fmu_dir / "CranePlant.fmu"))
    ctrl_md = read_model_description(str(fmu_dir / "BacksteppingController.fmu"))
    assert all(not u.dependencies for u in plant_md.outputs)
    (u,) = ctrl_md.outputs
    assert sorted(v.name for v in u.dependencies) == sorted(STATE)


def test_every_fmus_default_experiment_runs_at_its_systems_step(fmu_dir):
    """A host that runs an FMU with its defaults steps it as the built-in systems do (the LQR's
    discrete design, the sensor's delay are for that step); the plant's default is the paper's 20 s."""
    from crane_fmu import systems

    for system in systems.registered():
        for path in system.fmus(fmu_dir).values():
            experiment = read_model_description(str(path)).defaultExperiment
            assert float(experiment.stepSize) == system.step, (system.name, path.name)
    md = read_model_description(str(fmu_dir / "CranePlant.fmu"))
    assert (md.defaultExperiment.startTime, md.defaultExperiment.stopTime) == ("0.0", "20.0")


def test_free_swing_matches_dop853_on_the_symbolic_equations(plant_dir):
    """RK4 at 1 ms sub-steps (h = 10 ms) vs DOP853 at rtol = atol = 1e-12 over 20 s on the equations that
    sympy derives from the Lagrangian (tests/derivation.py): no code shared with the plant.

    Measured: 1.5e-9 rad on the angles and 1.3e-8 rad/s on the rates; the
    bounds below leave a margin of about 7 and guard against any change in
    the equations or a lower-order integrator (Euler would be off by ~1e-2).
    """
    from derivation import ACCEL
    from scipy.integrate import solve_ivp

    p = PlantParameters()
    result = simulate({"plant": plant_dir / "CranePlant.fmu"}, [], 20.0, 0.01).columns()

    def field(t, s):
        dd1, dd2 = ACCEL(s[2], s[3], s[4], s[5], 0.0, p.m1, p.m2, p.l1, p.l2, p.g)
        return [s[1], 0.0, s[3], dd1, s[5], dd2]

    ref = solve_ivp(field, (0.0, 20.0), PAPER_X0, method="DOP853", t_eval=result["time"], rtol=1e-12,
                    atol=1e-12).y.T
    got = _states(result)
    assert np.abs(got[:, [2, 4]] - ref[:, [2, 4]]).max() < 1e-8
    assert np.abs(got[:, [3, 5]] - ref[:, [3, 5]]).max() < 1e-7
    assert np.abs(got[:, :2]).max() == 0.0  # u = 0: the trolley stays put exactly


def test_the_free_swings_peak_is_the_independent_answer():
    """The largest theta2 of the free swing that seven host tests hold every FMU to (helpers.py), from DOP853 at
    rtol = atol = 1e-12 on the equations sympy derives (no code shared with the plant) sampled on the 1 ms grid:
    15.59762 deg; the hosts' tolerance is 5e-5 deg."""
    from derivation import ACCEL
    from helpers import FREE_SWING_MAX_THETA2_DEG
    from scipy.integrate import solve_ivp

    p = PlantParameters()

    def field(t, s):
        dd1, dd2 = ACCEL(s[2], s[3], s[4], s[5], 0.0, p.m1, p.m2, p.l1, p.l2, p.g)
        return [s[1], 0.0, s[3], dd1, s[5], dd2]

    grid = np.arange(20001) * 1e-3
    ref = solve_ivp(field, (0.0, 20.0), PAPER_X0, method="DOP853", t_eval=grid, rtol=1e-12, atol=1e-12).y
    assert math.degrees(ref[4].max()) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)


def test_free_swing_conserves_energy(plant_dir):
    """Over 100 s the energy output drifts by 4.5e-10 J (of 131 J); bound 1e-8 J."""
    result = simulate({"plant": plant_dir / "CranePlant.fmu"}, [], 100.0, 0.01).columns()
    energy = result["plant.energy"]
    assert np.abs(energy - energy[0]).max() < 1e-8
    assert energy[0] == pytest.approx(plant.energy(PAPER_X0, PlantParameters()), rel=1e-15)


def test_controller_fmu_equals_the_law_at_random_states(crane_fmus):
    """Same Python code inside and outside the FMU: the values must be identical."""
    rng = random.Random(3)
    for trial in range(20):
        inst = open_instance(crane_fmus["controller"], f"c{trial}")
        try:
            params = {"m1": rng.uniform(1, 5), "l1": rng.uniform(0.5, 2), "K1_theta2": rng.uniform(1, 200),
                      "w_theta2": rng.choice([0.0, 1.0]), "b3_form": rng.choice(["derived", "printed"]),
                      "x_d": rng.uniform(-2, 2)}
            inst.setup(0.0)
            for name, value in params.items():
                inst.set(name, value)
            inst.enter_initialization()
            inst.exit_initialization()
            for _ in range(5):
                state = [rng.uniform(-1, 1) for _ in range(6)]
                for name, value in zip(STATE, state):
                    inst.set(name, value)
                p = PlantParameters(m1=params["m1"], l1=params["l1"])
                k = ControllerGains(**{n: params[n] for n in ("K1_theta2", "w_theta2", "b3_form", "x_d")})
                assert inst.get("u") == controller.control(state, p, k)
        finally:
            inst.free()


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_closed_loop_equals_sampled_data_reference(crane_fmus, connections, algorithm):
    """Plant and controller FMUs through the master vs u held per step, plant by DOP853.

    With the theta2 row weighted 0 the loop is well damped: measured 1.7e-10 rad
    on the angles, 1.5e-9 rad/s on the rates over 20 s at h = 10 ms.
    """
    params = {"controller": {"w_theta2": 0.0}}
    result = simulate(crane_fmus, connections, 20.0, 0.01, algorithm, params).columns()
    gains = ControllerGains(w_theta2=0.0)
    ref, u = sampled_closed_loop(PAPER_X0, PlantParameters(), gains, 0.01, 2000, algorithm)
    got = _states(result)
    assert np.abs(got[:, [0, 2, 4]] - ref[:, [0, 2, 4]]).max() < 1e-9
    assert np.abs(got[:, [1, 3, 5]] - ref[:, [1, 3, 5]]).max() < 1e-8
    assert np.abs(result["controller.u"][:-1] - u).max() < 1e-8
    other, _ = sampled_closed_loop(PAPER_X0, PlantParameters(), gains, 0.01, 2000,
                                   "jacobi" if algorithm == "gauss-seidel" else "gauss-seidel")
    assert np.abs(got[:, 2] - other[:, 2]).max() > 1e-5  # the two modes are told apart


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_papers_law_closed_loop_equals_reference(crane_fmus, connections, algorithm):
    """The paper's law (W = I, K2_theta2 = 310) at h = 1 ms over 2 s.

    Its high loop gain amplifies the RK4 error: measured 1.0e-7 m on x, 9.5e-8
    rad on the angles, 4.8e-6 on the rates; bounds 1e-6 and 5e-5.
    """
    result = simulate(crane_fmus, connections, 2.0, 0.001, algorithm).columns()
    ref, _ = sampled_closed_loop(PAPER_X0, PlantParameters(), ControllerGains(), 0.001, 2000, algorithm)
    got = _states(result)
    assert np.abs(got[:, [0, 2, 4]] - ref[:, [0, 2, 4]]).max() < 1e-6
    assert np.abs(got[:, [1, 3, 5]] - ref[:, [1, 3, 5]]).max() < 5e-5


def test_instances_of_one_fmu_are_independent(crane_fmus):
    a, b = open_instance(crane_fmus["plant"], "a"), open_instance(crane_fmus["plant"], "b")
    try:
        for inst, angle in ((a, 0.1), (b, -0.3)):
            inst.setup(0.0)
            inst.set("theta1_0", angle)
            inst.enter_initialization()
            inst.exit_initialization()
        for k in range(10):
            a.do_step(k * 0.01, 0.01)
        assert b.get("theta1") == -0.3
        assert a.get("theta1") != 0.1
    finally:
        a.free()
        b.free()


def test_the_wrappers_cached_readers_and_writers_follow_reset_and_saved_states(crane_fmus):
    """The wrapper keeps one reader and writer per value-reference array: after fmi2Reset they must be the new
    slave's, after fmi2SetFMUstate they must see the restored values."""
    import ctypes

    inst = open_instance(crane_fmus["plant"], "plant")
    theta1, u, dx = ((ctypes.c_double * 1)() for _ in range(3))
    read_theta1, _ = inst.reader(inst.vr_array(["theta1"]), theta1)
    read_dx, _ = inst.reader(inst.vr_array(["dx"]), dx)
    write_u, _ = inst.writer(inst.vr_array(["u"]), u)

    def start(angle):
        inst.setup(0.0)
        inst.set("theta1_0", angle)
        inst.enter_initialization()
        inst.exit_initialization()

    try:
        start(0.1)
        assert read_theta1() == 0 and theta1[0] == 0.1
        u[0] = 2.0
        assert write_u() == 0
        inst.do_step(0.0, 0.01)
        saved = inst.get_state()
        inst.do_step(0.01, 0.01)
        assert read_dx() == 0 and dx[0] == pytest.approx(0.04, rel=1e-12)
        inst.set_state(saved)
        assert read_dx() == 0 and dx[0] == pytest.approx(0.02, rel=1e-12)
        inst.free_state(saved)
        inst._fmu.reset()
        start(-0.3)
        assert read_theta1() == 0 and theta1[0] == -0.3
        u[0] = -1.0
        assert write_u() == 0
        inst.do_step(0.0, 0.01)
        assert read_dx() == 0 and dx[0] == pytest.approx(-0.01, rel=1e-12)
    finally:
        inst.free()


def test_an_unzipped_fmu_is_reused_once_freed_and_removed_at_exit(crane_fmus):
    """Instances alive together each have their own folder; a freed one's folder, with its library still loaded,
    serves the next instance, which runs from a fresh fmi2Instantiate (the same step gives the same figures)."""
    import subprocess
    import sys

    script = """
import sys
from crane_fmu.cosim import open_instance
a, b = open_instance(sys.argv[1], "a"), open_instance(sys.argv[1], "b")
assert a._unzip != b._unzip
folders, libraries = {a._unzip, b._unzip}, {id(a._fmu), id(b._fmu)}

def swing(inst):
    inst.set("theta1_0", 0.2)
    inst.setup(0.0)
    inst.enter_initialization()
    inst.exit_initialization()
    inst.do_step(0.0, 0.01)
    return inst.get("theta1")

first = swing(a)
a.free()
b.free()
c = open_instance(sys.argv[1], "c")
assert c._unzip in folders and id(c._fmu) in libraries, (c._unzip, folders)
assert swing(c) == first and first != 0.2
c.free()
print(*folders)
"""
    done = subprocess.run([sys.executable, "-c", script, str(crane_fmus["plant"])], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    folders = done.stdout.split()
    assert len(folders) == 2 and not any(Path(f).exists() for f in folders)


@pytest.mark.parametrize("folder", ["fmus", "fmi3"])
def test_an_fmu_runs_after_another_of_its_core_whose_folder_is_gone(fmu_dir, folder):
    """Python FMUs of one core share its modules in a host's interpreter: after fmpy ran Gust (whose folder it
    then removed), MpcController, whose model module Gust never imported, must still start (a fresh process:
    in this one an earlier test may have imported every module already)."""
    import subprocess
    import sys

    script = """
import sys
from fmpy import simulate_fmu
simulate_fmu(sys.argv[1], stop_time=0.01, output_interval=1e-3)
simulate_fmu(sys.argv[2], stop_time=0.01, output_interval=1e-3)
"""
    fmus = [str(fmu_dir.parent / folder / f"{name}.fmu") for name in ("Gust", "MpcController")]
    done = subprocess.run([sys.executable, "-c", script, *fmus], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]


@pytest.mark.parametrize("folder", ["fmus", "fmi3"])
def test_an_fmu_run_again_from_a_new_folder_finds_the_modules_its_first_folder_had(fmu_dir, folder):
    """Python keeps an FMU's module from its first folder: fmpy ran TrajectoryPlanner with a ZV shaper (and
    removed that folder), then runs it again, from a new folder, planning the shortest move, whose modules (the
    MPC's, imported only then) must come from the new folder (a fresh process, as above)."""
    import subprocess
    import sys

    script = """
import sys
from fmpy import simulate_fmu
simulate_fmu(sys.argv[1], stop_time=0.01, output_interval=1e-3, start_values={"shaper": 2})
simulate_fmu(sys.argv[1], stop_time=0.01, output_interval=1e-3, start_values={"shaper": 5})
"""
    planner = str(fmu_dir.parent / folder / "TrajectoryPlanner.fmu")
    done = subprocess.run([sys.executable, "-c", script, planner], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]


@pytest.mark.parametrize("folder", ["fmus", "fmi3"])
def test_the_python_code_is_one_archive_with_checked_bytecode_for_this_python(fmu_dir, folder):
    """A host unpacks the FMU afresh each time: few files, and .pyc that spare the compile (refused if the
    source changes: hash-based, checked, PEP 552)."""
    import importlib.util
    import io
    import sys
    import zipfile

    def check(pyc, source):
        assert pyc[:4] == importlib.util.MAGIC_NUMBER
        assert int.from_bytes(pyc[4:8], "little") == 0b11
        assert pyc[8:16] == importlib.util.source_hash(source)

    with zipfile.ZipFile(fmu_dir.parent / folder / "CranePlant.fmu") as fmu:
        loose = [n for n in fmu.namelist() if n.startswith("resources/") and n.endswith(".py")]
        assert len(loose) == 1  # the slave script every wrapper imports
        script = loose[0].removeprefix("resources/")[:-3]
        check(fmu.read(f"resources/__pycache__/{script}.{sys.implementation.cache_tag}.pyc"), fmu.read(loose[0]))
        archive = zipfile.ZipFile(io.BytesIO(fmu.read("resources/python.zip")))
    sources = [n for n in archive.namelist() if n.endswith(".py")]
    assert {n.split("/")[0] for n in sources} == {script.rsplit("_", 1)[0], "pythonfmu" if folder == "fmus"
                                                  else "pythonfmu3"}
    for name in sources:
        check(archive.read(name[:-3] + ".pyc"), archive.read(name))


def test_no_limit_is_a_finite_start_value_and_setting_every_start_value_changes_nothing(fmu_dir):
    """Hosts read every parameter and log an error for +-inf (OMSimulator: 8 per run of paper), so a limit that is
    off starts at 1e60, which the models read as none: every Real start value of every FMU we build is finite; a
    host that sets every parameter to its start value (Simulink does) gets the system's own run, and INF where
    the start is 1e60 gives it too, bit for bit (paper, 2 s)."""
    from crane_fmu import systems
    from crane_fmu.build_scripts.build_fmus import fmi3_dir
    from crane_fmu.build_scripts.native import native_dir
    from crane_fmu.cosim import run

    folders = [fmu_dir, fmi3_dir(fmu_dir), native_dir(fmu_dir, 2), native_dir(fmu_dir, 3)]
    for path in (p for folder in folders for p in sorted(folder.glob("*.fmu"))):
        md = read_model_description(str(path))
        for v in md.modelVariables:
            if v.type in ("Real", "Float64") and v.start is not None:
                assert math.isfinite(float(v.start)), (path.name, v.name, v.start)
    paper = systems.get("paper")
    own = run(paper, fmu_dir, stop_time=2.0).columns()
    starts = {name: {v.name: v.start if v.type == "String" else float(v.start)
                     for v in read_model_description(str(path)).modelVariables if v.causality == "parameter"}
              for name, path in paper.fmus(fmu_dir).items()}
    infinite = {"plant": {"u_max": math.inf, "v_max": math.inf, "x_min": -math.inf, "x_max": math.inf,
                          "l1_max": math.inf, "dl1_max": math.inf},
                "controller": {"u_max": math.inf, "v_max": math.inf}}
    for values in (starts, infinite):
        again = run(paper.with_parameters(values), fmu_dir, stop_time=2.0).columns()
        assert all(np.array_equal(again[k], own[k]) for k in own)
    assert starts["plant"]["x_min"] == -1e60 and starts["controller"]["u_max"] == 1e60
