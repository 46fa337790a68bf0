"""`crane-fmu export`: a system with a user's FMU in its place, as an SSP file or as one FMU.

- The SSP file carries the user's FMU, the move it is told (its x_d) and every value; our master runs the
  file as it runs `simulate --use` (bit for bit), and OMSimulator (where ../shared/tools has it) gives the
  same last row.
- As one FMU: fmpy's container when a component is the user's (it runs as our Jacobi master without the
  initial exchange, which is what the container does), one native FMU when every component is native.
- A law file's Component is built as an FMU into the file; a plain law function cannot go into a file: one line.
- `info --system NAME --use INSTANCE=FILE` shows the user's FMU in the system.
"""

import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from third_party_hosts import OMSIMULATOR, SAME, omsimulator_log_problems, read_oms_mat, run_tool, tool

from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.cli import main
from crane_fmu.cosim import read_csv

ROOT = Path(__file__).resolve().parents[1]
STOP = 2.0  # s: the move is under way (x passes 1 m), the swing large


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """The designs' FMUs (plant, planner, LQR) and the user's PD controller (tests/pd_controller.py) built as a
    user builds it."""
    out = tmp_path_factory.mktemp("export")
    build_all(out / "fmus", ["CranePlant", "TrajectoryPlanner", "LqrController"], systems=[], containers=[],
              native=False, fmi3=False, log=lambda line: None)
    assert main(["build", "--component", str(ROOT / "tests" / "pd_controller.py"), "--out", str(out / "mine")]) == 0
    return out


def _main(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out + err


def _simulate(capsys, tmp_path, name, *argv):
    _main(capsys, "simulate", *argv, "--stop-time", STOP, "--out", tmp_path / name)
    return read_csv(tmp_path / name)


def test_an_exported_ssp_with_your_fmu_runs_as_simulate_use(fmus, tmp_path, capsys):
    mine = f"controller={fmus / 'mine' / 'PdController.fmu'}"
    said = _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", mine,
                 "--set", "controller.k_v=2.5", "--out", tmp_path / "mine.ssp")
    assert "controller.x_d = 2 m" in said and "wrote" in said
    with zipfile.ZipFile(tmp_path / "mine.ssp") as ssp:
        assert "resources/PdController.fmu" in ssp.namelist()
    (tmp_path / "elsewhere").mkdir()  # the file alone: no build folder beside it
    shutil.move(tmp_path / "mine.ssp", tmp_path / "elsewhere" / "mine.ssp")
    theirs = _simulate(capsys, tmp_path, "ssp.csv", "--system", tmp_path / "elsewhere" / "mine.ssp")
    ours = _simulate(capsys, tmp_path, "use.csv", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", mine,
                     "--set", "controller.k_v=2.5")
    assert list(theirs) == list(ours)
    for column in ours:
        assert np.array_equal(theirs[column], ours[column]), column
    assert ours["plant.x"][-1] > 1.0  # told the move: the load is on its way to 2 m
    other = _simulate(capsys, tmp_path, "other.csv", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use",
                      mine)
    assert other["plant.x"][-1] != ours["plant.x"][-1]  # the --set value is in the file


