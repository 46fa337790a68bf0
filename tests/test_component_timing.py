"""What docs/reference/controller-interface.md says of a component's functions holds: ``time`` in ``update`` is the
step's start, the law runs at t = 0 on the initial state before any update, and units come from a fixed list."""

import re
from pathlib import Path

import pytest

from crane_fmu.model.component import Component
from crane_fmu.model.tables import BASE_UNITS, MEASURED_STATE, output, parameter
from fmu_src.python.runtime import Runtime

pytestmark = pytest.mark.quick  # no build: the runtime every Python FMU runs its component with

DOC = Path(__file__).resolve().parent.parent / "docs" / "reference" / "controller-interface.md"


def _recording(calls):
    """A controller with a state that records every call of its law and its update."""
    def update(config, state, inputs, time, step):
        calls.append(("update", time, step, state))
        return (state[0] + 1,)

    def law(config, state, inputs):
        calls.append(("law", state))
        return (0.0,)

    return Component("Recorder", "controller", "records its calls", (parameter("k", 1.0, "1", "a gain"),)
                     + MEASURED_STATE + (output("u", "m/s2", "demanded trolley acceleration"),),
                     lambda values: values, law, feedthrough=True, initial_state=lambda config: (0,), update=update)


def test_the_law_runs_at_t0_on_the_initial_state_and_update_gets_the_steps_start():
    calls = []
    runtime = Runtime(_recording(calls))
    runtime.initialise()
    runtime.outputs()  # the master reads u at t = 0
    for k in range(3):
        assert runtime.step(k * 0.01, 0.01) is None
        runtime.outputs()
    assert calls == [("law", (0,)), ("update", 0.0, 0.01, (0,)), ("law", (1,)), ("update", 0.01, 0.01, (1,)),
                     ("law", (2,)), ("update", 0.02, 0.01, (2,)), ("law", (3,))]


def test_the_docs_say_when_the_functions_run_and_list_the_units_the_code_accepts():
    text = " ".join(DOC.read_text().split())
    assert "`time` in `update` is the **start** of the step" in text
    assert "The law runs first at t = 0, on `initial_state(config)`, **before any update**" in text
    listed = re.search(r"Units come from a \*\*fixed list\*\* \(`crane_fmu/model/tables.py`, `BASE_UNITS`\): (.*?) "
                       r"\(no unit\)", text).group(1)
    assert re.findall(r"`([^`]+)`", listed) == list(BASE_UNITS)
    with pytest.raises(ValueError, match="unit must be one of tables.BASE_UNITS"):
        Component("Bad", "controller", "a unit off the list", (output("u", "m/s^2", "u"),), lambda v: v,
                  lambda config, state, inputs: (0.0,))
