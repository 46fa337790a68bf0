"""The native CranePlant as a host integrates it (Model Exchange), in hosts nobody here wrote and in fmpy.

One FMU holds both interfaces; its co-simulation (RK4 at 1 ms sub-steps, within about 1e-12 rad of the
ODE over these runs) is the reference for the Model Exchange runs with the hosts' solver at a relative
tolerance of 1e-10: the angles agree within 1e-6 rad. A rail end ends the simulation at its state event,
which the host locates within 1e-6 s of the exact time. The directional derivatives are the Python
model's exact tangents (plant_continuous.jacobians) and central differences of the derivatives agree.
"""

import ctypes
import math
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu
from native_fmus import extracted
from third_party_hosts import CLEAN_ENV, FMUCHECK, OMSIMULATOR, SAME, fmusim_me, read_oms_mat, run_tool, tool

from crane_fmu.analysis.linearize import linearize
from crane_fmu.build_scripts.model_exchange import ROUNDING
from crane_fmu.model import plant
from crane_fmu.model import plant_continuous as me

RTOL = 1e-10     # the hosts' solver tolerance
ANGLES = 1e-6    # rad: Model Exchange against co-simulation
EVENT = 1e-6     # s: the rail end's state event
CASES = {        # name: (start values, stop time)
    "free swing": ({}, 2.0),  # Section V: released at theta1 = 10 deg
    "hoisting": ({"hoist": 0.3, "u": 0.2}, 1.0),
}
RAIL = ({"u": 1.0, "x_max": 0.5}, 2.0)  # x = t^2 / 2 reaches x_max = 0.5 m at t = 1 s exactly


@pytest.fixture(scope="module", params=[2, 3], ids=["FMI 2.0", "FMI 3.0"])
def plant_fmu(request, native):
    return native[request.param] / "CranePlant.fmu"


def _run(path, interface, start, stop, step=0.05):
    kwargs = {"solver": "CVode", "relative_tolerance": RTOL} if interface == "ModelExchange" else {}
    return fmpy.simulate_fmu(str(path), fmi_type=interface, start_values=start, stop_time=stop,
                             output_interval=step, output=["x", "theta1", "theta2"], **kwargs)


def _co_simulation(path, start, stop, step):
    return _run(path, "CoSimulation", start, stop, step)


def test_the_fmu_is_valid_and_declares_model_exchange(plant_fmu):
    assert validate_fmu(str(plant_fmu)) == []
    md = fmpy.read_model_description(str(plant_fmu))
    assert md.modelExchange is not None and md.coSimulation is not None
    assert [d.variable.derivative.name for d in md.derivatives] == list(me.STATES)
    assert len(md.eventIndicators if md.fmiVersion.startswith("3") else range(md.numberOfEventIndicators)) == 8


@pytest.mark.parametrize("case", CASES)
def test_fmpy_integrates_it_as_the_co_simulation_steps_it(plant_fmu, case):
    start, stop = CASES[case]
    ours, theirs = _co_simulation(plant_fmu, start, stop, 0.05), _run(plant_fmu, "ModelExchange", start, stop)
    assert np.allclose(theirs["time"], ours["time"])
    for angle in ("theta1", "theta2"):
        assert np.abs(theirs[angle] - ours[angle]).max() < ANGLES, (case, angle)
    assert np.abs(ours["theta1"]).max() > 0.1  # it swings


def test_a_rail_end_ends_the_run_at_its_state_event(plant_fmu):
    start, stop = RAIL
    result = _run(plant_fmu, "ModelExchange", start, stop, step=0.01)
    assert abs(result["time"][-1] - 1.0) < EVENT
    assert abs(result["x"][-1] - 0.5) < EVENT