def test_omsimulator_runs_the_exported_ssp_to_the_same_last_row(fmus, tmp_path, capsys):
    oms = tool(OMSIMULATOR)
    mine = f"controller={fmus / 'mine' / 'PdController.fmu'}"
    _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", mine, "--out",
          tmp_path / "mine.ssp")
    code, log = run_tool([oms, f"--tempDir={tmp_path / 'oms'}", f"--stopTime={STOP}",
                          f"--resultFile={tmp_path / 'oms.mat'}", tmp_path / "mine.ssp"], tmp_path)
    assert code == 0 and not omsimulator_log_problems(log), log[-3000:]
    theirs = read_oms_mat(tmp_path / "oms.mat", 1e-3)
    ours = _simulate(capsys, tmp_path, "use.csv", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", mine)
    for column in ("plant.x", "plant.theta1", "plant.theta2", "controller.u"):
        scale = max(1.0, abs(ours[column]).max())
        assert abs(theirs[f"transport.transport.{column}"][-1] - ours[column][-1]) <= SAME * scale, column


def test_an_exported_fmu_with_your_fmu_is_a_container_that_runs_as_the_jacobi_master(fmus, tmp_path, capsys):
    mine = f"controller={fmus / 'mine' / 'PdController.fmu'}"
    said = _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", mine, "--out",
                 tmp_path / "MyMove.fmu")
    assert "container" in said
    md = read_model_description(tmp_path / "MyMove.fmu")
    assert md.fmiVersion == "3.0" and {"x", "theta1", "u", "x_d"} <= {v.name for v in md.modelVariables}
    theirs = simulate_fmu(str(tmp_path / "MyMove.fmu"), stop_time=STOP, output_interval=1e-3, step_size=1e-3)
    ours = _simulate(capsys, tmp_path, "jacobi.csv", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", mine,
                     "--algorithm", "jacobi", "--no-initial-exchange")
    for name in ("x", "theta1", "theta2"):  # the plant's state; the container shows u as its last inner step set it
        assert np.array_equal(theirs[name], ours[f"plant.{name}"]), name
    assert ours["plant.x"][-1] > 1.0


def test_an_exported_fmu_of_native_components_is_one_native_fmu(fmus, tmp_path, capsys):
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: a one native FMU cannot be built")
    said = _main(capsys, "export", "--system", "lqr", "--fmu-dir", fmus / "fmus", "--set", "crane.l2=0.6",
                 "--out", tmp_path / "MyLqr.fmu")
    assert "one native FMU" in said
    md = read_model_description(tmp_path / "MyLqr.fmu")
    assert md.coSimulation.modelIdentifier == "MyLqr"
    theirs = simulate_fmu(str(tmp_path / "MyLqr.fmu"), stop_time=STOP, output_interval=1e-3, step_size=1e-3)
    ours = _simulate(capsys, tmp_path, "lqr.csv", "--system", "lqr", "--fmu-dir", fmus / "fmus", "--set",
                     "crane.l2=0.6")
    for name in ("x", "theta1", "theta2"):  # the native twins of the Python FMUs: rounding, not behaviour
        assert abs(theirs[name][-1] - ours[f"plant.{name}"][-1]) <= SAME * max(1.0, abs(ours[f"plant.{name}"]).max())


@pytest.mark.parametrize("use, out, message", [
    ("controller={tmp}/plain.py:law", "x.ssp",
     "a plain law function runs only in this toolkit's master; write it as a Component"),
    ("controller={mine}/PdController.fmu", "x.csv", "--out {tmp}/x.csv: writes a .ssp or .fmu file"),
    ("planner={mine}/PdController.fmu", "x.ssp", "has no output x_ref, which the system connects to controller.x_ref"),
])
def test_what_export_cannot_write_is_one_line(fmus, tmp_path, capsys, use, out, message):
    names = {"root": ROOT, "mine": fmus / "mine", "tmp": tmp_path}
    (tmp_path / "plain.py").write_text("def law(config, state, inputs):\n    return (-inputs[0],)\n")
    code = main(["export", "--system", "transport", "--fmu-dir", str(fmus / "fmus"), "--use", use.format(**names),
                 "--out", str(tmp_path / out)])
    err = capsys.readouterr().err
    assert code == 2 and message.format(**names) in err and err.count("\n") == 1, err
    assert not (tmp_path / out).exists()


def test_a_law_files_component_is_built_into_the_exported_ssp_and_runs_as_its_law_file(fmus, tmp_path, capsys):
    """`export --use controller=pd_sway.py`: the file's Component built as an FMU into the SSP file; the file
    run alone equals `simulate --use controller=pd_sway.py` (the law run in process) on every column, bit for bit."""
    law = f"controller={ROOT / 'examples' / 'my_controller' / 'pd_sway.py'}"
    said = _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", law,
                 "--set", "controller.k_x=1.5", "--out", tmp_path / "law.ssp")
    assert "wrote" in said
    with zipfile.ZipFile(tmp_path / "law.ssp") as ssp:
        assert "resources/PdSway.fmu" in ssp.namelist()
    theirs = _simulate(capsys, tmp_path, "ssp.csv", "--system", tmp_path / "law.ssp")
    ours = _simulate(capsys, tmp_path, "law.csv", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", law,
                     "--set", "controller.k_x=1.5")
    assert list(theirs) == list(ours)
    for column in ours:
        assert np.array_equal(theirs[column], ours[column]), column
    assert ours["plant.x"][-1] > 0.5  # told the move


