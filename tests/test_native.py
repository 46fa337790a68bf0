"""The native (C) CranePlant FMU against its specification, the Python plant.

The native FMUs are built by the session's ``fmu_dir`` fixture (``build_all`` builds them
into ``build/native`` beside ``build/fmus`` when a C compiler is found). The Python model is
the specification: every test here compares the native FMU with the Python model or FMU.
"""

import os
import random
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from helpers import FREE_SWING_MAX_THETA2_DEG
from native_fmus import close, compiler, messages, open_native, steps_after_restore

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import fmi3_dir
from crane_fmu.build_scripts.model_exchange import me_variables
from crane_fmu.build_scripts.native import FOLDERS, MODELS_DIR, source_path
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cosim import run
from crane_fmu.model import plant
from crane_fmu.model.parameters import PlantParameters

PLANT = components.get("CranePlant")


def _python_fmu(fmu_dir, version):
    return (fmu_dir if version == 2 else fmi3_dir(fmu_dir)) / "CranePlant.fmu"


# ---- one source: the same variables as the Python FMU ----------------------------------------------------------

def _variables(path):
    md = read_model_description(str(path))
    return [(v.name, v.valueReference, v.causality, v.variability, v.initial, v.start, v.unit, v.displayUnit,
             v.description) for v in md.modelVariables], md


def _units(path):
    """``[(unit, {base unit exponents}, [(display unit, factor)])]`` from modelDescription.xml."""
    with zipfile.ZipFile(path) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    return [(u.get("name"), dict(u.find("BaseUnit").attrib),
             [(d.get("name"), float(d.get("factor"))) for d in u.findall("DisplayUnit")])
            for u in root.find("UnitDefinitions")]


@pytest.mark.parametrize("version", [2, 3])
def test_native_model_description_has_the_python_fmus_variables(fmu_dir, native, version):
    """Names, value references, causalities, start values, units, display units, descriptions: identical, then
    the Model Exchange variables (locals) that only the native FMU has."""
    ours, md = _variables(native[version] / "CranePlant.fmu")
    theirs, py_md = _variables(_python_fmu(fmu_dir, version))
    assert ours[:len(theirs)] == theirs
    assert [v[0] for v in ours[len(theirs):]] == [v.name for v in me_variables(plant.COMPONENT)]
    assert {v[2] for v in ours[len(theirs):]} == {"local"}
    assert md.coSimulation.modelIdentifier == py_md.coSimulation.modelIdentifier == "CranePlant"
    native_units = _units(native[version] / "CranePlant.fmu")
    assert all(unit in native_units for unit in _units(_python_fmu(fmu_dir, version)))
    assert (md.defaultExperiment.stopTime, md.defaultExperiment.stepSize) == \
        (py_md.defaultExperiment.stopTime, py_md.defaultExperiment.stepSize)
    assert [u.variable.name for u in md.outputs] == [u.variable.name for u in py_md.outputs]
    assert validate_fmu(str(native[version] / "CranePlant.fmu")) == []


def test_the_c_variable_header_is_generated_from_the_table(native):
    """The value references and start values the C model uses are the table's (a generated header)."""
    with zipfile.ZipFile(native[2] / "CranePlant.fmu") as z:
        header = z.read("sources/CranePlant_variables.h").decode()
        names = [n for n in z.namelist() if n.startswith("binaries/")]
    for vr, v in enumerate(plant.VARIABLES):
        assert f"VR_{v.name} = {vr}," in header
    assert sorted(names) == ["binaries/linux64/CranePlant.so"] + (
        ["binaries/win64/CranePlant.dll"] if shutil.which("x86_64-w64-mingw32-gcc") else [])
    assert not any((folder / "CranePlant_variables.h").exists() for folder in FOLDERS)  # generated, never committed


# ---- the equations: accelerations at random states --------------------------------------------------------------

