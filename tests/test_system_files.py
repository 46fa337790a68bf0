"""The SSP package and the OSP file: read by our master, and run by libcosim."""

import json
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from build_scripts.system_files import write_osp, write_ssp
from crane_fmu.cli import main
from crane_fmu.cosim import ArrayRecorder, crane_system, read_csv, simulate
from crane_fmu.cosim.ssp import load_system
from crane_fmu.model import tables


@pytest.fixture(scope="module")
def system_files(fmu_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("system")
    return write_ssp(fmu_dir, out / "CraneSystem.ssp"), write_osp(fmu_dir)


def test_ssp_describes_the_crane_system(system_files, fmu_dir):
    ssp, _ = system_files
    with zipfile.ZipFile(ssp) as package:
        assert sorted(package.namelist()) == ["SystemStructure.ssd", "resources/BacksteppingController.fmu",
                                              "resources/CranePlant.fmu"]
    fmus, connections = crane_system(fmu_dir)
    with load_system(ssp) as system:
        assert sorted(system.fmus) == sorted(fmus)
        assert sorted(system.connections) == sorted(connections)
        assert system.parameters["plant"] == tables.defaults(tables.PLANT)
        assert system.parameters["controller"] == tables.defaults(tables.CONTROLLER)


def test_osp_file_lists_simulators_values_and_connections(system_files, fmu_dir):
    _, osp = system_files
    ns = {"o": "http://opensimulationplatform.com/MSMI/OSPSystemStructure"}
    root = ET.parse(osp).getroot()
    assert sorted(s.get("source") for s in root.iterfind(".//o:Simulator", ns)) == [
        "BacksteppingController.fmu", "CranePlant.fmu"]
    assert all((fmu_dir / s.get("source")).is_file() for s in root.iterfind(".//o:Simulator", ns))
    assert len(root.findall(".//o:VariableConnection", ns)) == 7


def test_simulate_system_runs_the_ssp_like_the_built_in_system(system_files, fmu_dir, tmp_path, capsys):
    ssp, _ = system_files
    assert main(["simulate", "--system", str(ssp), "--stop-time", "1", "--out", str(tmp_path / "ssp.csv")]) == 0
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "1", "--out", str(tmp_path / "dir.csv")]) == 0
    assert (tmp_path / "ssp.csv").read_bytes() == (tmp_path / "dir.csv").read_bytes()
    assert main(["simulate", "--system", str(ssp), "--stop-time", "1", "--set", "controller.w_theta2=0",
                 "--out", str(tmp_path / "w.csv")]) == 0
    assert not np.array_equal(read_csv(tmp_path / "w.csv")["plant.x"], read_csv(tmp_path / "ssp.csv")["plant.x"])


@pytest.mark.parametrize("content, message", [(b"not a zip", "is not an SSP package"),
                                              (None, "not found")])
def test_bad_system_files_are_one_line_errors(tmp_path, capsys, content, message):
    path = tmp_path / "broken.ssp"
    if content is not None:
        path.write_bytes(content)
    assert main(["simulate", "--system", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


LIBCOSIM = textwrap.dedent("""
    import json, sys
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    kind, path, steps = sys.argv[1], sys.argv[2], int(sys.argv[3])
    if kind == "ssp":
        execution = CosimExecution.from_ssp_file(path, step_size=1_000_000)  # 1 ms in ns
    else:
        execution = CosimExecution.from_osp_config_file(path)
    plant = [s.index for s in execution.slave_infos() if s.name.decode() == "plant"][0]
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(plant)}
    observer = CosimObserver.create_time_series(buffer_size=steps + 10)
    execution.add_observer(observer)
    for name in ("x", "theta1", "theta2"):
        observer.start_time_series(plant, refs[name], CosimVariableType.REAL)
    execution.simulate_until(target_time=steps * 1_000_000)
    series = {}
    for name in ("x", "theta1", "theta2"):
        times, _, values = observer.time_series_real_samples(plant, refs[name], from_step=0, sample_count=steps + 5)
        series[name] = [[t * 1e-9 for t in times], list(values)]
    print(json.dumps(series))
""")


@pytest.mark.parametrize("kind", ["ssp", "osp"])
def test_libcosim_runs_the_system_like_our_jacobi_master(system_files, crane_fmus, kind):
    pytest.importorskip("libcosimpy")
    path = system_files[0] if kind == "ssp" else system_files[1]
    proc = subprocess.run([sys.executable, "-c", LIBCOSIM, kind, str(path), "1000"], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    theirs = json.loads(proc.stdout.strip().splitlines()[-1])
    fmus, connections = crane_system(crane_fmus["plant"].parent)
    ours = simulate(fmus, connections, 1.0, 1e-3, "jacobi", recorder=ArrayRecorder()).columns()
    for name in ("x", "theta1", "theta2"):
        times, values = np.array(theirs[name][0]), np.array(theirs[name][1])
        assert len(times) > 900
        index = np.rint(times / 1e-3).astype(int)
        # libcosim steps the same FMUs in the same Jacobi pattern, yet not bit for bit (measured
        # 3e-15 rad on theta1 after 2 s, the paper's stiff loop amplifying rounding); bound 1e-12.
        assert np.abs(values - ours["plant." + name][index]).max() < 1e-12


def test_the_default_system_is_build_crane_system_ssp(system_files, fmu_dir, tmp_path, monkeypatch, capsys):
    ssp, _ = system_files
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "CraneSystem.ssp").write_bytes(ssp.read_bytes())
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--stop-time", "1", "--out", "default.csv"]) == 0
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "1", "--out", "dir.csv"]) == 0
    assert (tmp_path / "default.csv").read_bytes() == (tmp_path / "dir.csv").read_bytes()
    (tmp_path / "build" / "CraneSystem.ssp").unlink()
    assert main(["simulate", "--stop-time", "1", "--out", "x.csv"]) == 2
    assert "build/CraneSystem.ssp not found: build the FMUs first" in capsys.readouterr().err
