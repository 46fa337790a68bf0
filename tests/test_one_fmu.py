"""A system of native components as one native FMU (build_scripts/one_fmu.py), against our master.

Each built-in system tagged ``one-fmu`` whose components are all native (today ``paper``; the
others join by themselves once their components declare a native model) is built by ``crane-fmu build``
into ``build/native`` as one FMU, FMI 2.0 and 3.0. Run in fmpy, and in the C host without Python and
under Wine (FMI 2.0 and 3.0 alike: the host's ``outputs`` and ``outputs3``), it must give
``crane-fmu simulate --system NAME --fmu-dir build/native`` (our master, Gauss-Seidel, over the
native component FMUs): the same C models in the same order of calls, so 1e-9 guards only against
another order of operations (in practice the bits are equal on Linux).
"""

import shutil
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from helpers import (
    BINARIES,
    HOST_COMMAND,
    OBSERVED,
    host_rows,
    libcosim_run,
    master_run,
    observed,
    observed_columns,
    one_fmu,
    one_fmu_outputs,
    unpack_one_fmu,
)

from crane_fmu import systems
from crane_fmu.build_scripts.one_fmu import not_native, one_fmu_name, plan
from crane_fmu.cli import main
from crane_fmu.cosim import ArrayRecorder, FmiError, open_instance, simulate
from crane_fmu.cosim.master import Master
from crane_fmu.cosim.ssp import load_system

SYSTEMS = [name for name in systems.tagged("one-fmu") if not not_native(systems.get(name))]
CLEAN_ENV = {"PATH": "/usr/bin:/bin"}  # no venv, no pyenv: no Python to be found
SAME = 1e-9  # the same C models, the same calls: any difference is another order of operations


def _deviation(result, columns, name, every=1):
    return max(np.max(np.abs(result[own] - columns[column][::every])) for own, column in one_fmu_outputs(name).items())


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", SYSTEMS)
@pytest.mark.parametrize("every", [1, 2, 10])
def test_the_one_fmu_in_fmpy_is_our_master_over_the_native_fmus(native, tmp_path_factory, name, version, every):
    system = systems.get(name)
    columns = master_run(native, name, tmp=tmp_path_factory.mktemp("runs"))
    h = system.step * every
    result = simulate_fmu(str(one_fmu(native, name, version)), stop_time=system.stop_time, step_size=h,
                          output_interval=h, output=list(one_fmu_outputs(name)))
    assert len(result) == len(columns["time"][::every])
    assert np.array_equal(result["time"], columns["time"][::every])
    assert _deviation(result, columns, name, every) <= SAME


@pytest.mark.parametrize("version", [2, 3])
def test_judged_per_variable_our_master_reads_the_plant_twice_and_runs_every_system_as_its_one_fmu(native, version):
    """The native plant lists that ddx reads u (Model Exchange's acceleration now); nothing reads ddx, so no
    closed loop through u is algebraic. Our master reads the plant before setting u and again after it; the
    one-FMU's exchange, from the components' co-simulation tables (ddx reads no input), reads it once. Every
    built-in system closed through u gives the same numbers both ways, bit for bit (50 steps); so does the open
    loop of a planner per axis, whose plant our master reads once, after the planners."""
    folder = native[version]
    for name in SYSTEMS:
        system = systems.get(name)
        stop = system.start_time + 50 * system.step
        fmus, connections = system.resolve(folder)
        instances = {n: open_instance(path, n) for n, path in fmus.items()}
        try:
            master = Master(instances, connections)
            reads = [(i.name, f) for _, f, i in master.wiring.propagation() if f.endswith(("GetReal", "GetFloat64"))]
            recorder = ArrayRecorder()
            master.run(system.start_time, stop, system.step, [recorder], systems.bind(system).parameters)
            master.terminate()
        finally:
            for instance in instances.values():
                instance.free()
        demands = systems.plant_of(system).crane.demands
        fed = {(c.source, c.input) for c in connections if c.target == "plant" and c.input in demands}
        if any(source == "controller" for source, _ in fed):  # closed through the demands
            assert [i for i, _ in reads].count("plant") == 2, name
        else:  # an open loop (open-loop-3d): the planners' demands are set before the plant is read, once
            assert [i for i, _ in reads] == [*sorted({s for s, _ in fed}), "plant"] and len(fed) == len(demands), name
        ours = recorder.columns()
        one = simulate({"one": one_fmu(native, name, version)}, [], stop, system.step).columns()
        for own, column in one_fmu_outputs(name).items():
            assert np.array_equal(one[f"one.{own}"], ours[column]), (name, own)