ACCEL_HARNESS = r"""
#include <stdio.h>
#include "plant_equations.h"
int main(void) {
    PlantParameters p;
    double s[4], u, l1, dl1, dd[2];
    Load load;
    while (scanf("%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &p.m1, &p.m2, &p.l1, &p.l2,
                 &p.g, &s[0], &s[1], &s[2], &s[3], &u, &l1, &dl1, &load.hoist, &load.f1, &load.f2, &load.c1,
                 &load.c2) == 17) {
        angular_accelerations(s[0], s[1], s[2], s[3], u, &p, l1, dl1, &load, dd);
        printf("%.17g %.17g\n", dd[0], dd[1]);
    }
    return 0;
}
"""


@pytest.fixture(scope="module")
def accel_harnesses(tmp_path_factory):
    """The C accelerations with glibc's libm and with the portable math of the Windows build."""
    folder = tmp_path_factory.mktemp("accel")
    (folder / "harness.c").write_text(ACCEL_HARNESS)
    built = {}
    for name, flags in (("libm", []), ("portable", ["-DCRANE_OWN_MATH"])):
        built[name] = folder / name
        subprocess.run([compiler(), "-O2", "-Wall", "-Werror", "-ffp-contract=off", *flags, f"-I{MODELS_DIR}",
                        str(folder / "harness.c"), str(MODELS_DIR / "plant_equations.c"),
                        str(MODELS_DIR / "portable_math.c"),
                        "-o", str(built[name]), "-lm"], check=True)
    return built


def _random_cases(n, seed):
    rng = random.Random(seed)
    cases = []
    for i in range(n):
        p = (rng.uniform(0.5, 20), rng.choice([0.0, rng.uniform(0.0, 20)]), rng.uniform(0.2, 5), rng.uniform(0.1, 3),
             rng.uniform(1, 25))
        state = (rng.uniform(-3, 3), rng.uniform(-5, 5), rng.uniform(-3, 3), rng.uniform(-5, 5))
        u, l1, dl1 = rng.uniform(-10, 10), rng.uniform(0.2, 5), rng.uniform(-2, 2) * (i % 2)
        load = tuple(rng.uniform(-5, 5) * (i % 3 > 0) for _ in range(3)) + (rng.uniform(0, 2), rng.uniform(0, 2))
        if p[1] == 0.0:
            load = load[:2] + (0.0, load[3], 0.0)  # F2 and c2 act on no payload
        cases.append((p, state, u, l1, dl1, load))
    return cases


@pytest.mark.quick
@pytest.mark.parametrize("math_library", ["libm", "portable"])
def test_native_accelerations_equal_the_python_model_at_random_states(accel_harnesses, math_library):
    """Eqs (8)-(9) with hoisting, forces and damping, 2000 random states: 1e-12 relative (glibc's libm: bit for bit)."""
    cases = _random_cases(2000, seed=26)
    text = "\n".join(" ".join(repr(float(x)) for x in (*p, *s, u, l1, dl1, *load)) for p, s, u, l1, dl1, load in cases)
    out = subprocess.run([str(accel_harnesses[math_library])], input=text, capture_output=True, text=True, check=True)
    native_dd = np.array([[float(x) for x in line.split()] for line in out.stdout.splitlines()])
    python_dd = np.array([plant.angular_accelerations(*s, u, PlantParameters(*p), l1, (dl1, load[0], *load[1:]))
                          for p, s, u, l1, dl1, load in cases])
    assert native_dd.shape == python_dd.shape == (2000, 2)
    scale = np.maximum(np.abs(python_dd), 1.0)  # relative, and absolute where an acceleration is below 1 rad/s2
    assert np.max(np.abs(native_dd - python_dd) / scale) <= 1e-12
    if math_library == "libm":  # the same libm and the same operations: the same bits
        assert np.array_equal(native_dd, python_dd)


# ---- whole runs through our master: native plant vs Python plant -------------------------------------------------

RUNS = {  # name: (built-in system, plant parameters beyond the system's)
    "section5": ("paper", {}),
    "free-swing": ("free", {}),
    "hoisting": ("hoist-transport", {}),
    "disturbance": ("lqr", {"F1": 0.8, "F2": -0.5, "tau": 0.05, "v_max": 0.3, "c1": 0.4, "c2": 0.25}),
}


