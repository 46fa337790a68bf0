"""The paired design stored with the package (analysis/designs.json): used only while it is of the code that draws it,
and equal, case for case and bit for bit, to the design drawn now."""

import json

import pytest

from crane_fmu.analysis import planar_scenarios as planar
from crane_fmu.analysis.scenarios import CASES, QUICK_CASES

pytestmark = pytest.mark.quick


def test_the_stored_designs_are_of_the_code_of_now_and_equal_those_drawn_now():
    """When this fails after an edit of drawn_design, FACTORS or DESIGN_SEED:
    `python -c "from crane_fmu.analysis.planar_scenarios import write_designs; write_designs()"` stores them again."""
    stored = json.loads(planar.DESIGNS.read_text())
    assert stored["key"] == planar.design_key(), "analysis/designs.json is not of the code of now: write it again"
    same = stored["versions"] == planar.library_versions()  # else not used: drawn with the libraries of now
    for n in (CASES, QUICK_CASES):
        assert planar.design(n) == planar.drawn_design(n)
        assert (stored["designs"][str(n)] == planar.design(n)) or not same
    assert planar.design(5) == planar.drawn_design(5)  # another size: drawn


def test_a_stored_design_of_other_code_or_torn_is_not_used(tmp_path, monkeypatch):
    path = tmp_path / "designs.json"
    planar.write_designs(path, sizes=(3,))
    read = planar._stored_designs.__wrapped__  # not the process's cache: read now
    assert read(path) == json.loads(path.read_text())["designs"]  # of the code of now: used
    monkeypatch.setattr(planar, "DESIGN_SEED", planar.DESIGN_SEED + 1)
    assert read(path) == {}  # another seed: drawn
    monkeypatch.undo()
    monkeypatch.setattr(planar, "library_versions", lambda: "numpy 0.0 scipy 0.0")
    assert read(path) == {}  # other libraries: drawn
    monkeypatch.undo()
    path.write_text('{"key": ')
    assert read(path) == {}  # torn: drawn, not an error
    with pytest.raises(ValueError, match="cases must be a whole number >= 1, got 0"):
        planar.design(0)
