"""Our FMUs and SSP files in FMI hosts nobody here wrote, run as a user's tool runs them.

Reference-FMUs' fmusim (FMI 2.0 and 3.0), the FMU Compliance Checker (FMI 2.0) and OMSimulator (SSP
files and FMI 2.0 co-simulation FMUs; its FMI 3.0 import crashes, Reference-FMUs' FMUs' too) against our
master, for every kind of FMU we build: the pythonfmu FMUs, the native components, the one-FMU systems.
The tools live in ``../shared/tools`` (tests/third_party_hosts.py); without them these tests skip.

Tolerance: 1e-9 of each signal's largest magnitude (at least 1). The same FMU binaries run in every host,
so only a host's own rounding of time and steps can move a result: OMSimulator steps by differences of
its summed time, which the paper's law (|u| up to 810 m/s2) carries to 5e-10 of u over 20 s.
"""

import dataclasses
import re

import numpy as np
import pytest
from fmpy import read_model_description
from helpers import kind_folder
from third_party_hosts import (
    FMUCHECK,
    OMSIMULATOR,
    SAME,
    fmusim,
    fmusim_me,
    held_inputs,
    omsimulator_log_problems,
    read_oms_mat,
    run_tool,
    tool,
    worst_difference,
)

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import systems_dir
from crane_fmu.build_scripts.native import native_dir, ported
from crane_fmu.build_scripts.one_fmu import not_native, one_fmu_name, plan
from crane_fmu.cosim import System, run
from crane_fmu.cosim.ssp import load_system, write_ssp

KINDS = ("python", "native", "one-fmu")
ONE_FMU_SYSTEMS = [name for name in systems.tagged("one-fmu") if not not_native(systems.get(name))]
SHORT = 1.0  # s: the stop time where the run's length tests nothing (the step, the outputs, the log do)


def _fmus(request, fmu_dir, kind, version):
    """``{name: path}`` of every FMU of one kind and FMI version that ``crane-fmu build`` writes."""
    folder = kind_folder(request, fmu_dir, kind, version)
    if kind == "python":
        return {c.model_identifier: folder / f"{c.model_identifier}.fmu"
                for c in components.registered() if c.role != "benchmark"}
    if kind == "native":
        return {name: folder / f"{name}.fmu" for name in ported()}
    return {name: folder / f"{one_fmu_name(name)}.fmu" for name in ONE_FMU_SYSTEMS}


def _ours(fmu_dir, kind, name, path, stop_time):
    """Our master's run (Gauss-Seidel) of what the FMU is: the component alone, or the one-FMU's system over
    the native components; ``(columns, [(FMU output, our column)])``."""
    if kind == "one-fmu":
        system = systems.bind(systems.get(name))
        links = plan(system).links
        columns = run(system, native_dir(fmu_dir), stop_time=stop_time).columns()
        outputs = [v.name for v in plan(system).variables if v.causality == "output"]
        return columns, [(own, "{}.{}".format(*links[own][0])) for own in outputs]
    md = read_model_description(str(path))
    columns = run(System(name, {"it": str(path)}, step=float(md.defaultExperiment.stepSize)), fmu_dir,
                  stop_time=stop_time).columns()
    return columns, [(v.name, f"it.{v.name}") for v in md.modelVariables if v.causality == "output"]


# ---- fmusim: FMI 3.0 and 2.0, every FMU we build, under env -i --------------------------------------------------

@pytest.mark.parametrize("version", [3, 2])
@pytest.mark.parametrize("kind", KINDS)
def test_fmusim_runs_every_fmu_like_our_master(fmu_dir, tmp_path, kind, version, request):
    """1 s at each FMU's own step, in a bare environment (``env -i PATH=/usr/bin:/bin``). fmusim reads ``time``
    together with the outputs in one fmi3GetFloat64 call, as FMI 3.0 allows."""
    for name, path in _fmus(request, fmu_dir, kind, version).items():
        step = float(read_model_description(str(path)).defaultExperiment.stepSize)
        theirs = fmusim(path, SHORT, step, tmp_path / f"{name}.csv")
        ours, pairs = _ours(fmu_dir, kind, name, path, SHORT)
        assert np.allclose(theirs["time"], ours["time"], rtol=0, atol=1e-12), name
        assert worst_difference(theirs, ours, pairs) <= SAME, name


