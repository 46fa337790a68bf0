"""Every FMU's model structure lists its real dependencies, tested by behaviour.

An output's dependencies (FMI 2.0 ``Outputs``, FMI 3.0 ``Output``) name the inputs it reads at the same
instant: perturbing one input of an instance in step mode (no step taken) must move exactly the outputs that
list it, no fewer (a hidden feedthrough breaks a master's ordering) and no more (a claimed one makes a false
algebraic loop, as OMSimulator showed with outputs that listed nothing, read as "every input"). At
initialisation (``InitialUnknowns``, ``InitialUnknown``) the same holds for the inputs, and every output also
lists every parameter (until initialisation ends the outputs follow them). Every FMU kind we build: the
pythonfmu FMUs, the native components, the one-FMU systems (FMI 2.0 and 3.0), and the container FMUs.
"""

import random

import pytest
from fmpy import read_model_description
from native_fmus import open_native

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import container_name, containers_dir, fmi3_dir
from crane_fmu.build_scripts.native import native_dir, ported
from crane_fmu.build_scripts.one_fmu import not_native, one_fmu_name

# Parameters under which every declared dependency acts: the LQR and the MPC read l1_now only with a schedule
# (the MPC takes its nearest design: designs 1 mm apart, so that the test's change of l1_now picks another).
ACTING = {"LqrController": {"l1_low": 0.5, "l1_high": 2.0}, "MpcController": {"l1_low": 0.995, "l1_high": 1.005}}
# Outputs that are whole counts or grid times of a solve at the inputs: they read the inputs, but a small change
# need not move them, so for these the test asks only that what moved is listed.
STEPWISE = {"MpcController": {"iterations", "plan_end"}}


def _paths(fmu_dir, kind, version):
    if kind == "python":
        folder = fmu_dir if version == 2 else fmi3_dir(fmu_dir)
        return [folder / f"{c.model_identifier}.fmu" for c in components.registered() if c.role != "benchmark"]
    if kind == "container":
        return [containers_dir(fmu_dir) / f"{container_name(name)}.fmu" for name in systems.tagged("container")]
    folder = native_dir(fmu_dir, version)
    if not (folder / "CranePlant.fmu").exists():
        pytest.skip("no native FMUs were built (no C compiler)")
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


@pytest.mark.parametrize("kind, version", [("python", 2), ("python", 3), ("native", 2), ("native", 3),
                                           ("one-fmu", 2), ("one-fmu", 3), ("container", 3)])
def test_perturbing_an_input_moves_exactly_the_outputs_that_list_it(fmu_dir, kind, version):
    for path in _paths(fmu_dir, kind, version):
        md = read_model_description(str(path))
        inputs = [v.name for v in md.modelVariables if v.causality == "input"]
        outputs = [u.variable.name for u in md.outputs]
        parameters = {v.name for v in md.modelVariables if v.causality == "parameter"}
        fmu, vr, set_, get = open_native(path, version, ACTING.get(md.coSimulation.modelIdentifier))
        try:
            for initial in (True, False):  # initialisation mode, then step mode before any step
                if not initial:
                    fmu.exitInitializationMode()
                declared, listed_parameters = _declared(md, initial)
                moved = _moved(fmu, vr, set_, get, inputs, outputs) if inputs else {}
                stepwise = STEPWISE.get(md.coSimulation.modelIdentifier, set())
                for name in inputs:
                    listing = {o for o in outputs if name in declared[o]}
                    assert moved[name] - stepwise == listing - stepwise, (path.name, initial, name)
                    assert moved[name] <= listing, (path.name, initial, name)
                if initial:
                    assert all(listed == parameters for listed in listed_parameters.values()), path.name
                else:
                    assert not any(listed_parameters.values()), path.name
        finally:
            fmu.freeInstance()


def test_a_feedthrough_component_declares_its_inputs_per_output():
    """Where outputs read different inputs (each sensor channel its own), the table says so, not "all"."""
    sensor = components.get("Sensor").dependencies()
    assert sensor["x_m"] == ("x",) and sensor["dtheta2_m"] == ("dtheta2",)
    assert components.get("CranePlant").dependencies()["x"] == ()
    assert components.get("BacksteppingController").dependencies()["u"] == components.get(
        "BacksteppingController").names("input")
