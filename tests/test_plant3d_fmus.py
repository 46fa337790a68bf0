"""The CranePlant3D's FMUs: the Python FMU and the native ones (FMI 2.0 and 3.0, Co-Simulation and Model Exchange)
against the Python model, the planar CranePlant in every built-in planar run, its linearisation through
``crane-fmu linearize``, and hosts nobody here wrote (fmusim with CVODE). The model's own known answers:
test_plant3d.py; its C against it through ctypes: test_native_plant3d.py."""

import math
import random
from dataclasses import replace

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu
from native_fmus import close, messages, open_native, python_folder
from third_party_hosts import fmusim_me

from crane_fmu import compare, components, systems
from crane_fmu.analysis import scenarios
from crane_fmu.cli import main
from crane_fmu.cosim import Connection, run
from crane_fmu.model import plant3d
from crane_fmu.model import plant3d_continuous as me
from crane_fmu.model.component import Step

NAME = "CranePlant3D"
COMPONENT = plant3d.COMPONENT


# ---- one table, both interfaces ------------------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
def test_the_native_fmu_has_the_python_fmus_variables_and_declares_model_exchange(fmu_dir, native, version):
    path = native[version] / f"{NAME}.fmu"
    ours, theirs = read_model_description(str(path)), read_model_description(str(python_folder(fmu_dir, version)
                                                                                   / f"{NAME}.fmu"))

    def table(md):
        return [(v.name, v.causality, v.variability, v.start, v.unit, v.description) for v in md.modelVariables
                if v.causality in ("parameter", "input", "output")]

    assert table(ours) == table(theirs)
    assert validate_fmu(str(path)) == []
    assert ours.modelExchange is not None and ours.coSimulation is not None
    assert [d.variable.derivative.name for d in ours.derivatives] == list(me.STATES)
    assert len(ours.eventIndicators if version == 3 else range(ours.numberOfEventIndicators)) == len(me.INDICATORS)


# ---- the FMUs give the Python model's numbers ----------------------------------------------------------------------

SETTINGS = [  # every effect: drive lags and limits per axis, damping, forces, hoisting into its limits
    {"theta1y_0": 0.2, "dtheta2x_0": -0.5, "c1": 0.3, "c2": 0.1, "tau_x": 0.2, "vx_max": 0.5, "uy_max": 1.5,
     "vy_max": 0.8, "tau_y": 0.05},
    {"l1": 1.5, "l1_min": 1.2, "l1_max": 1.6, "dl1_max": 0.4, "theta2y_0": -0.3, "m2": 2.0, "x_min": -5.0,
     "y_max": 5.0},
    {"m2": 0.0, "theta1x_0": 0.0, "dtheta1y_0": 0.4, "ux_max": 2.0, "max_substep": 4e-4},
]


def _inputs(rng, settings):
    loaded = settings.get("m2", 1.0) != 0.0
    return (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-0.5, 0.5) if "l1_min" in settings else 0.0,
            rng.uniform(-10, 10), rng.uniform(-10, 10), *((rng.uniform(-10, 10), rng.uniform(-10, 10)) if loaded
                                                          else (0.0, 0.0)))


@pytest.mark.parametrize("kind, version", [("python", 2), ("native", 2), ("native", 3)])
def test_the_fmus_give_the_python_models_outputs_bit_for_bit(fmu_dir, native, kind, version):
    """300 steps (1 ms, and some longer ones of several sub-steps) of random inputs per setting: every output."""
    folder = python_folder(fmu_dir, version) if kind == "python" else native[version]
    inputs, outputs = COMPONENT.names("input"), COMPONENT.names("output")
    rng = random.Random(version)
    ours, theirs = [], []
    for settings in SETTINGS:
        fmu, vr, set_, get = open_native(folder / f"{NAME}.fmu", version, settings)
        config = COMPONENT.check(settings)
        state, t = COMPONENT.initial_state(config), 0.0
        values = _inputs(rng, settings)
        for j in range(300):
            if j % 20 == 0:  # each held 20 steps
                values = _inputs(rng, settings)
            set_([vr[n] for n in inputs], list(values))
            ours.append(get([vr[n] for n in outputs]))
            theirs.append(COMPONENT.output(config, state, values))
            if j == 0:
                fmu.exitInitializationMode()
            h = 1e-3 if j % 7 else 2.7e-3
            fmu.doStep(t, h)
            state, t = COMPONENT.update(config, state, values, t, h), t + h
            state = state.state if isinstance(state, Step) else state
        close(fmu)
    ours, theirs = np.array(ours), np.array(theirs)
    assert np.array_equal(ours, theirs) and np.ptp(theirs[:, outputs.index("y2")]) > 0.05