def _instance(path, name="one"):
    inst = open_instance(path, name)
    inst.setup(0.0, 20.0)
    inst.enter_initialization()
    inst.exit_initialization()
    return inst


@pytest.mark.parametrize("version", [2, 3])
def test_a_step_that_is_no_whole_multiple_of_the_system_step_is_refused(native, version):
    inst = _instance(one_fmu(native, "paper", version))
    try:
        with pytest.raises(FmiError, match=r"communication step 0\.0015 s must be a whole multiple of the system "
                                            r"step 0\.001 s"):
            inst.do_step(0.0, 0.0015)
    finally:
        inst.free()


@pytest.mark.parametrize("version", [2, 3])
def test_a_host_that_adds_up_its_steps_runs_to_the_end_like_our_master(native, tmp_path_factory, version):
    """t += 0.001 ten thousand times leaves t = 10 - 1.03e-13 (OMSimulator's time, the issue's remainder step); the
    step to 10 s is then within rounding (1e-6 of a system step) of none and taken as none: the outputs at 10 s are
    our master's. A step 1e-5 system steps off a whole number of them is still refused."""
    inst = _instance(one_fmu(native, "lqr", version))
    try:
        t = 0.0
        for _ in range(10_000):
            inst.do_step(t, 0.001)
            t += 0.001
        assert 0 < 10.0 - t < 2e-13
        inst.do_step(t, 10.0 - t)
        columns = master_run(native, "lqr", (), 10.0, tmp=tmp_path_factory.mktemp("runs"))
        assert max(abs(inst.get(own) - columns[column][-1]) for own, column in one_fmu_outputs("lqr").items()) <= SAME
        with pytest.raises(FmiError, match="must be a whole multiple of the system step 0.001 s"):
            inst.do_step(10.0, 0.001 + 1e-8)
    finally:
        inst.free()


@pytest.mark.parametrize("version", [2, 3])
def test_a_step_of_more_than_ten_million_system_steps_is_refused_not_run(native, version):
    """As the plant refuses a step of more than 10^7 RK4 sub-steps: a host must never hang in doStep."""
    inst = _instance(one_fmu(native, "paper", version))
    try:
        inst.do_step(0.0, 1.0)  # 1000 system steps: taken
        with pytest.raises(FmiError, match=r"communication step 20000\.0 s needs more than 10000000 system steps "
                                            r"of 0\.001 s"):
            inst.do_step(1.0, 20_000.0)
    finally:
        inst.free()


def test_an_inner_models_message_names_its_instance(native):
    inst = open_instance(one_fmu(native, "paper"), "one")
    inst.setup(0.0, 20.0)
    inst.set("l1", -1.0)
    inst.enter_initialization()
    try:
        with pytest.raises(FmiError, match="plant: l1 must be > 0 and finite, got -1.0"):
            inst.exit_initialization()
    finally:
        inst.free()


@pytest.mark.quick
def test_paper_interface_is_the_containers():
    links = plan(systems.get("paper")).links
    assert links["m1"] == [("plant", "m1"), ("controller", "m1")]
    assert links["x_d"] == [("controller", "x_d")] and links["theta1_0"] == [("plant", "theta1_0")]
    assert links["u"] == [("controller", "u")] and links["theta2"] == [("plant", "theta2")]
    assert {v.name for v in plan(systems.get("paper")).variables if v.causality == "input"} == {"F1", "F2", "hoist"}


