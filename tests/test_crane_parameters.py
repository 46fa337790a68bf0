"""The crane's parameters, set once (crane_fmu/crane_parameters.py): ``crane.l2`` sets ``l2`` on every instance that
models the crane, unless the instance has its own value.

The reference each run is held to is written independently of the rule under test: ``l2`` set on every instance
whose FMU *has* a parameter ``l2`` (read from the built modelDescription files), as a user did before. Same values,
same FMUs, same master: the bits must be equal, on the Python and the native FMUs, multi-FMU and one-FMU.
"""

import dataclasses
import json
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from third_party_hosts import (
    OMSIMULATOR,
    SAME,
    omsimulator_log_problems,
    read_oms_mat,
    run_tool,
    tool,
    worst_difference,
)

from crane_fmu import crane_parameters, systems
from crane_fmu.build_scripts.build_fmus import systems_dir
from crane_fmu.build_scripts.native import native_dir
from crane_fmu.build_scripts.one_fmu import not_native, one_fmu_name, plan
from crane_fmu.cli import main
from crane_fmu.cosim import System, run
from crane_fmu.cosim.ssp import load_system
from crane_fmu.sweep.runner import case_parameters

SYSTEMS = [s.name for s in systems.registered()]
ONE_FMU = [name for name in systems.tagged("one-fmu") if not not_native(systems.get(name))]
SHORT = 0.3  # s: long enough for a 0.6 m payload cable to move every output (checked: "it acts")
L2 = 0.6


def _native(fmu_dir):
    folder = native_dir(fmu_dir)
    if not (folder / "CranePlant.fmu").exists():
        pytest.skip("no native FMUs were built (no C compiler)")
    return folder


def _every_l2(system, folder):
    """``{instance: {"l2": L2}}`` for every instance whose FMU has a parameter ``l2``: the reference."""
    return {name: {"l2": L2} for name, path in system.fmus(folder).items()
            if any(v.name == "l2" and v.causality == "parameter"
                   for v in read_model_description(str(path)).modelVariables)}


def _short(system):
    return dataclasses.replace(system, stop_time=SHORT)


def _run(system, folder, values):
    prepared = systems.prepare(_short(system), values=[values])
    return prepared, run(prepared, folder).columns()


# ---- the rule, without FMUs --------------------------------------------------------------------------------------

@pytest.mark.quick
def test_the_rule_is_by_component_not_by_instance_name_and_an_own_value_overrides():
    """Instances named anything; the wind models only l1, l2; a gust and a sensor nothing; an own value wins."""
    system = System("odd", {"crane_body": "CranePlant", "brain": "LqrController", "gusty": "Gust", "eye": "CraneSensor",
                            "air": "Wind", "mind": "StateEstimator"},
                    parameters={"brain": {"l2": 0.5}})
    prepared = systems.prepare(system, values=[{"crane": {"l2": L2, "m1": 4.0}}])
    assert prepared.parameters["crane_body"]["l2"] == prepared.parameters["air"]["l2"] == L2
    assert prepared.parameters["mind"]["l2"] == L2 and prepared.parameters["brain"]["l2"] == 0.5  # its own
    assert prepared.parameters["mind"]["m1"] == prepared.parameters["brain"]["m1"] == 4.0
    assert "m1" not in prepared.parameters.get("air", {})  # the wind has no masses
    assert not {"l2", "m1"} & set(prepared.parameters.get("gusty", {})) | set(prepared.parameters.get("eye", {}))
    assert "crane" not in prepared.parameters  # bound: what the master gets names instances only
    # a later --set of the instance's own value overrides a crane value given with it, whatever the order
    later = systems.prepare(system, values=[{"crane": {"l1": 2.0}}, {"crane_body": {"l1": 1.5}}])
    earlier = systems.prepare(system, values=[{"crane_body": {"l1": 1.5}}, {"crane": {"l1": 2.0}}])
    assert later.parameters == earlier.parameters and later.parameters["crane_body"]["l1"] == 1.5
    assert later.parameters["brain"]["l1"] == later.parameters["mind"]["l1"] == 2.0


@pytest.mark.quick
def test_an_unregistered_fmu_models_the_crane_by_its_parameters_of_those_names():
    models = crane_parameters.modelled({"p": "CranePlant", "mine": "MyOwnLaw"},
                                       lambda name: {"mine": ("l2", "gain", "g")}[name])
    assert models == {"p": ("m1", "m2", "l1", "l2", "g"), "mine": ("l2", "g")}


