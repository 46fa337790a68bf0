"""Systems as data: name matching, SSP and OSP files in and out, .ssv parameter sets, libcosim."""

import json
import math
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
from helpers import assert_libcosim_matches, libcosim_run

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import systems_dir
from crane_fmu.cli import main
from crane_fmu.cosim import ArrayRecorder, Connection, System, connect, read_csv, simulate
from crane_fmu.cosim.ssp import load_parameters, load_system, write_ssp, write_ssv
from crane_fmu.model import backstepping, plant

CRANE = {"plant": (["u"], ["x", "dx", "theta1", "dtheta1", "theta2", "dtheta2", "x1"]),
         "controller": (["x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"], ["u"])}


@pytest.mark.quick
def test_matching_names_connects_the_crane_pair():
    found = connect(CRANE)
    assert sorted(found) == sorted([Connection("plant", s, "controller", s) for s in CRANE["controller"][0]]
                                   + [Connection("controller", "u", "plant", "u")])


@pytest.mark.quick
def test_written_out_connections_win_and_ambiguity_is_refused():
    interfaces = {**CRANE, "planner": ([], ["x"])}
    with pytest.raises(ValueError, match="input controller.x matches the outputs of plant, planner: connect it"):
        connect(interfaces)
    found = connect(interfaces, [Connection("planner", "x", "controller", "x")])
    assert Connection("planner", "x", "controller", "x") in found
    assert Connection("plant", "x", "controller", "x") not in found
    assert connect(interfaces, [], match_names=False) == []


@pytest.mark.quick
@pytest.mark.parametrize("conn, message", [
    (Connection("plant", "x", "nobody", "x"), "unknown instance 'nobody'"),
    (Connection("plant", "u", "controller", "x"), "plant.u is not an output"),
    (Connection("plant", "x", "controller", "u"), "controller.u is not an input"),
])
def test_bad_connections_are_named(conn, message):
    with pytest.raises(ValueError, match=message):
        connect(CRANE, [conn])


@pytest.fixture(scope="module")
def system_files(fmu_dir):
    """The paper system's SSP and OSP files, as ``crane-fmu build`` (the session's build) writes them."""
    return systems_dir(fmu_dir) / "paper.ssp", fmu_dir / "paper.OspSystemStructure.xml"


def test_ssp_describes_the_paper_system(system_files, fmu_dir):
    ssp, _ = system_files
    with zipfile.ZipFile(ssp) as package:
        assert sorted(package.namelist()) == ["SystemStructure.ssd", "resources/BacksteppingController.fmu",
                                              "resources/CranePlant.fmu"]
    fmus, connections = systems.get("paper").resolve(fmu_dir)
    with load_system(ssp) as system:
        assert sorted(system.instances) == sorted(fmus)
        assert sorted(system.connections) == sorted(connections) and len(connections) == 7
        # every value (no limit is 1e60: libcosim refuses INF in system files, OMSimulator logs an error for
        # it), but a String at the FMU's own start value (OMSimulator applies no String, and logs an error); the
        # crane's parameters once, the system's, which the instances' are mapped to (test_crane_parameters.py)
        crane = {"m1": 3.0, "m2": 7.0, "l1": 1.0, "l2": 0.5, "g": 9.8}
        assert system.parameters["crane"] == crane
        for instance, component in (("plant", plant.COMPONENT), ("controller", backstepping.COMPONENT)):
            defaults = component.defaults()
            assert system.parameters[instance] == {k: v for k, v in defaults.items()
                                                   if not isinstance(v, str) and k not in crane}
            assert defaults["u_max"] == defaults["v_max"] == 1e60 and all(map(math.isfinite, system.parameters[
                instance].values()))
        assert (system.start_time, system.stop_time, system.step) == (0.0, 20.0, 1e-3)  # the step: OMSimulator's


def test_osp_file_lists_simulators_values_and_connections(system_files, fmu_dir):
    import xml.etree.ElementTree as ET

    _, osp = system_files
    ns = {"o": "http://opensimulationplatform.com/MSMI/OSPSystemStructure"}
    root = ET.parse(osp).getroot()
    assert sorted(s.get("source") for s in root.iterfind(".//o:Simulator", ns)) == [
        "BacksteppingController.fmu", "CranePlant.fmu"]
    assert all((fmu_dir / s.get("source")).is_file() for s in root.iterfind(".//o:Simulator", ns))
    assert len(root.findall(".//o:VariableConnection", ns)) == 7


