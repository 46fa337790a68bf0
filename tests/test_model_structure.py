"""Every FMU's model structure lists its real dependencies, tested by behaviour.

An output's dependencies (FMI 2.0 ``Outputs``, FMI 3.0 ``Output``) name the inputs it reads at the same
instant: perturbing one input of an instance in step mode (no step taken) must move exactly the outputs that
list it, no fewer (a hidden feedthrough breaks a master's ordering) and no more (a claimed one makes a false
algebraic loop, as OMSimulator showed with outputs that listed nothing, read as "every input"). At
initialisation (``InitialUnknowns``, ``InitialUnknown``) the same holds for the inputs, and every output also
lists every parameter (until initialisation ends the outputs follow them). Every FMU kind we build: the
pythonfmu FMUs, the native components, the one-FMU systems (FMI 2.0 and 3.0), and the container FMUs.

An FMU with Model Exchange beside co-simulation has one ModelStructure for both: an input is listed exactly where
it moves the output in one of them (the plant's ``ddx`` reads ``u`` in Model Exchange only), so there the inputs are
perturbed in both, co-simulation's step mode and Model Exchange's continuous-time mode.
"""

import random

import pytest
from fmpy import read_model_description
from helpers import kind_folder
from native_fmus import open_native

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import container_name, containers_dir
from crane_fmu.build_scripts.native import ported
from crane_fmu.build_scripts.one_fmu import not_native, one_fmu_name

# Parameters under which every declared dependency acts: the LQR and the MPC read l1_now only with a schedule
# (the MPC takes its nearest design: designs 1 mm apart, so that the test's change of l1_now picks another); the
# LQR and the MPC (planar and of two axes) read the estimated forces only offset-free; the planner reads the measured
# swing only with plan_from measured.
ACTING = {"LqrController": {"l1_low": 0.5, "l1_high": 2.0, "offset_free": 1.0},
          "MpcController": {"l1_low": 0.995, "l1_high": 1.005, "offset_free": 1.0},
          "LqrController3D": {"offset_free": 1.0}, "MpcController3D": {"offset_free": 1.0},
          "TrajectoryPlanner": {"shaper": "shortest", "plan_from": "measured"}}
# Outputs that are whole counts or grid times of a solve at the inputs: they read the inputs, but a small change
# need not move them, so for these the test asks only that what moved is listed. The planner's swing references
# start at the measured swing only when it is more than a swing at rest (the plan of no interval: none).
STEPWISE = {"MpcController": {"iterations", "plan_end"},
            "TrajectoryPlanner": {"theta1_ref", "dtheta1_ref", "theta2_ref", "dtheta2_ref"}}


def _paths(request, fmu_dir, kind, version):
    if kind == "container":
        return [containers_dir(fmu_dir) / f"{container_name(name)}.fmu" for name in systems.tagged("container")]
    folder = kind_folder(request, fmu_dir, kind, version)
    if kind == "python":
        return [folder / f"{c.model_identifier}.fmu" for c in components.registered() if c.role != "benchmark"]
    if kind == "native":
        return [folder / f"{name}.fmu" for name in ported()]
    return [folder / f"{one_fmu_name(name)}.fmu" for name in systems.tagged("one-fmu")
            if not not_native(systems.get(name))]


def _declared(md, initial):
    """``{output: set of the inputs its (initial) unknown lists}``, and the parameters each lists (an FMU with
    Model Exchange also lists the continuous states an output depends on: neither)."""
    unknowns = md.initialUnknowns if initial else md.outputs
    names = {v.name for v in md.modelVariables if v.causality == "input"}
    states = {d.variable.derivative.name for d in md.derivatives}
    found = {u.variable.name: {v.name for v in u.dependencies} for u in unknowns if u.variable.causality == "output"}
    assert all(u.dependencies is not None for u in unknowns), "an unknown without a list claims every input"
    return {o: deps & names for o, deps in found.items()}, {o: deps - names - states for o, deps in found.items()}


