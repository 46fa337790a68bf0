"""An input that nothing feeds is read as its start value through the whole run: every command that runs a system
warns of each (one line, naming the nearest output), and refuses under --strict; no built-in system warns."""

from pathlib import Path

import pytest

from crane_fmu import compare, systems
from crane_fmu.cli import main
from crane_fmu.cosim import Connection
from crane_fmu.cosim.connections import UNCONNECTED, unfed
from crane_fmu.cosim.system import unfed_inputs
from crane_fmu.sweep import spec

ROOT = Path(__file__).resolve().parent.parent
# examples/my_controller with one more input, its name a typo of the plant's l1_now
TYPO = (ROOT / "examples" / "my_controller" / "my_controller.py").read_text().replace(
    'MEASURED = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")',
    'MEASURED = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2", "l1_nw")').replace(
    "self.x = self.dx = self.theta1", "self.l1_nw = 1.5\n        self.x = self.dx = self.theta1").replace(
    "class MyController", "class TypoController")
WARNING = ("crane-fmu: warning: input controller.l1_nw is fed by nothing: it stays at its start value 1.5 (the "
           "nearest output: plant.l1_now)")


@pytest.mark.quick
def test_every_unfed_input_is_found_with_the_nearest_output_and_a_marked_or_given_one_is_not():
    inputs = {"plant": {"u": "demand", "F1": f"a force; {UNCONNECTED}0, none"},
              "ctl": {"x": "", "thta1": "measured", "gain": "", "zzz": ""}}
    outputs = {"plant": ["x", "theta1", "dtheta1"], "ctl": ["u"]}
    found = unfed(inputs, outputs, [Connection("plant", "x", "ctl", "x")], given=[("ctl", "gain")])
    assert found == [("plant", "u", "ctl.u"), ("ctl", "thta1", "plant.theta1"), ("ctl", "zzz", None)]


@pytest.fixture(scope="module")
def typo_fmu(tmp_path_factory):
    from pythonfmu import FmuBuilder

    folder = tmp_path_factory.mktemp("typo")
    (folder / "typo_controller.py").write_text(TYPO)
    return FmuBuilder.build_FMU(folder / "typo_controller.py", dest=folder)


def test_no_built_in_system_contender_or_study_warns(fmu_dir):
    """Every input a built-in system leaves unfed says so in its description (the plant's hoist and forces, the
    LQR's references) or is given a value (the free swing's u = 0)."""
    for system in systems.registered():
        fmus, connections = systems.resolve(system, fmu_dir)
        assert unfed_inputs(fmus, connections, system.parameters) == [], system.name
    assert compare.unfed(compare.contenders((), fmu_dir), fmu_dir) == []
    for name in ("hard-hits", "region-of-attraction", "theta2-gain-sensitivity"):
        with systems.open_system(spec.load(f"builtin:{name}").system) as system:
            assert unfed_inputs(*systems.resolve(system, fmu_dir), system.parameters) == [], name


def test_simulate_warns_of_a_misspelt_input_and_refuses_it_under_strict(fmu_dir, typo_fmu, tmp_path, capsys):
    out = tmp_path / "run.csv"
    argv = ["simulate", "--fmu-dir", str(fmu_dir), "--system", "hoist-transport", "--stop-time", "0.05", "--use",
            f"controller={typo_fmu}", "--out", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err.splitlines()
    assert [line for line in err if "warning" in line] == [WARNING]
    out.write_text("kept\n")
    assert main(argv + ["--strict"]) == 2
    err = capsys.readouterr().err
    assert err.endswith("crane-fmu: error: --strict: input controller.l1_nw is fed by nothing: it stays at its start "
                        "value 1.5 (the nearest output: plant.l1_now); connect each, or give it a value with --set\n")
    assert "warning" not in err and out.read_text() == "kept\n"
    assert main(argv + ["--strict", "--set", "controller.l1_nw=2"]) == 0  # a value given on purpose: no warning
    assert "warning" not in capsys.readouterr().err


def test_compare_and_sweep_refuse_it_under_strict_before_anything_runs(fmu_dir, typo_fmu, tmp_path, capsys):
    board = tmp_path / "board"
    assert main(["compare", "--fmu-dir", str(fmu_dir), "--controller", str(typo_fmu), "--only", "--quick",
                 "--scenario", "S1,S7", "--out", str(board), "--strict"]) == 2
    err = capsys.readouterr().err
    assert err == ("crane-fmu: error: --strict: TypoController: input controller.l1_nw is fed by nothing: it stays at "
                   "its start value 1.5 (the nearest output: plant.l1_now) (in S1, S7)\n")
    assert not board.exists()
    chosen = compare.contenders([str(typo_fmu)], fmu_dir, only=True)
    assert compare.unfed(chosen, fmu_dir, ["S1"]) == [WARNING.replace("crane-fmu: warning: ", "TypoController: ")
                                                      + " (in S1)"]
    shapes = {}  # the board's way: from the runs plan() made, the lines of the runs made again, in every scenario
    compare.plan(chosen, fmu_dir, cases=2, shapes=shapes)
    assert compare.unfed(chosen, fmu_dir, shapes=shapes) == compare.unfed(chosen, fmu_dir) != []
    ssp = systems.write_ssp(systems.get("paper").with_instances({"controller": str(typo_fmu)}), fmu_dir,
                            tmp_path / "typo.ssp")
    study = tmp_path / "study.toml"
    study.write_text(f'system = "{ssp}"\nstop_time = 0.1\nstep = 0.01\n[parameters]\n"plant.l2" = [0.5, 0.6]\n')
    assert main(["sweep", str(study), "--fmu-dir", str(fmu_dir), "--out", str(tmp_path / "sweep"), "--strict"]) == 2
    assert "error: --strict: input controller.l1_nw is fed by nothing" in capsys.readouterr().err
    assert not (tmp_path / "sweep").exists()