def test_simulate_runs_the_ssp_like_the_named_system(system_files, fmu_dir, tmp_path, capsys):
    ssp, _ = system_files
    assert main(["simulate", "--system", str(ssp), "--stop-time", "1", "--out", str(tmp_path / "ssp.csv")]) == 0
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "1", "--out", str(tmp_path / "name.csv")]) == 0
    assert (tmp_path / "ssp.csv").read_bytes() == (tmp_path / "name.csv").read_bytes()
    assert main(["simulate", "--system", str(ssp), "--stop-time", "1", "--set", "controller.w_theta2=0",
                 "--out", str(tmp_path / "w.csv")]) == 0
    assert not np.array_equal(read_csv(tmp_path / "w.csv")["plant.x"], read_csv(tmp_path / "ssp.csv")["plant.x"])


def test_parameters_from_an_ssv_file(fmu_dir, tmp_path, capsys):
    ssv = write_ssv({"plant": {"l1": 1.5, "theta1_0": 0.2}, "controller": {"l1": 1.5, "b3_form": "printed"}},
                    tmp_path / "long.ssv")
    assert load_parameters(ssv) == {"plant": {"l1": 1.5, "theta1_0": 0.2},
                                    "controller": {"l1": 1.5, "b3_form": "printed"}}
    common = ["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "0.05"]
    assert main(common + ["--parameters", str(ssv), "--set", "plant.theta1_0=0.1", "--out",
                          str(tmp_path / "a.csv")]) == 0
    assert main(common + ["--set", "plant.l1=1.5", "--set", "plant.theta1_0=0.1", "--set", "controller.l1=1.5",
                          "--set", "controller.b3_form=printed", "--out", str(tmp_path / "b.csv")]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()  # --set wins over the file


def test_a_typo_in_an_ssv_file_is_one_line_naming_the_file_and_the_name(fmu_dir, tmp_path, capsys):
    """The same check as --set's (one checker of INSTANCE.VARIABLE names), nothing written."""
    ssv = write_ssv({"plant": {"L1": 1.5}}, tmp_path / "typo.ssv")
    out = tmp_path / "never.csv"
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--parameters", str(ssv), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--parameters {ssv}: plant.L1: plant has no parameter or input 'L1'" in err
    assert not out.exists()


def test_ssd_with_parameters_in_ssv_files_bound_to_components_and_system(system_files, tmp_path):
    ssp, _ = system_files
    with zipfile.ZipFile(ssp) as package:
        package.extractall(tmp_path)
    ssd = (tmp_path / "SystemStructure.ssd").read_text()
    component_set = ssd.index('<ssd:ParameterBinding>', ssd.index('name="controller"'))
    end = ssd.index("</ssd:ParameterBinding>", component_set) + len("</ssd:ParameterBinding>")
    ssd = ssd[:component_set] + '<ssd:ParameterBinding source="ctrl.ssv" prefix="ctrl." />' + ssd[end:]
    ssd = ssd.replace("<ssd:Connections>", '<ssd:ParameterBindings><ssd:ParameterBinding source="system.ssv" />'
                                           "</ssd:ParameterBindings><ssd:Connections>")
    (tmp_path / "SystemStructure.ssd").write_text(ssd)
    write_ssv({"ctrl": {"w_theta2": 0.0}}, tmp_path / "ctrl.ssv")
    write_ssv({"plant": {"l2": 0.25}}, tmp_path / "system.ssv")
    with load_system(tmp_path / "SystemStructure.ssd") as system:
        assert system.parameters["controller"] == {"w_theta2": 0.0}
        assert system.parameters["plant"]["l2"] == 0.25 and system.parameters["plant"]["x0"] == 0.0
        assert system.parameters["crane"]["l2"] == 0.5  # the crane's: the plant's own value overrides it


@pytest.mark.quick
@pytest.mark.parametrize("content, message", [(b"not a zip", "is not an SSP package"), (None, "not found")])
def test_bad_system_files_are_one_line_errors(tmp_path, capsys, content, message):
    path = tmp_path / "broken.ssp"
    if content is not None:
        path.write_bytes(content)
    assert main(["simulate", "--system", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_a_system_of_other_fmus_plots_what_it_has(fmu_dir, tmp_path, capsys):
    """A system without a crane: the CSV has its columns, the plot one panel per output."""
    floor = System("floor", {"a": str(fmu_dir / "TrivialPlant.fmu"), "b": str(fmu_dir / "TrivialController.fmu")})
    ssp = write_ssp(floor, fmu_dir, tmp_path / "floor.ssp")
    assert main(["simulate", "--system", str(ssp), "--stop-time", "0.1", "--step", "0.01", "--out",
                 str(tmp_path / "f.csv"), "--plot", str(tmp_path / "f.png")]) == 0
    assert list(read_csv(tmp_path / "f.csv")) == ["time", "a.x", "a.dx", "a.theta1", "a.dtheta1", "a.theta2",
                                                  "a.dtheta2", "b.u"]
    assert (tmp_path / "f.png").stat().st_size > 10_000


@pytest.mark.parametrize("kind", ["ssp", "osp"])
def test_libcosim_runs_the_system_like_our_jacobi_master(system_files, crane_fmus, connections, kind):
    theirs = libcosim_run(kind, system_files[0] if kind == "ssp" else system_files[1])
    ours = simulate(crane_fmus, connections, 1.0, 1e-3, "jacobi", recorder=ArrayRecorder()).columns()
    # libcosim steps the same FMUs in the same Jacobi pattern, yet not bit for bit (measured
    # 3e-15 rad on theta1 after 2 s, the paper's stiff loop amplifying rounding); bound 1e-12.
    assert_libcosim_matches(theirs, ours)


def test_the_default_system_is_paper_from_build_fmus(fmu_dir, tmp_path, monkeypatch, capsys):
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "fmus").symlink_to(fmu_dir)
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--stop-time", "1", "--out", "default.csv"]) == 0
    assert main(["simulate", "--system", "paper", "--fmu-dir", str(fmu_dir), "--stop-time", "1",
                 "--out", "named.csv"]) == 0
    assert (tmp_path / "default.csv").read_bytes() == (tmp_path / "named.csv").read_bytes()
    (tmp_path / "build" / "fmus").unlink()
    assert main(["simulate", "--stop-time", "1", "--out", "x.csv"]) == 2
    assert "build/fmus/CranePlant.fmu not found: build the FMUs first" in capsys.readouterr().err


ECOS_RUN = """
import json, sys
from ecospy.EcosSimulation import EcosSimulation
with EcosSimulation(ssp_path=sys.argv[1], step_size=0.001) as sim:
    sim.init(parameter_set="initialValues")
    start = [sim.get_real("plant::" + name) for name in ("x", "theta1")]
    sim.step_until(10.0)
    print(json.dumps([start, [sim.get_real("plant::" + name) for name in ("x", "theta1")]]))
"""


def _ecos_run(ssp, tmp_path):
    """Ecos (the ecospy wheel's engine) on an SSP package: plant ``[[x, theta1] at 0 s, at 10 s]``."""
    pytest.importorskip("ecospy", reason="Ecos (pip install ecospy) is not installed")
    (tmp_path / "ecos_run.py").write_text(ECOS_RUN)
    proc = subprocess.run([sys.executable, str(tmp_path / "ecos_run.py"), str(ssp)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    if "libtbb" in proc.stderr:
        pytest.skip("Ecos needs libtbb.so.12 (apt-get install libtbb12)")
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def transport_ssp(fmu_dir):
    """The transport system's SSP file, as ``crane-fmu build`` (the session's build) writes it."""
    return systems_dir(fmu_dir) / "transport.ssp"


def test_every_component_has_one_parameter_set_of_the_one_name_every_engine_reads(transport_ssp):
    """The SSD form Ecos, libcosim and OMSimulator all apply (see ssp.PARAMETER_SET)."""
    import xml.etree.ElementTree as ET

    from crane_fmu.cosim.ssp import SSD, SSV

    with zipfile.ZipFile(transport_ssp) as package:
        root = ET.fromstring(package.read("SystemStructure.ssd"))
    components = root.findall(f"{SSD}System/{SSD}Elements/{SSD}Component")
    assert sorted(c.get("name") for c in components) == ["controller", "planner", "plant"]
    for component in components:
        bindings = component.findall(f"{SSD}ParameterBindings/{SSD}ParameterBinding")
        assert len(bindings) == 1 and bindings[0].get("prefix") is None and bindings[0].get("source") is None
        sets = bindings[0].findall(f"{SSD}ParameterValues/{SSV}ParameterSet")
        assert [s.get("name") for s in sets] == ["initialValues"]
    # the system's one binding: the crane's parameters, each mapped to the instances it sets (test_crane_parameters)
    bindings = root.findall(f"{SSD}System/{SSD}ParameterBindings/{SSD}ParameterBinding")
    assert len(bindings) == 1 and bindings[0].get("prefix") is None and bindings[0].get("source") is None
    assert [s.get("name") for s in bindings[0].findall(f"{SSD}ParameterValues/{SSV}ParameterSet")] == ["initialValues"]
    assert [p.get("name") for p in bindings[0].iter(f"{SSV}Parameter")] == [f"crane.{n}" for n in ("m1", "m2", "l1",
                                                                                                     "l2", "g")]


@pytest.mark.parametrize("engine", ["ours", "libcosim", "ecos"])
def test_every_engine_moves_the_transport_package_from_rest_to_x_d(transport_ssp, engine, tmp_path, capsys):
    """The package's parameters reach every engine: the plant starts at rest (not the FMU's default
    of 10 degrees) and the planner's 2 m move ends there (the LQR's residual swing is far below the
    bounds: the bounds tell a move that happened from one that did not)."""
    if engine == "ours":
        assert main(["simulate", "--system", str(transport_ssp), "--out", str(tmp_path / "t.csv")]) == 0
        columns = read_csv(tmp_path / "t.csv")
        start, end = ([columns[f"plant.{name}"][i] for name in ("x", "theta1")] for i in (0, -1))
        assert columns["time"][-1] == 10.0
    elif engine == "libcosim":
        series = libcosim_run("ssp", transport_ssp, steps=10_000)
        start, end = ([series[name][1][i] for name in ("x", "theta1")] for i in (0, -1))
        assert abs(series["x"][0][-1] - 10.0) < 2e-3
    else:
        start, end = _ecos_run(transport_ssp, tmp_path)
    assert start == [0.0, 0.0]
    assert abs(end[0] - 2.0) < 0.01 and abs(end[1]) < math.radians(0.1), end


def _pushed(fmu_dir, tmp_path):
    """The free system with the plant's input u = 0.5 m/s2 (a start value the system sets; nothing feeds u), as an
    SSP and an OSP file: ``(ssp, osp)``."""
    from dataclasses import replace

    from crane_fmu.cosim.osp import write_osp

    free = systems.get("free")
    pushed = replace(free, parameters={"plant": {**free.parameters["plant"], "u": 0.5, "theta1_0": 0.0}})
    return write_ssp(pushed, fmu_dir, tmp_path / "pushed.ssp"), write_osp(pushed, fmu_dir, tmp_path / "pushed.xml")


def test_an_inputs_start_value_the_system_sets_is_in_its_files_and_our_master_takes_it(fmu_dir, tmp_path, capsys):
    """free.ssp keeps u = 0 (read back: no input left unfed, no warning); a system's u = 0.5 in the SSP and OSP files
    moves the trolley x = u t^2 / 2 (0.25 m at 1 s: RK4 integrates a constant acceleration exactly)."""
    with systems.open_system(str(systems_dir(fmu_dir) / "free.ssp")) as free:
        assert free.parameters["plant"]["u"] == 0.0
    assert main(["simulate", "--system", str(systems_dir(fmu_dir) / "free.ssp"), "--stop-time", "0.1", "--out",
                 str(tmp_path / "free.csv")]) == 0
    assert "warning" not in capsys.readouterr().err
    ssp, osp = _pushed(fmu_dir, tmp_path)
    assert main(["simulate", "--system", str(ssp), "--stop-time", "1", "--out", str(tmp_path / "pushed.csv")]) == 0
    assert read_csv(tmp_path / "pushed.csv")["plant.x"][-1] == pytest.approx(0.25, abs=1e-12)
    initial = [v.get("variable") for v in ET.parse(osp).getroot().iter() if v.tag.endswith("InitialValue")]
    assert "u" in initial


@pytest.mark.parametrize("engine", ["omsimulator", "libcosim-ssp", "libcosim-osp"])
def test_other_engines_take_an_inputs_start_value_from_the_files(fmu_dir, tmp_path, engine):
    """OMSimulator and libcosim apply the files' u = 0.5 to the unfed input: x(t) = u t^2 / 2."""
    ssp, osp = _pushed(fmu_dir, tmp_path)
    if engine == "omsimulator":
        from third_party_hosts import OMSIMULATOR, omsimulator_log_problems, read_oms_mat, run_tool, tool

        code, log = run_tool([tool(OMSIMULATOR), f"--tempDir={tmp_path / 'oms'}", "--stopTime=1.0",
                              f"--resultFile={tmp_path / 'oms.mat'}", ssp], tmp_path)
        assert code == 0 and not omsimulator_log_problems(log), log[-3000:]
        t, x = 1.0, read_oms_mat(tmp_path / "oms.mat", 1e-3)["free.free.plant.x"][-1]
    else:
        series = libcosim_run(engine.split("-")[1], ssp if engine.endswith("ssp") else osp, steps=1000)
        t, x = series["x"][0][-1], series["x"][1][-1]  # its last sample: 0.999 s
        assert abs(t - 1.0) < 2e-3
    assert x == pytest.approx(0.5 * t * t / 2, abs=1e-9)