def test_the_cable_is_held_from_the_state_event_at_its_limit(plant_fmu):
    """Hoisting at 0.3 m/s2 from l1 = 1 m reaches l1_max = 1.1 m at t = sqrt(2 * 0.1 / 0.3) s; from that event the
    cable is held there at rest (the hoist still pulls)."""
    result = fmpy.simulate_fmu(str(plant_fmu), fmi_type="ModelExchange", solver="CVode", relative_tolerance=RTOL,
                               start_values={"hoist": 0.3, "l1_max": 1.1}, stop_time=1.5, output_interval=0.05,
                               output=["l1_now", "dl1_now"])
    held = np.flatnonzero(result["l1_now"] == 1.1)
    assert abs(result["time"][held[0]] - math.sqrt(2 * 0.1 / 0.3)) < EVENT
    assert result["l1_now"].max() == 1.1 and np.all(result["l1_now"][held[0]:] == 1.1)
    assert np.all(result["dl1_now"][held[0] + 1:] == 0.0)  # the first row at the event is before its update


def _fmusim(path, start, stop, tmp_path, step=0.05):
    return fmusim_me(path, start, stop, step, tmp_path / f"{path.parent.name}.csv", RTOL)


@pytest.mark.parametrize("case", CASES)
def test_fmusim_integrates_it_with_cvode(plant_fmu, case, tmp_path):
    start, stop = CASES[case]
    theirs, ours = _fmusim(plant_fmu, start, stop, tmp_path), _co_simulation(plant_fmu, start, stop, 0.05)
    assert np.allclose(theirs["time"], ours["time"])
    for angle in ("theta1", "theta2"):
        assert np.abs(theirs[angle] - ours[angle]).max() < ANGLES, (case, angle)


def test_fmusim_stops_at_the_rail_end(plant_fmu, tmp_path):
    start, stop = RAIL
    theirs = _fmusim(plant_fmu, start, stop, tmp_path, step=0.01)
    assert abs(theirs["time"][-1] - 1.0) < EVENT and abs(theirs["x"][-1] - 0.5) < EVENT


def test_omsimulator_integrates_the_fmi2_plant(native, tmp_path):
    """OMSimulator takes a lone FMU as Model Exchange (CVODE); its FMI 3.0 import crashes (tools README)."""
    path = native[2] / "CranePlant.fmu"
    code, log = run_tool([tool(OMSIMULATOR), "--stopTime=2", f"--tolerance={RTOL!r}", "--resultFile=out.mat",
                          f"--tempDir={tmp_path}", path], tmp_path)
    assert code == 0 and "0 errors" in log and "NumRhsEvals" in log, log[-2000:]  # CVODE: Model Exchange
    theirs = read_oms_mat(tmp_path / "out.mat", 1e-3)  # its results every 1 ms (its default step)
    ours = _co_simulation(path, {}, 2.0, 0.05)
    on_grid = theirs["k"] % 50 == 0
    assert on_grid.sum() == len(ours["time"]) == 41
    for angle in ("theta1", "theta2"):
        assert np.abs(theirs[angle][on_grid] - ours[angle]).max() < ANGLES


def _documented_oms_script():
    """The interoperability page's OMSimulator recipe: a Lua script (its command line sets no start value)."""
    page = (Path(__file__).parent.parent / "docs" / "guide" / "interoperability.md").read_text()
    return re.search(r"## Model Exchange.*?```lua\n(.*?)```", page, re.S).group(1)


def _omsimulator_script(script, tmp_path):
    """Run an OMSimulator Lua script in tmp_path (beside a link to the build's folder); its log."""
    (tmp_path / "run.lua").write_text(script)
    code, log = run_tool([tool(OMSIMULATOR), "run.lua"], tmp_path)
    assert code == 0 and "0 errors" in log and "NumRhsEvals" in log, log[-2000:]  # CVODE: Model Exchange
    return log


def _fmi2_plant(native, tmp_path):
    (tmp_path / "build").symlink_to(native[2].parent)
    return native[2] / "CranePlant.fmu"