# ---- OMSimulator: every SSP file we write, as it is --------------------------------------------------------------

def _omsimulator(ssp, stop_time, tmp_path):
    """OMSimulator on an SSP file or FMU, from a temporary folder: ``(result, log)``."""
    out = tmp_path / "result.mat"
    code, log = run_tool([tool(OMSIMULATOR), f"--tempDir={tmp_path / 'oms'}", f"--stopTime={stop_time!r}",
                          f"--resultFile={out}", *(["--mode=cs"] if ssp.suffix == ".fmu" else []), ssp], tmp_path)
    assert code == 0, f"OMSimulator on {ssp.name}: exit {code}\n{log[-3000:]}"
    return out, log


@pytest.mark.parametrize("name", [s.name for s in systems.registered()])
def test_omsimulator_runs_every_built_in_ssp_file_like_our_master(fmu_dir, tmp_path, name):
    """``OMSimulator --stopTime=T --resultFile=R FILE.ssp`` on the file ``crane-fmu build`` wrote: at the file's step
    (its OMSimulator annotation; OMSimulator reads no other) and stop time (paper; the others 1 s), no warning or
    error in its log (no +-inf parameter, no String connector) and no algebraic loop (the plant's outputs read no
    input); the system's values applied, Enumerations too (hoist-transport's shapers)."""
    ssp = systems_dir(fmu_dir) / f"{name}.ssp"
    with load_system(ssp) as system:
        assert (system.step, system.stop_time) == (systems.get(name).step, systems.get(name).stop_time)
    stop_time = system.stop_time if name == "paper" else SHORT
    out, log = _omsimulator(ssp, stop_time, tmp_path)
    assert omsimulator_log_problems(log) == []
    assert "Alg. loop" not in log
    system = systems.bind(systems.get(name))
    ours = run(system, fmu_dir, stop_time=stop_time).columns()
    theirs = read_oms_mat(out, system.step)
    prefix = re.sub(r"\W", "_", name)
    pairs = [(f"{prefix}.{prefix}.{column}", column) for column in ours if column != "time"]
    assert np.array_equal(theirs["k"], np.arange(len(ours["time"])))
    assert worst_difference(theirs, ours, pairs) <= SAME


def test_omsimulator_applies_hoist_transports_shapers_over_its_whole_run(fmu_dir, tmp_path):
    """hoist-transport.ssp sets the planners' shapers (zvd, none: Enumerations, not the FMU's zv): OMSimulator's 12 s
    equal our master's (fmpy) run of the system, and differ from its run with the FMUs' own shaper (zv), which is
    what OMSimulator ran while the shaper was a String it does not apply."""
    ssp = systems_dir(fmu_dir) / "hoist-transport.ssp"
    system = systems.bind(systems.get("hoist-transport"))
    shapers = {name: values["shaper"] for name, values in system.parameters.items() if "shaper" in values}
    assert shapers == {"planner": "zvd", "hoist": "none"}
    out, log = _omsimulator(ssp, system.stop_time, tmp_path)
    assert omsimulator_log_problems(log) == []
    ours = run(system, fmu_dir).columns()
    theirs = read_oms_mat(out, system.step)
    pairs = [(f"hoist_transport.hoist_transport.{column}", column) for column in ours if column != "time"]
    assert np.array_equal(theirs["k"], np.arange(len(ours["time"])))
    assert worst_difference(theirs, ours, pairs) <= SAME
    default = dataclasses.replace(system, parameters={
        instance: {k: v for k, v in values.items() if k != "shaper"} for instance, values in system.parameters.items()})
    assert worst_difference(theirs, run(default, fmu_dir).columns(), pairs) > 1e-3


