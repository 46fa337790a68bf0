"""The planner's ``shaper`` is an FMI Enumeration (issue 49): OMSimulator applies no String from a system file, so a
String shaper ran the FMU's own (zv) there with exit 0. Users keep writing its name; files carry its value."""

import zipfile

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import systems_dir
from crane_fmu.cli import main
from crane_fmu.cosim import read_csv
from crane_fmu.model import planner
from crane_fmu.model.tables import enumeration_name, enumeration_value

SHAPER = next(v for v in planner.VARIABLES if v.name == "shaper")


@pytest.mark.quick
def test_the_shaper_is_an_enumeration_of_every_shaper_the_planner_knows():
    assert SHAPER.type == "Enumeration" and set(SHAPER.items) == set(planner.SHAPERS)
    assert [enumeration_value(SHAPER, name) for name in SHAPER.items] == [1, 2, 3, 4, 5]
    assert [enumeration_name(SHAPER, value) for value in (1, 2, 3, 4, 5)] == list(SHAPER.items)
    with pytest.raises(ValueError, match=r"^shaper must be one of 1 \(none\), 2 \(zv\), 3 \(zvd\), 4 \(ei\), "
                                         r"5 \(shortest\), got 6$"):
        enumeration_name(SHAPER, 6)
    with pytest.raises(ValueError, match=r"^shaper must be one of none, zv, zvd, ei, shortest, got 'ZVD'$"):
        enumeration_value(SHAPER, "ZVD")


@pytest.mark.quick
@pytest.mark.parametrize("given, named", [(3, "zvd"), (3.0, "zvd"), (1, "none"), ("ei", "ei")])
def test_a_systems_shaper_given_by_value_is_run_by_its_name(given, named):
    """An SSP or OSP file carries the item's value (3); the components' rules and Python models read the name."""
    system = systems.get("transport").with_parameters({"planner": {"shaper": given}})
    assert systems.prepare(system).parameters["planner"]["shaper"] == named


@pytest.mark.quick
@pytest.mark.parametrize("given", [6, 0, 2.5, True, "ZVD", "3"])
def test_a_shaper_no_item_has_is_refused_in_one_line(given):
    system = systems.get("transport").with_parameters({"planner": {"shaper": given}})
    with pytest.raises(ValueError) as refused:
        systems.prepare(system)
    assert "\n" not in str(refused.value) and str(refused.value).startswith("planner: shaper must be")


def test_the_cli_takes_a_shapers_name_and_refuses_another_in_one_line(fmu_dir, tmp_path, capsys):
    out = tmp_path / "zvd.csv"
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", "transport", "--set", "planner.shaper=zvd",
                 "--stop-time", "3", "--out", str(out)]) == 0
    default = tmp_path / "zv.csv"
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", "transport", "--stop-time", "3",
                 "--out", str(default)]) == 0
    zvd, zv = read_csv(out), read_csv(default)
    assert not np.array_equal(zvd["planner.x_ref"], zv["planner.x_ref"])
    capsys.readouterr()
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", "transport", "--set", "planner.shaper=ZVD",
                 "--out", str(tmp_path / "bad.csv")]) == 2
    err = capsys.readouterr().err
    assert err == "crane-fmu: error: planner: shaper must be one of zv, zvd, ei, none, shortest, got 'ZVD'\n"


def test_the_built_ssp_file_carries_the_shapers_values_and_runs_as_the_registered_system(fmu_dir, tmp_path):
    """hoist-transport.ssp: ssv:Integer 3 (zvd) and 1 (none), which OMSimulator applies (its ssv:Enumeration it
    refuses); read back, the file runs as the registered system."""
    ssp = systems_dir(fmu_dir) / "hoist-transport.ssp"
    with zipfile.ZipFile(ssp) as package:
        ssd = package.read("SystemStructure.ssd").decode()
    assert ssd.count('<ssv:Parameter name="shaper">') == 2
    assert '<ssv:Integer value="3" />' in ssd and '<ssv:Integer value="1" />' in ssd
    from_file, registered = tmp_path / "file.csv", tmp_path / "registered.csv"
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", str(ssp), "--out", str(from_file)]) == 0
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", "hoist-transport", "--out", str(registered)]) == 0
    a, b = read_csv(from_file), read_csv(registered)
    assert a.keys() == b.keys() and all(np.array_equal(a[name], b[name]) for name in b)
