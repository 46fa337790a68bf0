"""The scoreboard's floors kept on disk: computed once per version of the code, read back unchanged; those the package
ships used only while they are of the tasks and code of now, and equal to the floors computed now."""

import json

import pytest

from crane_fmu.analysis import floor, planar_scenarios
from crane_fmu.analysis.floor import METHOD, Floor

FLOORS = {"S1": Floor("S1", 2.31, "theta1 = 10 deg to rest", 0.01, METHOD),
          "S7": Floor("S7", None, "hoisting", 0.05, METHOD)}


@pytest.mark.quick  # no build, no linear program: the computation is counted, not run
def test_the_floors_are_computed_once_per_version_of_the_code_and_read_back_equal(tmp_path, monkeypatch):
    computed = []
    monkeypatch.setattr(floor, "scenario_floors", lambda: computed.append(1) or FLOORS)
    assert floor.stored_scenario_floors(tmp_path, shipped=None) == FLOORS and len(computed) == 1
    assert floor.stored_scenario_floors(tmp_path, shipped=None) == FLOORS and len(computed) == 1  # floats exact, None
    monkeypatch.setattr(floor, "code_key", lambda: "another-version")
    assert floor.stored_scenario_floors(tmp_path, shipped=None) == FLOORS and len(computed) == 2  # other code: again
    (tmp_path / "another-version.json").write_text('{"S1": [')  # torn: computed again, not an error
    assert floor.stored_scenario_floors(tmp_path, shipped=None) == FLOORS and len(computed) == 3


@pytest.mark.quick
def test_shipped_floors_are_used_only_while_they_are_of_the_tasks_and_code_of_now(tmp_path, monkeypatch):
    computed = []
    monkeypatch.setattr(floor, "scenario_floors", lambda: computed.append(1) or FLOORS)
    shipped = tmp_path / "floors.json"
    floor.write_shipped(shipped)
    assert json.loads(shipped.read_text())["key"] == floor.inputs_key() and len(computed) == 1
    assert floor.stored_scenario_floors(tmp_path / "store", shipped) == FLOORS and len(computed) == 1  # not computed
    tasks = floor.planar_tasks()
    tasks["S2"][1]["target"] = (3.0, *tasks["S2"][1]["target"][1:])  # another task (S2 3 m): not those floors
    monkeypatch.setattr(floor, "planar_tasks", lambda: tasks)
    assert floor.shipped_floors(shipped) is None
    assert floor.stored_scenario_floors(tmp_path / "store", shipped) == FLOORS and len(computed) == 2
    monkeypatch.undo()
    monkeypatch.setattr(floor, "scenario_floors", lambda: computed.append(1) or FLOORS)
    shipped.write_text('{"key": ')  # torn: computed, not an error
    assert floor.shipped_floors(shipped) is None
    assert floor.stored_scenario_floors(tmp_path / "store2", shipped) == FLOORS and len(computed) == 3


def test_the_floors_the_package_ships_are_of_the_code_of_now_and_equal_those_computed_now():
    """The linear programs run (about 7 CPU-s). When this fails after an edit of the floors' tasks, of floor.py or
    of crane_fmu/model: `python -m crane_fmu.analysis.floor` writes them again (a board computes them meanwhile).
    With other numpy or scipy versions than they were computed with, they are not used: the board computes them."""
    stored = json.loads(floor.SHIPPED.read_text())
    assert stored["key"] == floor.inputs_key(), ("crane_fmu/analysis/floors.json is not of the floors' tasks and code "
                                                 "of now: run `python -m crane_fmu.analysis.floor`")
    computed = floor.scenario_floors()
    if stored["versions"] == planar_scenarios.library_versions():
        assert floor.shipped_floors() == computed
    else:
        assert floor.shipped_floors() is None and floor.stored_scenario_floors() == computed


@pytest.mark.quick
def test_shipped_floors_of_other_libraries_are_not_used(tmp_path, monkeypatch):
    monkeypatch.setattr(floor, "scenario_floors", lambda: FLOORS)
    shipped = floor.write_shipped(tmp_path / "floors.json")
    assert floor.shipped_floors(shipped) == FLOORS
    monkeypatch.setattr(planar_scenarios, "library_versions", lambda: "numpy 0.0 scipy 0.0")
    assert floor.shipped_floors(shipped) is None