def test_the_documented_omsimulator_recipe_hoists_as_the_co_simulation(native, tmp_path):
    """The page's Lua script as written: OMSimulator's Model Exchange run of the hoisting case (FMI 2.0) is the
    co-simulation's within 1e-6 rad, and the cable follows l1 = 1 + hoist t^2 / 2 (no limit is reached)."""
    path = _fmi2_plant(native, tmp_path)
    script = _documented_oms_script()
    assert 'oms_setTolerance("model.root", 1e-10)' in script and 'oms_setStopTime("model", 1.0)' in script
    _omsimulator_script(script, tmp_path)
    theirs = read_oms_mat(tmp_path / "hoist.mat", 1e-3)
    start, stop = CASES["hoisting"]
    ours = _co_simulation(path, start, stop, 0.05)
    on_grid = theirs["k"] % 50 == 0
    assert on_grid.sum() == len(ours["time"]) == 21
    for angle in ("theta1", "theta2"):
        assert np.abs(theirs[f"model.root.plant.{angle}"][on_grid] - ours[angle]).max() < ANGLES
    t = theirs["k"] * 1e-3
    assert np.abs(theirs["model.root.plant.l1_now"] - (1.0 + start["hoist"] * t ** 2 / 2)).max() < ANGLES


def test_omsimulator_locates_the_rail_end(native, tmp_path):
    """The rail end's state event at t = 1 s, located by OMSimulator's CVODE within 1e-6 s (the FMU names the
    time the host gave it); OMSimulator does not end the run there (it integrates on to its stop time)."""
    _fmi2_plant(native, tmp_path)
    start, stop = RAIL
    script = _documented_oms_script().replace('"hoist.mat"', '"rail.mat"')
    script = re.sub(r'oms_setStopTime\("model", [^)]*\)', f'oms_setStopTime("model", {stop!r})', script)
    settings = "".join(f'oms_setReal("model.root.plant.{k}", {v!r})\n' for k, v in start.items())
    script = re.sub(r'(oms_setReal\([^\n]*\n)+', settings, script)
    log = _omsimulator_script(script, tmp_path)
    located = re.findall(r"reached the rail end x_max = 0.5 m \(x = (\S+) m\) at t = (\S+) s", log)
    assert len(located) == 1, log[-2000:]
    x, t = map(float, located[0])
    assert abs(t - 1.0) < EVENT and abs(x - 0.5) < EVENT
    theirs = read_oms_mat(tmp_path / "rail.mat", 1e-3)
    assert theirs["model.root.plant.x"].max() > 0.5 + 0.1  # past the rail end: the request to end was not heeded


def test_fmucheck_reports_nothing(native, tmp_path):
    path = native[2] / "CranePlant.fmu"
    code, log = run_tool([tool(FMUCHECK), "-h", "1e-3", "-s", "2", "-o", tmp_path / "out.csv", path], tmp_path)
    assert code == 0, log[-2000:]
    assert "Version returned from ME FMU" in log  # the Model Exchange interface was checked
    assert "0 warning(s) and error(s)" in log and "\t0 Warning(s)" in log and "\t0 Error(s)" in log, log[-2000:]


# ---- the Windows DLL's Model Exchange interface, under Wine ----