@pytest.mark.parametrize("name", ["paper", "lqr"])
def test_omsimulator_runs_an_ssp_file_of_native_fmus_like_our_master(native, tmp_path, name):
    """The SSP writer's file of a system on the native component FMUs (FMI 2.0), 1 s."""
    folder = native[2]
    ssp = write_ssp(systems.get(name), folder, tmp_path / f"{name}.ssp")
    out, log = _omsimulator(ssp, SHORT, tmp_path)
    assert omsimulator_log_problems(log) == [] and "Alg. loop" not in log
    ours = run(systems.get(name), folder, stop_time=SHORT).columns()
    pairs = [(f"{name}.{name}.{column}", column) for column in ours if column != "time"]
    assert worst_difference(read_oms_mat(out, systems.get(name).step), ours, pairs) <= SAME


@pytest.mark.parametrize("name", ONE_FMU_SYSTEMS)
def test_omsimulator_runs_every_one_fmu_to_its_end_like_our_master(fmu_dir, tmp_path, name, request):
    """``OMSimulator --mode=cs --stopTime=10 CraneX.fmu``: 1 ms steps at a summed time, then the remainder step of
    1.03e-13 s, which the one-FMU takes as no step at all (not an error); FMI 2.0."""
    path = _fmus(request, fmu_dir, "one-fmu", 2)[name]
    out, log = _omsimulator(path, 10.0, tmp_path)
    assert omsimulator_log_problems(log) == []
    ours, pairs = _ours(fmu_dir, "one-fmu", name, path, 10.0)
    theirs = read_oms_mat(out, systems.get(name).step)
    assert np.array_equal(theirs["k"], np.arange(len(ours["time"])))
    assert worst_difference(theirs, ours, pairs) <= SAME


@pytest.mark.parametrize("name, folder", [("lqg-transport", "python"), ("lqr", "python")] + [
    (s.name, "native") for s in systems.registered()])
def test_omsimulator_over_a_built_in_ssp_files_full_stop_time_ends_on_our_masters_last_row(fmu_dir, native, tmp_path,
                                                                                         name, folder):
    """OMSimulator over an SSP file for its whole stop time ends with a remainder step of about 1e-13 s (its summed
    time's rounding), which every component, Python and native, takes as no step, as the one-FMU systems do: the
    last row equals our master's (SAME). On main the components took it as a step: lqg-transport's last row
    differed by 1.7e-2 (the state estimator's update; issue 50); the tests of 1 s could not see it. Every built-in
    system on the native FMUs, two on the Python FMUs. The native file is the system's as the build and `export`
    write it, the crane's values included (hoist-transport's crane.l1 = 2 m: without it OMSimulator ran the plant's
    own l1 = 1 m); mpc3d-path's y axis starts at t0 = 2.864 s, which OMSimulator's summed time reaches just short
    (the planner's rounding margin: test_native_mpc3d)."""
    system = systems.get(name)
    if folder == "python":
        ssp = systems_dir(fmu_dir) / f"{name}.ssp"
        fmus = fmu_dir
    else:
        fmus = native[2]
        ssp = systems.write_ssp(system, fmus, tmp_path / f"{name}.ssp")  # as `crane-fmu export` and the build write
    out, log = _omsimulator(ssp, system.stop_time, tmp_path)
    assert omsimulator_log_problems(log) == []
    ours = run(systems.bind(system), fmus).columns()
    theirs = read_oms_mat(out, system.step)
    prefix = re.sub(r"\W", "_", name)
    pairs = [(f"{prefix}.{prefix}.{column}", column) for column in ours if column != "time"]
    assert theirs["k"][-1] == round(system.stop_time / system.step) == len(ours["time"]) - 1
    last = {column: np.array([theirs[column][-1]]) for column, _ in pairs}
    assert worst_difference(last, {c: ours[c][-1:] for _, c in pairs}, pairs) <= SAME


