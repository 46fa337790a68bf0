"""fmi2GetFMUstate / fmi2SetFMUstate / serialisation on the built FMUs, and the master's rollback."""

import numpy as np
import pytest
from fmpy import read_model_description

from crane_fmu.cosim import ArrayRecorder, Master, open_instance

H = 0.01


@pytest.mark.parametrize("name", ["CranePlant", "BacksteppingController"])
def test_state_capabilities_are_declared(fmu_dir, name):
    cs = read_model_description(str(fmu_dir / f"{name}.fmu")).coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate and not cs.needsExecutionTool


def _master(crane_fmus, connections, tag=""):
    instances = {name: open_instance(path, name + tag) for name, path in crane_fmus.items()}
    master = Master(instances, connections)
    master.initialize(0.0, 10.0, {"controller": {"w_theta2": 0.0}})
    return master


def _run(master, first, last):
    recorder = ArrayRecorder()
    recorder.start(master.output_names)
    master.advance(0.0, H, first, last, [recorder])
    master.finish(last * H, [recorder])
    return np.frombuffer(recorder._rows, dtype=float).copy()


def _free(master):
    for inst in master.instances.values():
        inst.free()


def test_restoring_a_saved_state_repeats_the_run_bit_for_bit(crane_fmus, connections):
    master = _master(crane_fmus, connections)
    try:
        master.advance(0.0, H, 0, 500)  # to t = 5 s
        saved = master.save_state()
        first = _run(master, 500, 1000)  # to t = 10 s
        master.restore_state(saved)
        again = _run(master, 500, 1000)
        assert first.size == again.size > 0 and np.array_equal(first, again)
        for name, state in saved.items():
            master.instances[name].free_state(state)
    finally:
        _free(master)


def test_serialised_state_continues_identically_in_another_instance(crane_fmus, connections):
    source, target = _master(crane_fmus, connections, "_a"), _master(crane_fmus, connections, "_b")
    try:
        source.advance(0.0, H, 0, 500)
        blobs = {}
        for name, inst in source.instances.items():
            state = inst.get_state()
            blobs[name] = inst.serialize_state(state)
            inst.free_state(state)
        assert all(len(b) > 100 for b in blobs.values())
        for name, inst in target.instances.items():
            state = inst.deserialize_state(blobs[name])
            inst.set_state(state)
            inst.free_state(state)
        assert np.array_equal(_run(source, 500, 1000), _run(target, 500, 1000))
    finally:
        _free(source)
        _free(target)


def test_state_covers_the_integrator_not_only_the_variables(crane_fmus, connections):
    """Restoring must bring back the plant's motion, which no FMU variable holds but the outputs."""
    master = _master(crane_fmus, connections)
    try:
        plant = master.instances["plant"]
        saved = plant.get_state()
        theta1 = plant.get("theta1")
        master.advance(0.0, H, 0, 100)
        assert plant.get("theta1") != theta1
        plant.set_state(saved)
        assert plant.get("theta1") == theta1
        plant.free_state(saved)
    finally:
        _free(master)