# The instances each parameter of the one-FMU sets, written out here from the rule (the module docstring of
# build_scripts/one_fmu.py, as the container's): m1, m2, l1, l2, g, the crane's, to every instance whose component
# models the crane (plant, controller, planner, estimator) and that has no value of its own (hoist-transport's
# planner keeps its l1 of 1.5 m, its hoist planner its l1 of 1 m); x_d to the planner if there is one, else to the
# controller; theta1_0 to the plant. Not from plan(), the code under test.
PAIR, TRIO = {"plant", "controller"}, {"plant", "controller", "planner"}
CRANE = ("m1", "m2", "l1", "l2", "g")
FORCES_3D = ("F1x", "F1y", "F2x", "F2y")
REACHES = {
    **{name: {**dict.fromkeys(CRANE, PAIR), "x_d": {"controller"}, "theta1_0": {"plant"}, "F1": {"plant"},
              "F2": {"plant"}, "hoist": {"plant"}} for name in ("paper", "lqr", "energy", "hard-hit", "mpc",
                                                                 "mpc-transport")},
    "transport": {**dict.fromkeys(CRANE, TRIO), "x_d": {"planner"}, "theta1_0": {"plant"}, "F1": {"plant"},
                  "F2": {"plant"}, "hoist": {"plant"}},
    "hoist-transport": {**dict.fromkeys(CRANE, TRIO | {"hoist"}), "l1": PAIR, "x_d": {"planner"},
                        "theta1_0": {"plant"}, "F1": {"plant"}, "F2": {"plant"}},
    # the estimator models the crane too: a host's m1 reaches its Kalman filter's design as the controller's
    "lqg": {**dict.fromkeys(CRANE, PAIR | {"estimator"}), "x_d": {"controller"}, "theta1_0": {"plant"},
            "F1": {"plant"}, "F2": {"plant"}, "hoist": {"plant"}},
    "lqg-transport": {**dict.fromkeys(CRANE, TRIO | {"estimator"}), "x_d": {"planner"}, "theta1_0": {"plant"},
                      "F1": {"plant"}, "F2": {"plant"}, "hoist": {"plant"}},
    # a planner per axis, each planning along its own x: y_d is planner_y's x_d; no controller, so each axis's
    # planned acceleration shows as its demand (an output)
    "open-loop-3d": {**dict.fromkeys(CRANE, {"plant", "planner_x", "planner_y"}), "x_d": {"planner_x"},
                     "y_d": {("planner_y", "x_d")}, "theta1x_0": {"plant"}, "hoist": {"plant"},
                     **dict.fromkeys(FORCES_3D, {"plant"})},
    # the crane in three dimensions: y_d to the controller, or to the planner of the y axis alone as its x_d
    # the MPC of each axis takes its own targets (mpc3d-path's waypoint and corridor are the system's, not set here)
    **{name: {**dict.fromkeys(CRANE, PAIR), "x_d": {"controller"}, "y_d": {"controller"}, "theta1x_0": {"plant"},
              **dict.fromkeys(FORCES_3D, {"plant"}), "hoist": {"plant"}}
       for name in ("lqr3d", "mpc3d", "mpc3d-move", "mpc3d-path")},
    **{name: {**dict.fromkeys(CRANE, TRIO | {"planner_y"}), "x_d": {"planner"}, "y_d": {("planner_y", "x_d")},
              "theta1x_0": {"plant"}, **dict.fromkeys(FORCES_3D, {"plant"}), "hoist": {"plant"}}
       for name in ("lqr3d-move", "lqr3d-path")},
}


def _reached(name, own):
    """``[(instance, variable)]`` that the one-FMU's ``own`` sets by :data:`REACHES` (an instance: its ``own``)."""
    return sorted(i if isinstance(i, tuple) else (i, own) for i in REACHES[name][own])


@pytest.mark.quick
@pytest.mark.parametrize("name", SYSTEMS)
def test_each_parameter_and_input_reaches_the_instances_the_rule_names(name):
    p = plan(systems.get(name))
    settable = {v.name for v in p.variables if v.causality in ("parameter", "input")}
    assert settable == set(REACHES[name])
    for own in REACHES[name]:
        assert sorted(p.links[own]) == _reached(name, own), own
    outputs = {v.name for v in p.variables if v.causality == "output"}
    assert set(systems.plant_of(systems.get(name)).crane.demands) <= outputs



@pytest.mark.parametrize("name", SYSTEMS)
def test_an_ssp_files_one_fmu_sets_what_the_built_in_systems_does(fmu_dir, name):
    """The SSP file holds every value, also a controller's own x_d beside its planner's references (transport's LQR:
    0): each own parameter and input still reaches the instances it reaches in the built-in system (x_d the planner
    alone), so that a host that sets every parameter to its start value runs the file's system."""
    with load_system(fmu_dir.parent / "systems" / f"{name}.ssp") as system:
        links = plan(system).links
    assert dict(links) == dict(plan(systems.get(name)).links)

SETTINGS = {"CranePlant": [{"m1": 4.0, "l1": 1.2}, {"theta1_0": 0.1, "x_d": 0.5}, {"F1": 2.0, "F2": -1.0}],
            "CranePlant3D": [{"m1": 4.0, "l1": 1.2}, {"theta1x_0": 0.1, "x_d": 0.5, "y_d": -1.0},
                             {"F1x": 2.0, "F2y": -1.0}]}