@pytest.mark.quick
def test_crane_is_a_reserved_instance_name():
    system = System("clash", {"crane": "CranePlant", "controller": "LqrController"})
    for call in (lambda: systems.prepare(system), lambda: systems.resolve(system, "nowhere")):
        with pytest.raises(ValueError) as error:
            call()
        assert str(error.value).startswith("system clash: an instance may not be called 'crane'")
        assert "\n" not in str(error.value)


@pytest.mark.quick
def test_a_name_that_is_no_crane_parameter_is_refused_in_one_line(capsys):
    with pytest.raises(ValueError, match=r"^crane\.x0: the crane's parameters are m1, m2, l1, l2, g$"):
        crane_parameters.with_values(systems.get("lqr"), {"crane": {"x0": 1.0}})
    assert main(["info", "--system", "lqr", "--set", "crane.L2=0.6"]) == 2
    assert capsys.readouterr().err.strip() == ("crane-fmu: error: --set 'crane.L2=0.6': crane has no parameter or "
                                               "input 'L2'; valid: m1, m2, l1, l2, g; did you mean 'l2'?")


@pytest.mark.quick
def test_hoist_transport_sets_the_cranes_l1_once_and_its_planners_keep_their_own():
    """The plant's and the controller's 2 m cable is the crane's; the planner's 1.5 m design value and the hoist's
    1 m stay theirs. Prepared, every instance has the values it had before they were the crane's."""
    system = systems.get("hoist-transport")
    assert system.parameters["crane"] == {"l1": 2.0}
    assert "l1" not in system.parameters["plant"] and "l1" not in system.parameters["controller"]
    prepared = systems.prepare(system).parameters
    assert [prepared[i]["l1"] for i in ("plant", "controller", "planner", "hoist")] == [2.0, 2.0, 1.5, 1.0]
    moved = systems.prepare(system, values=[{"crane": {"l1": 1.8}}]).parameters
    assert [moved[i]["l1"] for i in ("plant", "controller", "planner", "hoist")] == [1.8, 1.8, 1.5, 1.0]


