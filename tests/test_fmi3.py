"""The FMI 3.0 pair (pythonfmu3): validated, units declared natively, co-simulated like the FMI 2.0 pair."""

import math

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from crane_fmu.build_scripts.build_fmus import fmi3_dir
from crane_fmu.cosim import simulate
from crane_fmu.cosim.fmi3 import Fmi3Instance
from crane_fmu.model import backstepping, plant, tables


@pytest.fixture(scope="session")
def fmi3_fmus(fmu_dir):
    folder = fmi3_dir(fmu_dir)
    return {"plant": folder / "CranePlant.fmu", "controller": folder / "BacksteppingController.fmu"}


@pytest.mark.parametrize("instance, table", [("plant", plant.VARIABLES), ("controller", backstepping.VARIABLES)])
def test_fmi3_fmus_validate_and_declare_units(fmi3_fmus, instance, table):
    path = fmi3_fmus[instance]
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.fmiVersion == "3.0" and not md.coSimulation.needsExecutionTool
    units = {u.name: u for u in md.unitDefinitions}
    variables = {v.name: v for v in md.modelVariables}
    for row in table:
        v = variables[row.name]
        assert v.description == row.description
        if row.type == "Real":
            assert v.type == "Float64" and v.unit == row.unit and row.unit in units
            assert v.displayUnit == tables.DISPLAY_UNITS.get(row.unit)
    assert units["rad"].displayUnits[0].name == "deg"
    assert units["rad"].displayUnits[0].factor == pytest.approx(180 / math.pi, rel=1e-15)


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
def test_fmi3_pair_gives_the_fmi2_results(crane_fmus, fmi3_fmus, connections, algorithm):
    fmi2 = simulate(crane_fmus, connections, 2.0, 1e-3, algorithm).columns()
    fmi3 = simulate(fmi3_fmus, connections, 2.0, 1e-3, algorithm).columns()
    assert list(fmi2) == list(fmi3)
    for name in fmi2:
        assert np.array_equal(fmi2[name], fmi3[name]), name  # same Python code: bit for bit


def test_fmi3_state_round_trip(fmi3_fmus):
    inst = Fmi3Instance(fmi3_fmus["plant"], "plant3")
    try:
        inst.setup(0.0)
        inst.enter_initialization()
        inst.exit_initialization()
        state = inst.get_state()
        inst.do_step(0.0, 0.5)
        after = inst.get("theta1")
        inst.set_state(inst.deserialize_state(inst.serialize_state(state)))
        inst.do_step(0.0, 0.5)
        assert inst.get("theta1") == after
        inst.free_state(state)
    finally:
        inst.free()


@pytest.mark.parametrize("kind", ["python", "native", "one-fmu"])
def test_time_is_read_with_any_other_variables_and_never_set(fmu_dir, kind, request):
    """FMI 3.0's independent variable in one fmi3GetFloat64 call with others, anywhere in it (as fmusim reads it
    with the outputs); setting it is refused with a message."""
    from fmpy.fmi1 import FMICallException
    from helpers import kind_folder
    from native_fmus import open_native

    path = kind_folder(request, fmu_dir, kind, 3) / ("CraneLqr.fmu" if kind == "one-fmu" else "CranePlant.fmu")
    fmu, vr, set_, get = open_native(path, 3)
    try:
        time, x, theta1 = 0, vr["x"], vr["theta1"]
        assert get([time, theta1, time]) == [0.0, math.radians(10), 0.0]
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.25)
        alone = get([x]) + get([theta1])
        assert get([x, time, theta1]) == [alone[0], 0.25, alone[1]]
        assert get([time]) == [0.25] and get([theta1, x]) == alone[::-1]
        with pytest.raises(FMICallException):
            set_([time], [1.0])
    finally:
        fmu.freeInstance()