NAN, INF = float("nan"), float("inf")
REFUSED = [{"m1": 0.0}, {"l2": NAN}, {"max_substep": 0.0}, {"c2": -1.0}, {"tau_y": INF}, {"uy_max": 0.0},
           {"vx_max": NAN}, {"dl1_max": -1.0}, {"m2": 0.0, "c2": 0.5}, {"x_min": 1.0, "x_max": 1.0},
           {"y_min": 2.0, "y_max": 1.0}, {"theta2y_0": INF}, {"dy0": NAN}, {"y0": 3.0, "y_max": 2.0},
           {"x0": -3.0, "x_min": -2.0}, {"l1": 2.0, "l1_max": 1.5}]


@pytest.mark.parametrize("settings", REFUSED, ids=lambda c: ",".join(f"{k}={v!r}" for k, v in c.items()))
def test_every_parameter_refusal_has_the_python_fmus_rule_and_message(fmu_dir, native, settings):
    ours, theirs = messages(native[2] / f"{NAME}.fmu", settings), messages(fmu_dir / f"{NAME}.fmu", settings)
    assert ours == theirs and ours[0][-2] == "exit: 3"


@pytest.mark.parametrize("settings, steps", [
    ({"y_max": 0.01}, [(k * 1e-3, 1e-3, {"uy": 2.0}) for k in range(200)]),  # the rail end along y
    ({"m2": 0.0}, [(0.0, 1e-3, {"F2y": 1.0})]),  # a force on no mass
    ({}, [(0.0, 1e-3), (1e-3, -1e-3)]),  # an unusable step
    ({"max_substep": 1e-9}, [(0.0, 1.0)]),  # too many sub-steps
    ({"l1_max": 1.05}, [(k * 1e-3, 1e-3, {"hoist": 1.0}) for k in range(400)]),  # the cable held at its limit
])
def test_discards_errors_and_notes_have_the_python_fmus_status_and_message(fmu_dir, native, settings, steps):
    """Every call's status and every message of the model (the Python FMU also says which CPython it runs)."""
    ours = messages(native[2] / f"{NAME}.fmu", settings, steps, logging_on=True)
    theirs = messages(fmu_dir / f"{NAME}.fmu", settings, steps, logging_on=True)
    assert ours[0] == theirs[0] and ours[1] == [m for m in theirs[1] if not m.startswith("using the host process")]
    assert ours[1], "a message is logged"


# ---- without y it is the planar crane, in every built-in planar run ------------------------------------------------

PLANAR_TO_SPATIAL = {"u_max": "ux_max", "v_max": "vx_max", "tau": "tau_x", "theta1_0": "theta1x_0",
                     "dtheta1_0": "dtheta1x_0", "theta2_0": "theta2x_0", "dtheta2_0": "dtheta2x_0"}
INPUTS = {"u": "ux", "hoist": "hoist", "F1": "F1x", "F2": "F2x"}
SAME = {"x": "x", "dx": "dx", "theta1": "theta1x", "dtheta1": "dtheta1x", "theta2": "theta2x", "dtheta2": "dtheta2x",
        "l1_now": "l1_now", "dl1_now": "dl1_now", "ddx": "ddx"}
OUT_OF_PLANE = ("y", "dy", "theta1y", "dtheta1y", "theta2y", "dtheta2y", "ddy")