@pytest.mark.quick
def test_info_lists_each_crane_parameter_its_value_unit_and_the_instances_it_sets(capsys):
    assert main(["info", "--system", "hoist-transport", "--set", "crane.l2=0.6"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "    crane.m1 = 3 kg: plant, planner, hoist, controller" in lines
    assert "    crane.l1 = 2 m (set): plant, controller; own values: planner = 1.5, hoist = 1" in lines
    assert "    crane.l2 = 0.6 m (set): plant, planner, hoist, controller" in lines
    assert "    crane.g = 9.8 m/s2: plant, planner, hoist, controller" in lines
    assert main(["info", "--system", "lqg"]) == 0
    assert "    crane.l2 = 0.5 m: plant, controller, estimator" in capsys.readouterr().out.splitlines()
    assert main(["info"]) == 0
    assert "  crane.l2  [m] cable length hook to payload" in capsys.readouterr().out.splitlines()


@pytest.mark.parametrize("name", ["hoist-transport", "lqg", "mpc-transport", "lqr3d-move"])
def test_info_reads_an_ssp_file_as_the_system_it_was_written_from(fmu_dir, name, capsys):
    """`info --system FILE.ssp`: the crane's parameters, the instances they set and what the components derive (the
    planner's Enumeration, held in the file as its item's value) are the built-in system's."""
    def lines(system):
        assert main(["info", "--system", str(system)]) == 0
        return [line.replace(" (set)", "") for line in capsys.readouterr().out.splitlines()[1:]]  # the file sets all

    ours = lines(systems_dir(fmu_dir) / f"{name}.ssp")
    assert ours == lines(name)
    assert any(line.startswith("    crane.l2 = 0.5 m: plant") for line in ours)


@pytest.mark.quick
def test_a_studys_crane_value_sets_the_bound_instances_that_the_case_gives_none_of_their_own():
    binding = {"l2": ["plant", "controller", "estimator"]}
    base = {"plant": {"theta1_0": 0.1}, "controller": {"h": 0.001}}
    assert case_parameters({"crane.l2": L2, "controller.l2": 0.5}, base, binding) == {
        "plant": {"theta1_0": 0.1, "l2": L2}, "controller": {"h": 0.001, "l2": 0.5}, "estimator": {"l2": L2}}
    assert case_parameters({"plant.l1": 1.5}, base, binding) == {"plant": {"theta1_0": 0.1, "l1": 1.5},
                                                                  "controller": {"h": 0.001}}


# ---- the bits: every built-in system, Python and native, multi-FMU and one-FMU ----------------------------------

@pytest.mark.parametrize("kind", ["python", "native"])
def test_crane_l2_gives_the_bits_of_l2_set_on_every_instance_that_has_one(fmu_dir, kind):
    folder = fmu_dir if kind == "python" else _native(fmu_dir)
    for name in SYSTEMS:
        system = systems.get(name)
        if kind == "native" and not_native(system):
            continue
        reference = _every_l2(system, folder)
        assert "plant" in reference, name
        ours, columns = _run(system, folder, {"crane": {"l2": L2}})
        theirs, expected = _run(system, folder, reference)
        assert ours.parameters == theirs.parameters, name
        assert list(columns) == list(expected), name
        for column, values in expected.items():
            assert np.array_equal(columns[column], values), (name, column)
        plain = run(systems.prepare(_short(system)), folder).columns()
        swing = "plant." + systems.plant_of(system).crane.swing[-1]  # the load cable's: theta2, swing2
        assert not np.array_equal(plain[swing], columns[swing]), name  # it acts


def test_through_the_command_line_crane_l2_is_l2_set_on_every_instance(fmu_dir, tmp_path):
    common = ["simulate", "--system", "lqg-transport", "--fmu-dir", str(fmu_dir), "--stop-time", str(SHORT)]
    assert main(common + ["--set", "crane.l2=0.6", "--out", str(tmp_path / "crane.csv")]) == 0
    every = [f"--set={i}.l2=0.6" for i in _every_l2(systems.get("lqg-transport"), fmu_dir)]
    assert len(every) == 4  # plant, planner, controller, estimator
    assert main(common + every + ["--out", str(tmp_path / "every.csv")]) == 0
    assert (tmp_path / "crane.csv").read_bytes() == (tmp_path / "every.csv").read_bytes()
    # a controller told another crane: its own value overrides the crane's
    told_out = str(tmp_path / "told.csv")
    assert main(common + ["--set", "crane.l2=0.6", "--set", "controller.l2=0.5", "--out", told_out]) == 0
    told = [item for item in every if not item.startswith("--set=controller.")] + ["--set=controller.l2=0.5"]
    assert main(common + told + ["--out", str(tmp_path / "told-every.csv")]) == 0
    assert (tmp_path / "told.csv").read_bytes() == (tmp_path / "told-every.csv").read_bytes()
    assert (tmp_path / "told.csv").read_bytes() != (tmp_path / "crane.csv").read_bytes()


@pytest.mark.parametrize("version", [2, 3])
def test_the_one_fmus_l2_is_our_masters_crane_l2(fmu_dir, version):
    """The one-FMU's parameter l2 (the crane's, derived from the same rule) set to 0.6: our master's run of
    ``crane.l2 = 0.6`` over the native components, every output bit for bit."""
    folder = _native(fmu_dir)
    for name in ONE_FMU:
        system = _short(systems.get(name))
        ours = run(systems.prepare(system, values=[{"crane": {"l2": L2}}]), folder).columns()
        path = (folder if version == 2 else folder / "fmi3") / f"{one_fmu_name(name)}.fmu"
        outputs = [v.name for v in plan(system).variables if v.causality == "output"]
        theirs = simulate_fmu(str(path), stop_time=SHORT, step_size=system.step, output_interval=system.step,
                              start_values={"l2": L2}, output=outputs)
        links = plan(system).links
        for own in outputs:
            assert np.array_equal(theirs[own], ours["{}.{}".format(*links[own][0])]), (name, own)


# ---- SSP files: written, read back, run in OMSimulator and libcosim ---------------------------------------------

def _with_system_level_l2(ssp, out, value):
    """A copy of an SSP package whose system-level ``crane.l2`` is ``value``; the components' own sets unchanged."""
    with zipfile.ZipFile(ssp) as source, zipfile.ZipFile(out, "w") as target:
        for item in source.namelist():
            data = source.read(item)
            if item == "SystemStructure.ssd":
                text, count = re.subn(r'(<ssv:Parameter name="crane\.l2">\s*<ssv:Real value=")[^"]*"',
                                      rf'\g<1>{value!r}"', data.decode())
                assert count == 1
                data = text.encode()
            target.writestr(item, data)
    return out


def test_the_ssp_files_carry_the_cranes_parameters_and_our_reader_reads_them_back(fmu_dir, tmp_path):
    for name in ("lqr", "hoist-transport"):
        original = systems.get(name)
        with load_system(systems_dir(fmu_dir) / f"{name}.ssp") as loaded:
            crane = crane_parameters.values(loaded)
            assert crane == {**{"m1": 3.0, "m2": 7.0, "l1": 1.0, "l2": 0.5, "g": 9.8}, **original.parameters.get(
                "crane", {})}
            assert (crane_parameters.bound(loaded, systems.modelled(loaded))
                    == crane_parameters.bound(original, systems.modelled(original)))
            for values in ({}, {"crane": {"l2": L2}}):
                prepared = systems.prepare(loaded, values=[values]).parameters
                expected = systems.prepare(original, values=[values]).parameters
                for instance, own in expected.items():
                    assert {k: prepared[instance][k] for k in own} == own, (name, instance)
    edited = _with_system_level_l2(systems_dir(fmu_dir) / "lqr.ssp", tmp_path / "lqr.ssp", L2)
    with load_system(edited) as loaded:
        prepared = systems.prepare(loaded).parameters
    assert prepared["plant"]["l2"] == prepared["controller"]["l2"] == L2  # the system's value, not the components'


def test_omsimulator_applies_an_ssp_files_system_level_crane_l2_as_our_master_does(fmu_dir, tmp_path):
    """Only the system-level ``crane.l2`` of the built file changed (the components' own sets keep 0.5):
    OMSimulator's run is our master's ``--set crane.l2=0.6``, and not the run with 0.5."""
    for name in ("lqr", "hoist-transport"):
        ssp = _with_system_level_l2(systems_dir(fmu_dir) / f"{name}.ssp", tmp_path / f"{name}.ssp", L2)
        out = tmp_path / f"{name}.mat"
        code, log = run_tool([tool(OMSIMULATOR), f"--tempDir={tmp_path / 'oms'}", "--stopTime=1.0",
                              f"--resultFile={out}", ssp], tmp_path)
        assert code == 0, log[-3000:]
        assert omsimulator_log_problems(log) == [], log[-3000:]  # the planners' shapers applied: Enumerations
        system = systems.get(name)
        prefix = re.sub(r"\W", "_", name)
        theirs = read_oms_mat(out, system.step)
        for value, near in ((L2, True), (0.5, False)):
            ours = run(systems.prepare(system, values=[{"crane": {"l2": value}}]), fmu_dir, stop_time=1.0).columns()
            pairs = [(f"{prefix}.{prefix}.{column}", column) for column in ours if column != "time"]
            assert (worst_difference(theirs, ours, pairs) <= SAME) == near, (name, value)


LIBCOSIM = Path(__file__).parent / "libcosim_run.py"


def test_libcosim_applies_the_one_value_written_into_each_component(fmu_dir, tmp_path):
    """libcosim reads the components' own sets only (its parser skips the system's bindings): a file written with
    ``crane.l2 = 0.6`` runs there as our (Jacobi) master's ``--set crane.l2=0.6``; the file edited at the system's
    level alone runs with the components' 0.5 (what the interoperability page says)."""
    pytest.importorskip("libcosimpy")
    system = crane_parameters.with_values(systems.get("lqr"), {"crane": {"l2": L2}})
    written = systems.write_ssp(system, fmu_dir, tmp_path / "lqr.ssp")
    edited = _with_system_level_l2(systems_dir(fmu_dir) / "lqr.ssp", tmp_path / "edited.ssp", L2)
    for path, value in ((written, L2), (edited, 0.5)):
        proc = subprocess.run([sys.executable, str(LIBCOSIM), "ssp", str(path), "1000"], capture_output=True,
                              text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr[-2000:]
        theirs = json.loads(proc.stdout.strip().splitlines()[-1])
        ours = run(systems.prepare(systems.get("lqr"), values=[{"crane": {"l2": value}}]), fmu_dir,
                   algorithm="jacobi", stop_time=1.0).columns()
        for signal in ("x", "theta1", "theta2"):
            times, values = np.array(theirs[signal][0]), np.array(theirs[signal][1])
            index = np.rint(times / 1e-3).astype(int)
            assert len(times) > 900 and np.abs(values - ours[f"plant.{signal}"][index]).max() < 1e-12, (value, signal)