# mpc3d-path's x_d is its path's end along x: the x axis moves in the first leg alone (to 3 m), so it stays 3 m
OWN_SETTINGS = {"mpc3d-path": [{"m1": 4.0, "l1": 1.2}, {"theta1x_0": 0.1, "y_d": 2.5}, {"F1x": 2.0, "F2y": -1.0}]}


@pytest.mark.parametrize("name, values", [(name, values) for name in SYSTEMS for values in OWN_SETTINGS.get(
    name, SETTINGS[systems.plant_of(systems.get(name)).model_identifier])],
    ids=lambda s: ",".join(s) if isinstance(s, dict) else s)
def test_values_set_on_the_one_fmu_reach_every_instance_that_has_them(native, tmp_path_factory, name, values):
    """As our master with the same values set on each instance the rule names (REACHES); and they act."""
    settings = [f"{instance}.{variable}={value!r}" for own, value in values.items()
                for instance, variable in _reached(name, own)]
    stop_time = 5.0
    columns = master_run(native, name, settings, stop_time, tmp=tmp_path_factory.mktemp("runs"))
    plain = master_run(native, name, (), stop_time, tmp=tmp_path_factory.mktemp("runs"))
    for version in (2, 3):
        step = systems.get(name).step
        result = simulate_fmu(str(one_fmu(native, name, version)), stop_time=stop_time, step_size=step,
                              output_interval=step, start_values=values, output=list(one_fmu_outputs(name)))
        assert _deviation(result, columns, name) <= SAME
        assert _deviation(result, plain, name) > 1e-3  # they act


@pytest.mark.parametrize("name", SYSTEMS)
def test_setting_every_parameter_to_its_start_value_changes_nothing(native, tmp_path_factory, name):
    """What many tools do (Simulink sets every parameter): the run must be the system's own."""
    md = read_model_description(str(one_fmu(native, name)))
    starts = {v.name: float(v.start) for v in md.modelVariables if v.causality == "parameter"}
    columns = master_run(native, name, (), 5.0, tmp=tmp_path_factory.mktemp("runs"))
    step = systems.get(name).step
    result = simulate_fmu(str(one_fmu(native, name)), stop_time=5.0, step_size=step, output_interval=step,
                          start_values=starts, output=list(one_fmu_outputs(name)))
    assert _deviation(result, columns, name) <= SAME


@pytest.mark.parametrize("name", SYSTEMS)
def test_libcosim_runs_the_one_fmu_from_an_ssp_like_our_master(native, tmp_path, name):
    """The one-FMU as the only component of an SSP package (every parameter set to its start value, as our SSP
    writer does), in libcosim at the system's step."""
    from crane_fmu.cosim import System
    from crane_fmu.cosim.ssp import write_ssp

    system = systems.get(name)
    ssp = write_ssp(System(name, {"crane": str(one_fmu(native, name))}, stop_time=system.stop_time), native[2],
                    tmp_path / f"{name}.ssp")
    steps = round(system.stop_time / system.step)
    ours = master_run(native, name, tmp=tmp_path)
    states, _ = observed(name)
    theirs = libcosim_run("ssp", ssp, steps=steps, instance="crane", names=states)
    for signal in states:
        times, values = np.array(theirs[signal][0]), np.array(theirs[signal][1])
        assert len(times) >= steps
        index = np.rint(times / system.step).astype(int)
        assert np.max(np.abs(values - ours[one_fmu_outputs(name)[signal]][index])) <= SAME, signal


