"""The component registry: a controller kind that lives only in the tests works everywhere.

``pd_controller.py`` (one model module with one descriptor) is registered here,
with a system that uses it; then it is built, simulated by name, written into an
SSP file, run by libcosim and swept on Dask, and no other file of the project
names it.
"""

import math
import tempfile
from pathlib import Path

import numpy as np
import pd_controller
import pyarrow.parquet as pq
import pytest
from helpers import assert_libcosim_matches, libcosim_run

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import build_all, systems_dir
from crane_fmu.cli import main
from crane_fmu.cosim import ArrayRecorder, System, read_csv, run
from crane_fmu.cosim.instance import _SPARE_FOLDERS
from crane_fmu.model import plant
from crane_fmu.model.component import Component
from crane_fmu.sweep import spec
from crane_fmu.sweep.runner import run_study

PD = System("pd", {"plant": "CranePlant", "controller": "PdController"},
            parameters={"controller": {"x_d": 0.5}}, stop_time=5.0, description="test: PD on the trolley")



@pytest.fixture(scope="module")
def pd_build(tmp_path_factory):
    components.register(pd_controller.COMPONENT)
    systems.register(PD)
    try:
        out = tmp_path_factory.mktemp("pd") / "fmus"
        build_all(out, ["CranePlant", "PdController"], systems=["pd"], native=False, log=lambda _: None)
        yield out
    finally:
        components.unregister("PdController")
        systems.unregister("pd")


def _python_loop(stop_time, step, k_x=4.0, k_v=3.0, x_d=0.5):
    """The same loop without FMI: the plant's update and the law, Gauss-Seidel order."""
    config = plant.configure(plant.COMPONENT.defaults())
    state, rows = config.state0, []
    for k in range(round(stop_time / step)):
        u = pd_controller.law(state, k_x, k_v, x_d)
        rows.append(state[:6])
        state = plant.update(config, state, (u, 0.0, 0.0, 0.0), k * step, step)
    return np.array(rows + [state[:6]])


def test_the_new_kind_is_built_in_both_fmi_versions(pd_build):
    assert (pd_build / "PdController.fmu").is_file() and (pd_build.parent / "fmi3" / "PdController.fmu").is_file()
    assert (systems_dir(pd_build) / "pd.ssp").is_file() and (pd_build / "pd.OspSystemStructure.xml").is_file()


def test_simulated_by_name_equals_the_python_loop(pd_build, tmp_path, capsys):
    assert main(["simulate", "--system", "pd", "--fmu-dir", str(pd_build), "--step", "0.01",
                 "--out", str(tmp_path / "pd.csv"), "--plot", str(tmp_path / "pd.png")]) == 0
    result = read_csv(tmp_path / "pd.csv")
    expected = _python_loop(5.0, 0.01)
    got = np.column_stack([result[f"plant.{n}"] for n in ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")])
    assert np.array_equal(got, expected)  # the same Python code on both sides: bit for bit
    assert abs(result["plant.x"][-1] - 0.5) < 0.02  # the PD law moves the trolley to x_d
    fmi3 = run(systems.prepare(PD, 0.01), pd_build.parent / "fmi3", recorder=ArrayRecorder()).columns()
    assert np.array_equal(fmi3["plant.x"], result["plant.x"])


def test_its_parameter_rules_apply_by_model_identifier(pd_build, tmp_path, capsys):
    assert main(["simulate", "--system", "pd", "--fmu-dir", str(pd_build), "--set", "controller.k_v=-1",
                 "--out", str(tmp_path / "bad.csv")]) == 2
    assert "controller: k_v must be > 0 and finite, got -1.0" in capsys.readouterr().err


def test_the_ssp_file_runs_in_libcosim_like_our_jacobi_master(pd_build):
    theirs = libcosim_run("ssp", systems_dir(pd_build) / "pd.ssp")
    ours = run(PD, pd_build, algorithm="jacobi", recorder=ArrayRecorder(), stop_time=1.0).columns()
    assert_libcosim_matches(theirs, ours)


def test_swept_on_dask(pd_build, tmp_path, monkeypatch):
    """A sweep on a local cluster of its own; its workers leave no extracted FMU behind when they stop."""
    study = spec.parse({"system": "pd", "stop_time": 2.0, "step": 0.01,
                        "parameters": {"controller.k_x": [2.0, 8.0], "controller.k_v": [3.0, -1.0]}})
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setenv("TMPDIR", str(temporary))  # the workers' temporary folder: they take this environment
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    summary = run_study(study, tmp_path / "out", pd_build, workers=2, progress=False)
    ours = {Path(folder) for folders in _SPARE_FOLDERS.values() for folder, _ in folders}  # removed at our exit
    assert [p for p in temporary.glob("*/modelDescription.xml") if p.parent not in ours] == []
    rows = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    assert summary["cases"] == 4 and [r["status"] for r in rows] == ["ok", "invalid", "ok", "invalid"]
    expected = _python_loop(2.0, 0.01, k_x=2.0)
    assert rows[0]["max_theta1_deg"] == pytest.approx(math.degrees(np.abs(expected[:, 2]).max()), rel=1e-12)
    assert rows[1]["error"] == "controller: k_v must be > 0 and finite, got -1.0"


@pytest.mark.quick
def test_descriptors_are_checked():
    table = pd_controller.COMPONENT.variables
    with pytest.raises(ValueError, match="role must be one of plant, controller, planner, disturbance, sensor, "):
        Component("X", "observer", "", table, pd_controller.configure, lambda *a: ())
    with pytest.raises(ValueError, match="X.k_x: unit must be one of"):
        Component("X", "controller", "", (table[0]._replace(unit="furlong"),), pd_controller.configure, lambda *a: ())
    with pytest.raises(ValueError, match="a component 'CranePlant' is already registered"):
        components.register(Component("CranePlant", "plant", "", table, pd_controller.configure, lambda *a: ()))


@pytest.mark.quick
@pytest.mark.parametrize("name, text, message", [
    ("nothing.py", "X = 1\n", "--component {path}: defines no Component (crane_fmu.model.component.Component)"),
    ("broken.py", "import no_such_module_here\n",
     "--component {path}: importing it failed: ModuleNotFoundError: No module named 'no_such_module_here'"),
    ("notes.txt", "", "--component {path}: expected a Python file (MODULE.py) that defines a Component"),
    ("json.py", "", "--component {path}: 'json' is a standard library module's name; rename the file"),
    ("taken.py", "from crane_fmu.model.lqr import COMPONENT\n",
     "--component {path}: defines no Component"),  # an imported one is not the module's own
])
def test_build_component_mistakes_are_one_line(tmp_path, capsys, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    assert main(["build", "--component", str(path), "--out", str(tmp_path / "fmus")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message.format(path=path) in err
    assert not (tmp_path / "fmus").exists()


def test_build_component_leaves_another_module_of_that_name_alone(tmp_path):
    """A module already imported under the file's name (a pythonfmu build's, say) is back after the build."""
    import sys
    from pathlib import Path

    text = Path(pd_controller.__file__).read_text().replace('"PdController"', '"PdTwo"')
    (tmp_path / "pd_controller.py").write_text(text)
    assert main(["build", "--component", str(tmp_path / "pd_controller.py"), "--out", str(tmp_path / "fmus")]) == 0
    assert (tmp_path / "fmus" / "PdTwo.fmu").is_file() and (tmp_path / "fmus" / "fmi3" / "PdTwo.fmu").is_file()
    assert sys.modules["pd_controller"] is pd_controller and components.find("PdTwo") is None