def _planar_runs():
    """Every built-in system with a CranePlant, and every scenario of the board with the LQR (one case each)."""
    runs = [(system.name, system) for system in systems.registered()
            if "CranePlant" in systems.kinds(system).values()]
    lqr, = compare.contenders(("LqrController",), only=True)
    for scenario in (s.id for s in scenarios.scenarios().values() if s.plant == "CranePlant"):
        for case in scenarios.systems_for(lqr, scenario, cases=1):
            runs.append((f"{scenario} {case.label}", systems.prepare(case.system, case.step, case.stop_time)))
    return runs


def test_without_y_it_is_the_planar_crane_in_every_built_in_planar_run(native):
    """A CranePlant3D beside the CranePlant of each run, fed whatever feeds the planar plant (its u as ux, F1 and F2
    as F1x and F2x, the hoist) with the planar plant's parameters: its planar state is the CranePlant's to 1e-12 at
    every step, and nothing leaves the plane.

    Where the run itself is reproducible: a second CranePlant, fed the same and started one ulp away (theta1_0),
    stays within 1e-6 of the first. In every run but one: the paper's law (its u up to 810 m/s2) drives the planar
    plant itself so hard that its one-ulp twin departs by 84 rad by the end; that run is compared over the time its
    one-ulp twin stays within 1e-14 (0.8 s).
    """
    worst, shortened = {}, {}
    for label, system in _planar_runs():
        fmus, connections = system.resolve(native[2])
        plant = next(name for name, kind in systems.kinds(system).items() if kind == "CranePlant")
        into = [c for c in connections if c.target == plant]
        planar = system.parameters.get(plant, {})
        start = planar.get("theta1_0", components.get("CranePlant").defaults()["theta1_0"])
        twins = tuple(Connection(c.source, c.output, "twin", INPUTS[c.input]) for c in into) + tuple(
            Connection(c.source, c.output, "ulp", c.input) for c in into)
        # the planar values on the twin: parameters, and an input's start (free sets u)
        values = {PLANAR_TO_SPATIAL.get(k, INPUTS.get(k, k)): v for k, v in planar.items()}
        with_twins = systems.prepare(replace(
            system, instances={**system.instances, "twin": NAME, "ulp": "CranePlant"},
            connections=tuple(connections) + twins, match_names=False,
            parameters={**system.parameters, "twin": values,
                        "ulp": {**planar, "theta1_0": math.nextafter(start, math.inf)}}))  # crane.*: on both twins
        result = run(with_twins, native[2]).columns()
        apart = np.max([np.abs(result[f"ulp.{a}"] - result[f"{plant}.{a}"]) for a in SAME], axis=0)
        end = len(apart) if apart.max() <= 1e-6 else int(np.argmax(apart > 1e-14))
        if end < len(apart):
            shortened[label] = result["time"][end - 1]
        worst[label] = max(np.abs(result[f"twin.{b}"][:end] - result[f"{plant}.{a}"][:end]).max()
                           for a, b in SAME.items())
        assert not any(result[f"twin.{name}"].any() for name in OUT_OF_PLANE), label
    assert max(worst.values()) <= 1e-12, worst
    assert set(shortened) == {"paper"} and shortened["paper"] > 0.5, shortened
    assert len(worst) >= 20


# ---- the linearisation at rest: two planar cranes ------------------------------------------------------------------