def test_the_ssp_file_of_your_law_file_packs_as_the_container_export_writes(fmus, tmp_path, capsys):
    """`export --use controller=pd_sway.py --out law.ssp` (no --set: the file holds every value, each the FMU's own
    start value or one the container sets), then `build --container law.ssp`: the container equals the one that
    `export --out Law.fmu` writes, bit for bit, and so our Jacobi master without the initial exchange."""
    law = f"controller={ROOT / 'examples' / 'my_controller' / 'pd_sway.py'}"
    _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", law, "--out",
          tmp_path / "law.ssp")
    assert _main(capsys, "build", "--container", tmp_path / "law.ssp", "--out", tmp_path / "b" / "fmus").splitlines() \
        == [str(tmp_path / "b" / "containers" / "CraneLaw.fmu")]
    _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", law, "--out",
          tmp_path / "Law.fmu")
    theirs, exported = (simulate_fmu(str(path), stop_time=STOP, output_interval=1e-3, step_size=1e-3)
                        for path in (tmp_path / "b" / "containers" / "CraneLaw.fmu", tmp_path / "Law.fmu"))
    assert theirs.dtype.names == exported.dtype.names
    for name in exported.dtype.names:
        assert np.array_equal(theirs[name], exported[name]), name
    ours = _simulate(capsys, tmp_path, "jacobi.csv", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", law,
                     "--algorithm", "jacobi", "--no-initial-exchange")
    for name in ("x", "theta1", "theta2"):
        assert np.array_equal(theirs[name], ours[f"plant.{name}"]), name
    assert ours["plant.x"][-1] > 0.5  # told the move


def test_a_tuned_value_in_an_ssp_file_the_container_cannot_set_is_one_line(fmus, tmp_path, capsys):
    """`export --set controller.k_x=1.5 --out law.ssp`, then `build --container law.ssp`: k_x differs from the FMU's
    start value and the container does not expose it; refused naming it alone, and nothing written."""
    law = f"controller={ROOT / 'examples' / 'my_controller' / 'pd_sway.py'}"
    _main(capsys, "export", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", law, "--set",
          "controller.k_x=1.5", "--out", tmp_path / "law.ssp")
    assert main(["build", "--container", str(tmp_path / "law.ssp"), "--out", str(tmp_path / "b" / "fmus")]) == 2
    err = capsys.readouterr().err
    assert "exposes, not controller.k_x; build it" in err and err.count("\n") == 1, err
    assert not (tmp_path / "b" / "containers").exists() or not any((tmp_path / "b" / "containers").iterdir())