def _host_rows(command, *args, cwd=None, env=None):
    done = subprocess.run([*map(str, command), *map(str, args)], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return np.array([[float(v) for v in line.split(",")] for line in done.stdout.replace("\r", "").splitlines()])


WINDOWS = {2: ("me", "linux64", "win64"), 3: ("me3", "x86_64-linux", "x86_64-windows")}  # host mode, binaries


@pytest.mark.parametrize("version", [2, 3])
def test_the_windows_dll_integrated_under_wine_gives_the_linux_run(native, host, windows_host, wine_env, tmp_path,
                                                                   version):
    """host.c's ``me`` mode (``me3`` for FMI 3.0: Model Exchange, RK4 at 1 ms over the FMU's derivatives, an event at
    a step's end where an indicator changes sign) on the Linux library and on the Windows DLL under Wine: the free
    swing, the hoisting run and the run into the rail end agree to 1e-9 (the DLL computes with the same math source,
    mingw's libm is not used). The Linux run is the co-simulation's RK4 at 1 ms to rounding (the same steps over
    the same derivatives), and it ends at the step that reaches the rail end (x_max = 0.5 m at t = 1 s)."""
    path = native[version] / "CranePlant.fmu"
    mode, linux_platform, windows_platform = WINDOWS[version]
    with zipfile.ZipFile(path) as z:
        z.extractall(tmp_path)
    dll = tmp_path / "binaries" / windows_platform / "CranePlant.dll"
    if not dll.exists():
        pytest.skip("the FMU has no Windows binary (mingw-w64 missing at build time)")
    shutil.copy(windows_host, tmp_path)
    shutil.copy(dll, tmp_path)
    md = fmpy.read_model_description(str(path))
    token = md.instantiationToken if version == 3 else md.guid
    vr = {v.name: v.valueReference for v in md.modelVariables}
    indicators = len(md.eventIndicators) if version == 3 else md.numberOfEventIndicators
    observed = ["x", "theta1", "theta2"]
    for case, (start, stop) in {**CASES, "rail end": RAIL}.items():
        arguments = [round(stop / 1e-3), 1e-3, len(md.derivatives), indicators,
                     *(f"{vr[k]}={v!r}" for k, v in start.items()), *(vr[k] for k in observed)]
        linux = _host_rows([host, mode, tmp_path / "binaries" / linux_platform / "CranePlant.so", token], *arguments,
                           env=CLEAN_ENV)
        windows = _host_rows(["wine", tmp_path / "host.exe", mode, dll.name, token], *arguments, cwd=tmp_path,
                             env=wine_env)
        assert windows.shape == linux.shape and np.abs(windows - linux).max() <= SAME, case
        if case == "rail end":
            assert linux[-1, 0] == 1.0 and abs(linux[-1, 1] - 0.5) < EVENT
            continue
        ours = _co_simulation(path, start, stop, 1e-3)
        assert len(linux) == len(ours["time"]) and np.array_equal(linux[:, 0], ours["time"])
        for column, name in enumerate(observed, start=1):
            assert np.abs(linux[:, column] - ours[name]).max() <= SAME, (case, name)


# ---- directional derivatives ----

STATE = (0.1, 0.2, 0.15, -0.3, -0.05, 0.4, 1.2, 0.1, 0.0)
INPUTS = (0.4, 0.2, 0.3, -0.1)
PARAMETERS = {"c1": 0.05, "c2": 0.02, "tau": 0.0}


class _Instance:
    """An instance of the plant in continuous-time mode at STATE and INPUTS (its mode free)."""

    def __init__(self, path, parameters, state=STATE, inputs=INPUTS):
        md = fmpy.read_model_description(str(path))
        self.fmi3 = md.fmiVersion.startswith("3")
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.derivatives = [d.variable.valueReference for d in md.derivatives]
        self.states = [d.variable.derivative.valueReference for d in md.derivatives]
        self.inputs = [self.vr[n] for n in me.INPUTS]
        self.outputs = [u.variable.valueReference for u in md.outputs]
        kind = FMU3Model if self.fmi3 else FMU2Model
        token = md.instantiationToken if self.fmi3 else md.guid
        self.fmu = kind(guid=token, unzipDirectory=extracted(path),
                        modelIdentifier=md.modelExchange.modelIdentifier, instanceName="me")
        self.fmu.instantiate()
        set_ = self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        set_([self.vr[k] for k in parameters], list(parameters.values()))
        self.fmu.exitInitializationMode()
        (self.fmu.updateDiscreteStates if self.fmi3 else self.fmu.newDiscreteStates)()
        self.fmu.enterContinuousTimeMode()
        set_(self.inputs, list(inputs))
        self.set_ = set_
        self.x = (ctypes.c_double * len(state))(*state)
        self.fmu.setContinuousStates(self.x, len(state))

    def derivatives_at(self, x, u):
        self.fmu.setContinuousStates((ctypes.c_double * len(x))(*x), len(x))
        self.set_(self.inputs, list(u))
        dx = (ctypes.c_double * len(x))()
        self.fmu.getDerivatives(dx, len(x)) if not self.fmi3 else self.fmu.getContinuousStateDerivatives(dx, len(x))
        return np.array(dx)

    def jacobian(self):
        unknowns, knowns = self.derivatives + self.outputs, self.states + self.inputs
        return np.array([self.fmu.getDirectionalDerivative(unknowns, [k], [1.0]) for k in knowns]).T


@pytest.fixture
def instance(plant_fmu):
    made = _Instance(plant_fmu, PARAMETERS)
    yield made
    made.fmu.terminate()
    made.fmu.freeInstance()


def test_directional_derivatives_are_the_models_exact_jacobians(instance):
    config = plant.COMPONENT.check(PARAMETERS)
    a, b, c, d = (np.array(m) for m in me.jacobians(config, STATE, INPUTS, me.FREE))
    want = np.block([[a, b], [c, d]])
    assert np.abs(instance.jacobian() - want).max() <= 1e-12 * max(1.0, np.abs(want).max())


def test_directional_derivatives_agree_with_central_differences(instance):
    jac, h = instance.jacobian(), 1e-6
    n = len(STATE)
    for k in range(n + len(INPUTS)):
        x, u = np.array(STATE), np.array(INPUTS)
        plus, minus = (x.copy(), u.copy()), (x.copy(), u.copy())
        (plus[0] if k < n else plus[1])[k % n if k < n else k - n] += h
        (minus[0] if k < n else minus[1])[k % n if k < n else k - n] -= h
        difference = (instance.derivatives_at(*plus) - instance.derivatives_at(*minus)) / (2 * h)
        assert np.abs(jac[:n, k] - difference).max() < 1e-6, k


@pytest.mark.parametrize("plant_fmu", [3], ids=["FMI 3.0"], indirect=True)  # adjoint derivatives are FMI 3.0's
def test_the_adjoint_is_the_transposed_directional_derivative(instance):
    assert instance.fmi3
    unknowns, knowns = instance.derivatives + instance.outputs, instance.states + instance.inputs
    seed = [math.sin(i + 1.0) for i in range(len(unknowns))]
    adjoint = instance.fmu.getAdjointDerivative(unknowns, knowns, seed, len(knowns))  # fmpy's default is len(unknowns)
    assert np.abs(np.array(adjoint) - instance.jacobian().T @ seed).max() < 1e-12 * max(1.0, np.abs(adjoint).max())


def test_linearize_uses_the_directional_derivatives_and_at_rest_is_the_linearisation(plant_fmu):
    lin = linearize(plant_fmu, {"theta1": 0.0})
    assert lin.method == "directional derivatives (Model Exchange)"
    assert lin.states == list(me.STATES)
    big_w, small_w = plant.linearisation(plant.COMPONENT.check({}).params)
    assert np.abs(lin.A[np.ix_([3, 5], [2, 4])] + np.array(big_w)).max() < 1e-9
    assert np.abs(lin.B[[3, 5], 0] + np.array(small_w)).max() < 1e-9


def test_the_documented_fmpy_recipe_stops_at_the_rail_end(native, tmp_path):
    """The interoperability page's fmpy recipe, run as written in a clone's layout: it stops where x = u t^2 / 2
    reaches x_max, at the time it prints."""
    page = (Path(__file__).parent.parent / "docs" / "guide" / "interoperability.md").read_text()
    block = re.search(r"## Model Exchange.*?```python\n(.*?)```", page, re.S).group(1)
    (tmp_path / "build").symlink_to(native[2].parent)
    (tmp_path / "recipe.py").write_text(block)
    done = subprocess.run([sys.executable, "recipe.py"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    last = done.stdout.splitlines()[-1]  # after fmpy's log of the FMU's warning (the rail end)
    printed = re.fullmatch(r"stopped at the rail end x_max = 2 m at t = (\d+\.\d{6}) s", last)
    assert printed and abs(float(printed.group(1)) - math.sqrt(2 * 2.0 / 0.5)) < 1e-6, done.stdout


# ---- directional derivatives in co-simulation ----

CS_PARAMETERS = {"c1": 0.05, "c2": 0.02, "tau": 0.05}  # the drive's lag on: its state is one of the knowns


def _stepped_co_simulation(path):
    """A co-simulation instance of the plant 0.2 s into a run at INPUTS (pushed, hoisted, forced: all nine states
    move), and its value references."""
    md = fmpy.read_model_description(str(path))
    fmi3 = md.fmiVersion.startswith("3")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    kind = FMU3Slave if fmi3 else FMU2Slave
    fmu = kind(guid=md.instantiationToken if fmi3 else md.guid, unzipDirectory=extracted(path),
               modelIdentifier=md.coSimulation.modelIdentifier, instanceName="cs")
    fmu.instantiate()
    set_ = fmu.setFloat64 if fmi3 else fmu.setReal
    if fmi3:
        fmu.enterInitializationMode(startTime=0.0)
    else:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
    set_([vr[k] for k in CS_PARAMETERS], list(CS_PARAMETERS.values()))
    set_([vr[n] for n in me.INPUTS], list(INPUTS))
    fmu.exitInitializationMode()
    for k in range(200):
        fmu.doStep(k * 1e-3, 1e-3)
    return fmu, md, vr, set_, (fmu.getFloat64 if fmi3 else fmu.getReal)


@pytest.fixture
def co_simulation(plant_fmu):
    made = _stepped_co_simulation(plant_fmu)
    yield made
    made[0].terminate()
    made[0].freeInstance()


def _co_simulation_element(path):
    return ET.fromstring(zipfile.ZipFile(path).read("modelDescription.xml")).find("CoSimulation")


def test_co_simulation_gives_the_directional_derivatives_at_its_communication_point(plant_fmu, co_simulation):
    """FMI 2.0 section 2.1.9 (Step Mode), FMI 3.0 alike: the outputs and state derivatives by the states and inputs
    at the communication point. They are the model's exact Jacobians there, except co-simulation's ddx (the
    acceleration over the last step, a value it keeps: no input or state moves it); the input columns are the
    central differences of what fmi2GetReal gives (the state derivatives by the inputs, the outputs none)."""
    fmu, md, vr, set_, get = co_simulation
    flag = "providesDirectionalDerivatives" if md.fmiVersion.startswith("3") else "providesDirectionalDerivative"
    assert _co_simulation_element(plant_fmu).get(flag) == "true"
    states = [d.variable.derivative.valueReference for d in md.derivatives]
    inputs = [vr[n] for n in me.INPUTS]
    unknowns = [d.variable.valueReference for d in md.derivatives] + [u.variable.valueReference for u in md.outputs]
    jacobian = np.array([fmu.getDirectionalDerivative(unknowns, [k], [1.0]) for k in states + inputs]).T
    state = get(states)
    a, b, c, d = (np.array(m) for m in me.jacobians(plant.COMPONENT.check(CS_PARAMETERS), tuple(state), INPUTS,
                                                      me.FREE))
    want = np.block([[a, b], [c, d]])
    kept = [i for i, unknown in enumerate(unknowns) if unknown == vr["ddx"]]
    assert len(kept) == 2 and np.count_nonzero(want[kept]) > 0  # der(dx) and the output ddx: Model Exchange's move
    want[kept] = 0.0
    assert np.abs(jacobian - want).max() <= 1e-12 * max(1.0, np.abs(want).max())
    h = 1e-6
    for j in range(len(inputs)):
        values = list(INPUTS)
        values[j] = INPUTS[j] + h
        set_(inputs, values)
        plus = np.array(get(unknowns))
        values[j] = INPUTS[j] - h
        set_(inputs, values)
        minus = np.array(get(unknowns))
        set_(inputs, list(INPUTS))
        assert np.abs(jacobian[:, len(states) + j] - (plus - minus) / (2 * h)).max() < 1e-6, me.INPUTS[j]
    assert np.count_nonzero(jacobian[:, len(states):]) > 0


@pytest.mark.parametrize("plant_fmu", [3], ids=["FMI 3.0"], indirect=True)
def test_co_simulation_gives_the_adjoint_derivatives_too(plant_fmu, co_simulation):
    fmu, md, vr, _, _ = co_simulation
    element = _co_simulation_element(plant_fmu)
    assert element.get("providesDirectionalDerivatives") == element.get("providesAdjointDerivatives") == "true"
    knowns = [d.variable.derivative.valueReference for d in md.derivatives] + [vr[n] for n in me.INPUTS]
    unknowns = [d.variable.valueReference for d in md.derivatives] + [u.variable.valueReference for u in md.outputs]
    jacobian = np.array([fmu.getDirectionalDerivative(unknowns, [k], [1.0]) for k in knowns]).T
    seed = [math.cos(i + 0.5) for i in range(len(unknowns))]
    adjoint = np.array(fmu.getAdjointDerivative(unknowns, knowns, seed, len(knowns)))
    assert np.abs(adjoint - jacobian.T @ seed).max() < 1e-12 * max(1.0, np.abs(adjoint).max())


# ---- the ModelStructure against the directional derivatives ----

OTHER_STATE = (-0.3, 0.5, -0.12, 0.7, 0.2, -0.25, 0.8, -0.2, 0.3)
OTHER_INPUTS = (-0.3, 0.1, -0.2, 0.4)


def test_the_model_structure_lists_exactly_the_dependencies_the_directional_derivatives_show(plant_fmu):
    """Each derivative and each output depends (ModelStructure: Derivatives, Outputs) on exactly the states and
    inputs whose column of the directional derivatives is not zero somewhere: at two generic states and inputs,
    with the drive's lag off (ddx is u) and on (ddx is the drive's state); an entry within rounding of zero
    (1e-12; a term that cancels leaves 1e-16) is zero. The output ddx too, which reads u in Model Exchange only
    (the acceleration now; in co-simulation the acceleration over the last step, its own test above): one
    ModelStructure serves both interfaces, so it lists u."""
    md = fmpy.read_model_description(str(plant_fmu))
    unknowns = list(md.derivatives) + list(md.outputs)
    shown = [set() for _ in unknowns]
    for parameters in (PARAMETERS, CS_PARAMETERS):
        for state, inputs in ((STATE, INPUTS), (OTHER_STATE, OTHER_INPUTS)):
            made = _Instance(plant_fmu, parameters, state, inputs)
            try:
                jacobian, knowns = made.jacobian(), made.states + made.inputs
            finally:
                made.fmu.terminate()
                made.fmu.freeInstance()
            for row, found in enumerate(shown):
                found |= {knowns[k] for k in np.flatnonzero(np.abs(jacobian[row]) > ROUNDING)}
    names = {v.valueReference: v.name for v in md.modelVariables}
    for unknown, found in zip(unknowns, shown):
        listed = {names[v.valueReference] for v in unknown.dependencies}
        found = {names[k] for k in found}
        assert listed == found, (unknown.variable.name, sorted(listed ^ found))
    ddx = md.outputs[[u.variable.name for u in md.outputs].index("ddx")]
    assert {v.name for v in ddx.dependencies} == {"drive", "u"}