def test_crane_fmu_linearize_gives_two_planar_cranes_at_rest(native, tmp_path, capsys):
    """``crane-fmu linearize`` of both native plants at the hanging rest (Model Exchange's directional derivatives):
    per axis the CranePlant3D's A and B are the CranePlant's, and the axes are not coupled."""
    for name, at in (("CranePlant", "theta1=0"), (NAME, "theta1x=0")):
        assert main(["linearize", str(native[2] / f"{name}.fmu"), "--at", at, "--set", "l1=1.5",
                     "--out", str(tmp_path / f"{name}.npz")]) == 0
    assert "directional derivatives" in capsys.readouterr().out
    planar, spatial = np.load(tmp_path / "CranePlant.npz"), np.load(tmp_path / f"{NAME}.npz")
    p_states, s_states = list(planar["states"]), list(spatial["states"])
    p_inputs, s_inputs = list(planar["inputs"]), list(spatial["inputs"])
    names = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
    for axis in ("x", "y"):
        rows = [s_states.index(n.replace("x", axis) if n in ("x", "dx") else n + axis) for n in names]
        same = [p_states.index(n) for n in names]
        assert spatial["A"][np.ix_(rows, rows)] == pytest.approx(planar["A"][np.ix_(same, same)], rel=1e-12, abs=1e-12)
        assert spatial["B"][rows, s_inputs.index("u" + axis)] == pytest.approx(planar["B"][same, p_inputs.index("u")],
                                                                                rel=1e-12, abs=1e-12)
        others = [i for i in range(len(s_states)) if i not in rows and s_states[i] not in ("l1_now", "dl1_now")]
        assert not spatial["A"][np.ix_(rows, others)].any()


# ---- Model Exchange in hosts ---------------------------------------------------------------------------------------

RTOL, ANGLES, EVENT = 1e-10, 1e-6, 1e-6  # the hosts' tolerance; rad: ME against CS; s: a state event
ELLIPTIC = {"theta1x_0": 0.3, "dtheta1y_0": 0.8, "theta2y_0": -0.2, "ux": 0.3, "uy": -0.2, "hoist": 0.2}
WATCHED = ["x", "y", "theta1x", "theta1y", "theta2x", "theta2y"]


def _fmpy(path, interface, start, stop, step=0.05):
    kwargs = {"solver": "CVode", "relative_tolerance": RTOL} if interface == "ModelExchange" else {}
    return fmpy.simulate_fmu(str(path), fmi_type=interface, start_values=start, stop_time=stop,
                             output_interval=step, output=WATCHED, **kwargs)


def _fmusim(path, start, stop, tmp_path, step=0.05):
    return fmusim_me(path, start, stop, step, tmp_path / "me.csv", RTOL)


@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_and_fmusim_integrate_it_as_the_co_simulation_steps_it(native, version, tmp_path):
    """A spatial swing while the trolley moves in x and y and the hoist lowers: CVODE at 1e-10 (fmpy's and
    fmusim's) against the co-simulation's RK4 at 1 ms (within about 1e-12 of the ODE): within 1e-6 rad."""
    path = native[version] / f"{NAME}.fmu"
    ours = _fmpy(path, "CoSimulation", ELLIPTIC, 2.0)
    for theirs in (_fmpy(path, "ModelExchange", ELLIPTIC, 2.0), _fmusim(path, ELLIPTIC, 2.0, tmp_path)):
        assert np.allclose(theirs["time"], ours["time"])
        for name in WATCHED:
            assert np.abs(theirs[name] - ours[name]).max() < ANGLES, name
    assert np.abs(ours["theta1y"]).max() > 0.05 and abs(ours["y"][-1]) > 0.3  # out of the plane, both axes


def test_a_rail_end_along_y_ends_the_run_at_its_state_event(native, tmp_path):
    """uy = 1 m/s2 from rest reaches y_max = 0.5 m at t = 1 s exactly."""
    start = {"uy": 1.0, "y_max": 0.5}
    for result in (_fmpy(native[2] / f"{NAME}.fmu", "ModelExchange", start, 2.0, step=0.01),
                   _fmusim(native[2] / f"{NAME}.fmu", start, 2.0, tmp_path, step=0.01)):
        assert abs(result["time"][-1] - 1.0) < EVENT and abs(result["y"][-1] - 0.5) < EVENT


def test_the_component_is_registered_with_one_order_of_inputs():
    """Registered as a plant; its table's inputs are those its Model Exchange reads by name (IN), in one order."""
    assert components.get(NAME) is COMPONENT and COMPONENT.role == "plant"
    assert COMPONENT.names("input") == me.INPUTS and tuple(plant3d.IN._fields) == me.INPUTS
    assert tuple(me.IN._fields) == me.INPUTS and COMPONENT.continuous.states == me.STATES