def test_info_shows_your_fmu_in_the_system(fmus, capsys):
    """`info --system transport --use controller=PdController.fmu`: the file in the LQR's place, each parameter with
    the value the system sets (told the move: x_d = 2; --set k_v) or its start value, and the note on the move."""
    mine = fmus / "mine" / "PdController.fmu"
    said = _main(capsys, "info", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", f"controller={mine}",
                 "--set", "controller.k_v=2.5").splitlines()
    at = said.index("  controller = PdController.fmu (yours: PdController, in place of LqrController)")
    assert said[at + 1:at + 4] == ["    k_x = 4.0 (its start value)", "    k_v = 2.5 (set)", "    x_d = 2 (set)"]
    assert any("told the move's target, controller.x_d = 2 m" in line for line in said)
    assert "  planner = TrajectoryPlanner" in said  # the rest of the system as before
    said = _main(capsys, "info", "--system", "transport", "--fmu-dir", fmus / "fmus", "--use", f"controller={mine}",
                 "--set", "planner.x_d=1.5").splitlines()  # told the target as set (it said 2 m)
    assert "    x_d = 1.5 (set)" in said and any("controller.x_d = 1.5 m (planner.x_d)" in line for line in said)
    for argv, message in [(["--use", f"controller={mine}"], "--use needs --system NAME"),
                          (["--system", "transport", "--use", f"controler={mine}"], "did you mean"),
                          (["--system", "transport", "--use", f"controller={mine}", "--set", "controller.k_q=1"],
                           "k_q")]:
        assert main(["info", *map(str, argv), "--fmu-dir", str(fmus / "fmus")]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err


def test_a_sweep_studies_your_fmu_and_its_law_file_alike(fmus, tmp_path, capsys, dask_scheduler):
    """A gains study of the user's controller: `use` in the study file (the FMU) or `--use` (its law file) give the
    same rows; the files' digests are in the case ids, so another controller's study never reuses them."""
    pytest.importorskip("distributed")
    import pyarrow.parquet as pq

    study = tmp_path / "gains.toml"
    study.write_text(f'system = "transport"\nstop_time = 4.0\nstep = 0.001\nmetrics = ["trolley_final_m", '
                     f'"max_theta1_deg"]\n[parameters]\n"controller.k_x" = [1.0, 4.0]\n'
                     f'[use]\ncontroller = "{fmus / "mine" / "PdController.fmu"}"\n')
    tables = {}
    for name, more in (("fmu", []), ("law", ["--use", f"controller={ROOT / 'tests' / 'pd_controller.py'}"])):
        said = _main(capsys, "sweep", study, "--out", tmp_path / name, "--fmu-dir", fmus / "fmus", "--scheduler",
                     dask_scheduler,
                     "--no-progress", *more)
        assert "2 cases: 2 run now, 0 already done, 0 not ok" in said, said
        assert "it is told the move's target, controller.x_d = 2 m" in said  # as simulate says
        tables[name] = pq.read_table(tmp_path / name / "results.parquet").to_pydict()
    fmu, law = tables["fmu"], tables["law"]
    assert list(fmu["status"]) == ["ok", "ok"]
    assert fmu["trolley_final_m"] == law["trolley_final_m"] and fmu["max_theta1_deg"] == law["max_theta1_deg"]
    assert set(fmu["case_id"]).isdisjoint(law["case_id"])  # each study's rows are its controller's
    assert fmu["trolley_final_m"][1] != fmu["trolley_final_m"][0]  # the gain reaches the user's FMU
    assert 1.0 < fmu["trolley_final_m"][1] < 2.2  # told the move (x_d = 2 m) and on its way there


def test_the_python_route_builds_your_system_and_its_ssp_file(tmp_path):
    """The controller interface page's Python route, as written, in a clone's folder: the system file of a system
    with the user's controller names FMUs of one folder, so the plant is built beside it; the page's first call,
    without the plant, is one ValueError naming it (it was a traceback from deep inside the SSP writer)."""
    import re
    import subprocess
    import sys

    page = (ROOT / "docs" / "reference" / "controller-interface.md").read_text()
    block = re.search(r"tests/test_export.py::test_the_python_route_builds_your_system_and_its_ssp_file -->\n"
                      r"```python\n(.*?)```", page, re.S).group(1)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    done = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert re.fullmatch(r"theta1 = -?\d\.\d{4} rad at 5 s; wrote build/systems/pd.ssp\n", done.stdout), done.stdout
    with zipfile.ZipFile(tmp_path / "build" / "systems" / "pd.ssp") as ssp:
        assert {"resources/CranePlant.fmu", "resources/PdSway.fmu"} <= set(ssp.namelist())
    alone = block.replace('["PdSway", "CranePlant"]', '["PdSway"]').replace('"build/mine"', '"build/alone"')
    done = subprocess.run([sys.executable, "-c", alone], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode != 0
    assert done.stderr.strip().splitlines()[-1] == (
        "ValueError: system pd needs CranePlant.fmu in build/alone: build it there too, e.g. "
        "build_all('build/alone', ['PdSway', 'CranePlant'], systems=['pd'])")