# ---- fmusim's Model Exchange: the crane in three dimensions, moved --------------------------------------------------

ME_TOLERANCE, ME_SAME = 1e-12, 1e-7  # CVODE's relative tolerance; m, m/s, rad: its integration against RK4 at 1 ms


@pytest.mark.parametrize("version", [3, 2])
def test_fmusim_integrates_the_spatial_crane_moved_by_the_planned_accelerations_as_our_master(native, tmp_path,
                                                                                               version):
    """open-loop-3d in our master (the native FMUs, RK4 at 1 ms) for 6 s, the plant's speed limits off; fmusim runs
    the native CranePlant3D as Model Exchange (CVODE) from the same start, its inputs ux and uy the planners'
    accelerations as our master recorded them (held over each step: an input file with a jump at each change): each
    state within 1e-7 of our master's (measured: 5e-10). With the speed limits on (1 m/s, the planners' cruise
    speed), the limit's state events put the hosts 4e-6 m apart: a limit acting, not the integration, so off."""
    system = systems.bind(systems.get("open-loop-3d")).with_parameters({"plant": {"vx_max": 1e60, "vy_max": 1e60}})
    ours = run(system, native[2], stop_time=6.0).columns()
    demands = {axis.demand: ours[f"planner_{axis.position}.ddx_ref"] for axis in systems.plant_of(system).crane.axes}
    inputs = held_inputs(tmp_path / "inputs.csv", ours["time"], demands)
    theirs = fmusim_me(native[version] / "CranePlant3D.fmu", system.parameters["plant"], 6.0, 0.01,
                       tmp_path / "me.csv", ME_TOLERANCE, inputs)
    k = np.rint(theirs["time"] / system.step).astype(int)
    assert np.allclose(theirs["time"], k * system.step, rtol=0, atol=1e-12) and k[-1] == 6000
    states = components.get("CranePlant3D").crane.state
    apart = {name: float(np.abs(theirs[name] - ours[f"plant.{name}"][k]).max()) for name in states}
    assert max(apart.values()) <= ME_SAME, apart
    assert abs(ours["plant.x"][-1] - 2.0) < 1e-9 and abs(ours["plant.y"][-1] - 1.5) < 1e-9  # it moved


# ---- fmuCheck: every FMI 2.0 FMU, the FMU's own log included ----------------------------------------------------

@pytest.mark.parametrize("kind", KINDS)
def test_fmucheck_reports_no_warning_or_error_on_any_fmi2_fmu(fmu_dir, tmp_path, kind, request):
    """``fmuCheck.linux64 -l 4`` (info: the FMU's messages too) checks the XML and runs the FMU alone at its default
    experiment's step: the one-FMU systems and native components to its stop time (hoist-transport's planned end
    of the hoist, at 3 s, is information), the Python FMUs for 2 s (each starts an interpreter: the run's length
    tests nothing more)."""
    for name, path in _fmus(request, fmu_dir, kind, 2).items():
        experiment = read_model_description(str(path)).defaultExperiment
        stop_time = 2.0 if kind == "python" else float(experiment.stopTime)
        code, log = run_tool([tool(FMUCHECK), "-l", "4", "-h", experiment.stepSize, "-s", repr(stop_time), "-n", "0",
                              "-t", tmp_path, "-o", tmp_path / "out.csv", path], tmp_path)
        summary = log[log.rindex("FMU check summary"):] if "FMU check summary" in log else log[-2000:]
        assert code == 0 and f"Simulation finished successfully at time {stop_time:g}" in log, f"{name}: {summary}"
        assert re.search(r"FMU reported:\s+0 warning\(s\) and error\(s\)\s+Checker reported:\s+0 Warning\(s\)\s+"
                         r"0 Error\(s\)", summary), f"{name}: {summary}"
        assert "[WARNING]" not in log and "[ERROR]" not in log, f"{name}: {log[-3000:]}"
