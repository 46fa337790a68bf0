"""The scoreboard's floors kept on disk: computed once per version of the code, read back unchanged."""

import pytest

from crane_fmu.analysis import floor
from crane_fmu.analysis.floor import METHOD, Floor

pytestmark = pytest.mark.quick  # no build, no linear program: the computation is counted, not run

FLOORS = {"S1": Floor("S1", 2.31, "theta1 = 10 deg to rest", 0.01, METHOD),
          "S7": Floor("S7", None, "hoisting", 0.05, METHOD)}


def test_the_floors_are_computed_once_per_version_of_the_code_and_read_back_equal(tmp_path, monkeypatch):
    computed = []
    monkeypatch.setattr(floor, "scenario_floors", lambda: computed.append(1) or FLOORS)
    assert floor.stored_scenario_floors(tmp_path) == FLOORS and len(computed) == 1
    assert floor.stored_scenario_floors(tmp_path) == FLOORS and len(computed) == 1  # read back: floats exact, None
    monkeypatch.setattr(floor, "code_key", lambda: "another-version")
    assert floor.stored_scenario_floors(tmp_path) == FLOORS and len(computed) == 2  # other code: computed again
    (tmp_path / "another-version.json").write_text('{"S1": [')  # torn: computed again, not an error
    assert floor.stored_scenario_floors(tmp_path) == FLOORS and len(computed) == 3