def _moved(fmu, vr, set_, get, inputs, outputs):
    """``{input: set of the outputs a small change of it moves}``, at small random input values."""
    rng = random.Random(7)
    base = {name: 1.0 if name == "l1_now" else rng.uniform(-1e-3, 1e-3) for name in inputs}
    set_([vr[n] for n in inputs], list(base.values()))
    before = get([vr[o] for o in outputs])
    moved = {}
    for name in inputs:
        set_([vr[name]], [base[name] + 1e-3 * (1.0 + abs(base[name]))])
        after = get([vr[o] for o in outputs])
        set_([vr[name]], [base[name]])
        moved[name] = {o for o, a, b in zip(outputs, after, before) if a != b}
    assert get([vr[o] for o in outputs]) == before  # set back: nothing else changed
    return moved


def _moved_in_each_mode(path, version, md, inputs, outputs, model_exchange):
    """``[{input: moved outputs} in initialisation mode, the same after it]``: co-simulation's step mode before any
    step, or Model Exchange's continuous-time mode."""
    fmu, vr, set_, get = open_native(path, version, ACTING.get(md.coSimulation.modelIdentifier),
                                     model_exchange=model_exchange)
    try:
        found = [_moved(fmu, vr, set_, get, inputs, outputs)]
        fmu.exitInitializationMode()
        if model_exchange:
            (fmu.updateDiscreteStates if version == 3 else fmu.newDiscreteStates)()
            fmu.enterContinuousTimeMode()
        return found + [_moved(fmu, vr, set_, get, inputs, outputs)]
    finally:
        fmu.freeInstance()


@pytest.mark.parametrize("kind, version", [("python", 2), ("python", 3), ("native", 2), ("native", 3),
                                           ("one-fmu", 2), ("one-fmu", 3), ("container", 3)])
def test_perturbing_an_input_moves_exactly_the_outputs_that_list_it(fmu_dir, kind, version, request):
    for path in _paths(request, fmu_dir, kind, version):
        md = read_model_description(str(path))
        inputs = [v.name for v in md.modelVariables if v.causality == "input"]
        outputs = [u.variable.name for u in md.outputs]
        parameters = {v.name for v in md.modelVariables if v.causality == "parameter"}
        stepwise = STEPWISE.get(md.coSimulation.modelIdentifier, set())
        interfaces = (False, True) if md.modelExchange else (False,)
        by_interface = [_moved_in_each_mode(path, version, md, inputs, outputs, me) for me in interfaces] if inputs \
            else [[{}, {}]]
        for initial in (True, False):  # initialisation mode, then step mode (continuous-time mode) after it
            declared, listed_parameters = _declared(md, initial)
            for name in inputs:
                listing = {o for o in outputs if name in declared[o]}
                moved = set().union(*(modes[not initial][name] for modes in by_interface))
                assert moved - stepwise == listing - stepwise, (path.name, initial, name)
                assert moved <= listing, (path.name, initial, name)
            if initial:
                assert all(listed == parameters for listed in listed_parameters.values()), path.name
            else:
                assert not any(listed_parameters.values()), path.name


def test_a_feedthrough_component_declares_its_inputs_per_output():
    """Where outputs read different inputs (each sensor channel its own), the table says so, not "all"."""
    sensor = components.get("Sensor").dependencies()
    assert sensor["x_m"] == ("x",) and sensor["dtheta2_m"] == ("dtheta2",)
    assert components.get("CranePlant").dependencies()["x"] == ()
    assert components.get("BacksteppingController").dependencies()["u"] == components.get(
        "BacksteppingController").names("input")


def test_the_model_exchange_plant_lists_what_its_acceleration_reads_and_co_simulation_does_not_move_it(native):
    """ddx is the acceleration now in Model Exchange (u through the drive), over the last step in co-simulation:
    listed, u moves it in Model Exchange only, and the union rule above is what holds the listing."""
    path = native[2] / "CranePlant.fmu"
    md = read_model_description(str(path))
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    outputs = [u.variable.name for u in md.outputs]
    assert "u" in _declared(md, False)[0]["ddx"]
    co_simulation, model_exchange = (_moved_in_each_mode(path, 2, md, inputs, outputs, me)[1] for me in (False, True))
    assert "ddx" in model_exchange["u"] and "ddx" not in co_simulation["u"]