def _run(name, folder):
    system_name, extra = RUNS[name]
    return run(systems.bind(systems.get(system_name).with_parameters({"plant": extra})), folder).columns()


@pytest.mark.parametrize("name", list(RUNS))
def test_native_runs_equal_the_python_plant_over_their_whole_length(fmu_dir, native, name):
    """Section V (native plant and controller), free swing, hoisting, disturbances: 1e-9 at every step."""
    ours, theirs = _run(name, native[2]), _run(name, fmu_dir)
    assert list(ours) == list(theirs)
    assert len(ours["time"]) == len(theirs["time"]) > 10_000
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    assert worst <= 1e-9  # glibc's libm in both: in practice 0
    if name == "disturbance":  # the run does exercise what it names
        assert np.max(np.abs(theirs["plant.dx"])) == pytest.approx(0.3, abs=1e-9)
    if name == "hoisting":
        assert np.ptp(theirs["plant.l1_now"]) > 0.9


def test_free_swing_max_theta2_in_our_master_is_the_python_fmus(native):
    columns = run(systems.get("free"), native[2]).columns()
    assert np.degrees(np.max(columns["plant.theta2"])) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)


# ---- fmpy ----------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_simulates_the_native_fmu_like_the_python_fmu(fmu_dir, native, version):
    """fmpy.simulate_fmu, default experiment (20 s at 1 ms): the free swing, to the last bit, max theta2 15.5976 deg."""
    ours = fmpy.simulate_fmu(str(native[version] / "CranePlant.fmu"), output_interval=1e-3)
    theirs = fmpy.simulate_fmu(str(_python_fmu(fmu_dir, version)), output_interval=1e-3)
    assert len(ours) == len(theirs) == 20_001
    for name in ("x", "theta1", "theta2", "dtheta1", "dtheta2", "energy"):
        assert np.max(np.abs(ours[name] - theirs[name])) <= 1e-9, name
    assert np.degrees(np.max(ours["theta2"])) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)


def test_fmpy_command_line_simulates_the_native_fmu(native, tmp_path):
    out = tmp_path / "fmpy.csv"
    subprocess.run([str(Path(sys.executable).parent / "fmpy"), "simulate", str(native[2] / "CranePlant.fmu"),
                    "--output-interval", "0.001", "--output-file", str(out), "--output-variables", "theta2"],
                   check=True, capture_output=True)
    theta2 = np.genfromtxt(out, delimiter=",", names=True)["theta2"]
    assert np.degrees(theta2.max()) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)


# ---- refusals and failures: the Python FMU's rules and messages ------------------------------------------------------

INF, NAN = float("inf"), float("nan")
REFUSED = [{"m1": -1.0}, {"m1": 0.0}, {"m2": -0.5}, {"l1": NAN}, {"l2": INF}, {"g": 0.0}, {"max_substep": -1e-3},
           {"c1": -1.0}, {"c2": INF}, {"tau": NAN}, {"l1_min": -0.1}, {"u_max": 0.0}, {"v_max": -INF},
           {"dl1_max": NAN}, {"m2": 0.0, "c2": 0.5}, {"x_min": 1.0, "x_max": 1.0}, {"x0": INF}, {"dtheta2_0": NAN},
           {"x0": 5.0, "x_max": 2.0}, {"l1_min": 1.5}, {"l1_max": 0.25}, {"x_min": NAN}]