# ---- the C host: no Python; Windows under Wine --------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", SYSTEMS)
def test_the_c_host_runs_the_one_fmu_without_python(native, host, tmp_path, name, version):
    system = systems.get(name)
    guid, vrs = unpack_one_fmu(native, name, tmp_path, version)
    steps = round((system.stop_time - system.start_time) / system.step)
    library = tmp_path / "binaries" / BINARIES[version][0] / f"{one_fmu_name(name)}.so"
    rows = host_rows([host, HOST_COMMAND[version]], library, guid, steps, system.step, *vrs, env=CLEAN_ENV)
    expected = observed_columns(master_run(native, name, tmp=tmp_path), name)
    assert rows.shape == expected.shape
    assert np.max(np.abs(rows - expected)) <= SAME


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", SYSTEMS)
def test_the_windows_dll_under_wine_gives_the_linux_run(native, windows_host, wine_env, tmp_path, name, version):
    """The DLL uses the portable sin, cos and exp, Linux glibc's: as for the plant alone (test_native_hosts), the
    states agree to 1e-9 and u to 1e-9 relative."""
    guid, vrs = unpack_one_fmu(native, name, tmp_path, version)
    dll = tmp_path / "binaries" / BINARIES[version][1] / f"{one_fmu_name(name)}.dll"
    if not dll.exists():
        pytest.skip("the one-FMU has no Windows binary (mingw-w64 missing at build time)")
    shutil.copy(windows_host, tmp_path)
    shutil.copy(dll, tmp_path)
    system = systems.get(name)
    steps = round((system.stop_time - system.start_time) / system.step)
    windows = host_rows(["wine", tmp_path / "host.exe", HOST_COMMAND[version]], dll.name, guid, steps, system.step,
                   *vrs, env=wine_env, cwd=tmp_path)
    expected = observed_columns(master_run(native, name, tmp=tmp_path), name)
    assert windows.shape == expected.shape
    states = 1 + len(observed(name)[0])  # time, then the states; the demands after them
    assert np.max(np.abs(windows[:, :states] - expected[:, :states])) <= SAME
    assert np.max(np.abs(windows[:, states:] - expected[:, states:]) / np.maximum(np.abs(expected[:, states:]), 1.0)) \
        <= SAME


# ---- the command ----------------------------------------------------------------------------------------------------

def test_build_one_fmu_from_an_ssp_file_gives_the_built_in_systems_run(fmu_dir, native, tmp_path, capsys):
    ssp = fmu_dir.parent / "systems" / "paper.ssp"
    out = tmp_path / "fmus"
    assert main(["build", "--out", str(out), "--one-fmu", str(ssp)]) == 0
    written = capsys.readouterr().out.split()
    assert written == [str(tmp_path / "native" / "CranePaper.fmu"),
                       str(tmp_path / "native" / "fmi3" / "CranePaper.fmu")]
    for version in (2, 3):
        ours = simulate_fmu(written[version - 2], stop_time=2.0, output=list(OBSERVED))
        built_in = simulate_fmu(str(one_fmu(native, "paper", version)), stop_time=2.0, output=list(OBSERVED))
        assert all(np.array_equal(ours[v], built_in[v]) for v in OBSERVED)


def test_build_one_fmu_refuses_a_system_with_python_only_components_in_one_line(fmu_dir, tmp_path, capsys):
    """A built-in system and an SSP file of the plant with a component that has no native model (every built-in
    system's components are native; the benchmark's trivial ones, built with --bench, are not): one line, exit 2,
    nothing written."""
    from crane_fmu import components
    from crane_fmu.build_scripts.native import ported
    from crane_fmu.cosim import System
    from crane_fmu.cosim.ssp import write_ssp

    other = next((c.model_identifier for c in components.registered() if c.model_identifier not in ported()), None)
    if other is None:
        pytest.skip("every component is native")
    ssp = write_ssp(System("mixed", {"plant": str(fmu_dir / "CranePlant.fmu"), "other": str(fmu_dir / f"{other}.fmu")}),
                    fmu_dir, tmp_path / "mixed.ssp")
    assert main(["build", "--out", str(tmp_path / "fmus"), "--one-fmu", "paper", str(ssp)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "has no native model" in err and other in err
    assert not (tmp_path / "native").exists()  # nothing written: every system is checked first


def test_build_writes_the_built_in_one_fmus_whose_components_are_native_and_notes_the_others(build_record, native):
    """The run's one ``crane-fmu build`` (the session's build, conftest.py): the one-FMU of each system tagged
    one-fmu whose components are all native, FMI 2.0 and 3.0, and a note naming each of the others."""
    code, printed = build_record
    tagged = systems.tagged("one-fmu")
    ones = {one_fmu_name(name) for name in tagged}
    written = sorted(Path(line).relative_to(native[2].parent) for line in printed
                     if Path(line).parent in (native[2], native[3]) and Path(line).stem in ones)
    assert written == sorted(Path(folder) / f"{one_fmu_name(name)}.fmu" for name in SYSTEMS
                             for folder in ("native", "native/fmi3"))
    assert all((native[2].parent / path).is_file() for path in written)
    notes = [line for line in printed if line.startswith("note:")]
    others = [name for name in tagged if name not in SYSTEMS]
    assert [note.split()[1] for note in notes] == [one_fmu_name(name) for name in others]
    assert all("has no native model yet" in note for note in notes)