@pytest.mark.parametrize("settings", REFUSED, ids=lambda s: ",".join(f"{k}={v}" for k, v in s.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, settings):
    ours = messages(native[2] / "CranePlant.fmu", settings, instance_name="plant")
    theirs = messages(fmu_dir / "CranePlant.fmu", settings, instance_name="plant")
    assert ours == theirs
    assert ours[0][-2] == "exit: 3" and ours[1][-1].startswith("fmi2ExitInitializationMode: ")


STEPS = {
    "non-finite state": ({"theta1_0": 3.0}, [(0.0, 1e-3, {"u": 1e300})]),
    "rail end": ({"x_max": 0.01}, [(0.0, 0.5, {"u": 2.0})]),
    "F2 without payload": ({"m2": 0.0}, [(0.0, 1e-3, {"F2": 1.0})]),
    "step not finite": ({}, [(0.0, NAN, {})]),
    "step negative": ({}, [(0.0, -1e-3, {})]),
    "too many sub-steps": ({"max_substep": 1e-9}, [(0.0, 1.0, {})]),
    "hoist limit reached": ({"l1_max": 1.01}, [(0.0, 0.5, {"hoist": 1.0}), (0.5, 0.5, {"hoist": 1.0})]),
}


def test_a_hoist_limit_reached_at_rest_is_a_note_and_one_hit_at_speed_a_warning(fmu_dir, native):
    """The end of a planned hoist (the cable arrives at 1 mm/s) is information, logged only to a host that asks
    for every message; a cable stopped at 1 m/s by its limit is a warning, logged always. Both FMUs alike."""
    at_rest = ({"l1": 1.0000012, "l1_min": 1.0}, [(0.0, 1e-3, {"hoist": -1.0}), (1e-3, 1e-3, {"hoist": 0.0})])
    at_speed = ({"l1_max": 1.01}, [(0.0, 0.5, {"hoist": 1.0}), (0.5, 0.5, {"hoist": 1.0})])
    logs = {}
    for name, (settings, steps) in (("at rest", at_rest), ("at speed", at_speed)):
        for logging_on in (False, True):
            runs = [messages(folder / "CranePlant.fmu", settings, steps, instance_name="plant", logging_on=logging_on)
                    for folder in (native[2], fmu_dir)]
            hoist = [[m for m in log if m.startswith("hoist:")] for _, log in runs]  # the Python FMU says more
            assert runs[0][0] == runs[1][0] == ["end"] and hoist[0] == hoist[1], (name, logging_on)
            logs[name, logging_on] = hoist[0]
    assert logs["at rest", False] == [] and logs["at rest", True] == [
        "hoist: l1 reached 1.0 m at t = 0.002 s and is held there"]
    assert logs["at speed", False] == logs["at speed", True] and len(logs["at speed", False]) == 1
    assert logs["at speed", False][0].startswith("hoist: l1 hit the limit 1.01 m at 0.")


@pytest.mark.parametrize("case", list(STEPS))
def test_discards_and_step_errors_have_the_python_fmus_status_and_message(fmu_dir, native, case):
    settings, steps = STEPS[case]
    ours = messages(native[2] / "CranePlant.fmu", settings, steps, instance_name="plant")
    theirs = messages(fmu_dir / "CranePlant.fmu", settings, steps, instance_name="plant")
    assert ours == theirs
    assert ours[1], "a message is logged"


# ---- FMU state, with the integrator's --------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_fmu_state_saved_serialised_and_restored_repeats_the_steps_exactly(native, version, tmp_path):
    """The drive's lagged acceleration and the cable's state are part of it (tau > 0, hoisting)."""
    fmu, vr, set_, get = open_native(native[version] / "CranePlant.fmu", version, {"tau": 0.08, "v_max": 0.5},
                                     instance_name="p")
    fmu.exitInitializationMode()
    outputs = [vr[n] for n in ("x", "dx", "theta1", "theta2", "l1_now", "dl1_now", "ddx")]

    def steps(k0, n):
        rows = []
        for k in range(k0, k0 + n):
            set_([vr["u"], vr["hoist"]], [np.sin(k * 0.01), 0.3 * np.cos(k * 0.02)])
            fmu.doStep(k * 1e-3, 1e-3)
            rows.append(get(outputs))
        return rows

    steps(0, 300)
    first, again, third = steps_after_restore(fmu, version, steps, 300, 300)
    close(fmu)
    assert first == again == third
    assert len({round(r[-1], 6) for r in first}) > 10  # the drive's acceleration moves: the lag is in the state


# ---- the source FMU -----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_the_source_fmu_compiles_with_fmpy_and_runs(native, version, tmp_path, monkeypatch):
    """fmpy's build_platform_binary (CMake; fmpy 0.3.32 has no compile_platform_binary) on the sources alone."""
    from fmpy.build import build_platform_binary

    if shutil.which("cmake") is None and not (Path(sys.executable).parent / "cmake").exists():
        pytest.skip("no cmake")
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(native[version] / "CranePlant.fmu") as z:
        z.extractall(folder)
    shutil.rmtree(folder / "binaries")
    monkeypatch.setenv("PATH", str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"])  # the venv's cmake
    (tmp_path / "cmake").mkdir()
    build_platform_binary(folder, build_dir=tmp_path / "cmake")
    platform = "linux64" if version == 2 else "x86_64-linux"
    assert (folder / "binaries" / platform / "CranePlant.so").exists()
    result = fmpy.simulate_fmu(str(folder), output_interval=1e-3)
    reference = fmpy.simulate_fmu(str(native[version] / "CranePlant.fmu"), output_interval=1e-3)
    assert np.degrees(np.max(result["theta2"])) == pytest.approx(FREE_SWING_MAX_THETA2_DEG, abs=5e-5)
    # FMI 2.0 sources use the C library's libm (here glibc: the same bits); FMI 3.0 ones the portable math
    assert np.max(np.abs(result["theta1"] - reference["theta1"])) <= 1e-9


STRICT = ["-c", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wno-unused-parameter", "-Werror", "-DCRANE_OWN_MATH"]


def test_the_model_and_framework_compile_without_warnings_under_strict_flags(tmp_path):
    """ISO C99, -Wall -Wextra -Werror (less unused parameters: the stubs of unsupported calls), every file."""
    from crane_fmu.build_scripts.native import variables_header

    (tmp_path / "CranePlant_variables.h").write_text(variables_header(PLANT))
    for name in ("BacksteppingController", "LqrController"):
        (tmp_path / f"{name}_variables.h").write_text(variables_header(components.get(name)))
    includes = [f"-I{tmp_path}", *(f"-I{folder}" for folder in FOLDERS), f"-I{fmi_headers()}"]
    for name in ("fmi2Functions.c", "fmi3Functions.c", "instance.c", "continuous.c", "py_repr.c", "component.c",
                 "crane_plant.c", "plant_continuous.c", "backstepping.c", "lqr.c", "lqr_design.c", "plant_equations.c",
                 "linalg.c", "portable_math.c"):
        subprocess.run([compiler(), *STRICT, *includes, str(source_path(name)), "-o", str(tmp_path / "f.o")],
                       check=True)


# ---- the build and the benchmark -----------------------------------------------------------------------------------

def test_without_a_c_compiler_the_build_warns_or_refuses(monkeypatch, tmp_path):
    from crane_fmu.build_scripts import native as native_build

    monkeypatch.setattr(native_build.shutil, "which", lambda name: None)
    log = []
    assert native_build.build_native(tmp_path / "fmus", ["CranePlant"], log=log.append) == []
    assert log == ["warning: no C compiler found (set CC or install gcc); no native FMUs built"]
    with pytest.raises(native_build.NativeUnavailable, match="no C compiler"):
        native_build.build_native(tmp_path / "fmus", ["CranePlant"], required=True)
    python_only = next(c.model_identifier for c in components.registered() if not c.native)
    assert native_build.build_native(tmp_path / "fmus", [python_only]) == []  # nothing to port: no folder
    assert not (tmp_path / "native").exists()


def test_bench_native_runs_and_prints_its_figures(native, capsys):
    """A smoke test only: the figures are measured with crane-fmu bench --native, not asserted here."""
    from crane_fmu.cli import main

    assert main(["bench", "--native", "--stop-time", "0.2", "--repeat", "1"]) == 0
    printed = capsys.readouterr().out
    assert "2. native pair (plant + controller), our master" in printed and "3. native pair in the C host" in printed
    assert "4. whole processes" in printed
