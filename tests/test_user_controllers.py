"""A controller designer's FMU in a system's place, from the user's side (`simulate --use`, `compare`).

- Every connection the system was designed with keeps both ends in the FMUs used: a controller whose
  output is misnamed, or a plant without the input u, is one line naming the instance, the variable
  and the FMU, exit 2, and nothing is written (no silently open loop).
- An FMU whose role does not fit its place (a plant as the controller) is refused the same way.
- One rule for what a controller is told (crane_fmu.controller_interface.told), in simulate and compare:
  the planner's references, else the move's target as x_d, else refused with that reason.
"""

from pathlib import Path

import numpy as np
import pytest
import user_controllers

from crane_fmu import components, systems
from crane_fmu.analysis import planar_scenarios as planar
from crane_fmu.analysis import scenarios
from crane_fmu.build_scripts.build_fmus import build_fmu
from crane_fmu.cli import main
from crane_fmu.compare import contenders
from crane_fmu.controller_interface import told
from crane_fmu.cosim import ArrayRecorder, read_csv, run

CRANE = components.get("CranePlant").crane


@pytest.fixture(scope="module")
def user_fmus(tmp_path_factory):
    """``{model identifier: path}``: the test controllers as FMI 2.0 FMUs, never registered.

    Built with pythonfmu's own binary (the quickest build): these FMUs are refused before any is loaded.
    """
    out = tmp_path_factory.mktemp("mine")
    return {c.model_identifier: build_fmu(c, out) for c in (user_controllers.PD_TYPO, user_controllers.PD_REGULATOR)}


def _simulate(capsys, fmu_dir, tmp_path, system, use, *more):
    code = main(["simulate", "--system", system, "--fmu-dir", str(fmu_dir), "--use", use,
                 "--out", str(tmp_path / "run.csv"), *more])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("system, use, message", [
    # the held examples: a misnamed output, the plant in the controller's place
    ("lqr", "controller={PdTypo}", "controller: {PdTypo} has no output u, which the system connects to plant.u"),
    ("lqr", "controller={fmu_dir}/CranePlant.fmu",
     "controller: {fmu_dir}/CranePlant.fmu is a plant (CranePlant), where the system has a controller "
     "(LqrController)"),
    ("transport", "planner={fmu_dir}/LqrController.fmu", "where the system has a planner (TrajectoryPlanner)"),
    ("transport", "plant={PdRegulator}", "plant: {PdRegulator} has no input u, which the system feeds from "
                                          "controller.u"),
    ("transport", "controller={PdRegulator}",
     "controller ({PdRegulator}) cannot be told where the load goes (2 m): it misses a parameter x_d or the "
     "inputs x_ref, dx_ref, ddx_ref"),
])
def test_a_replaced_fmu_that_breaks_the_loop_is_one_line(fmu_dir, user_fmus, tmp_path, capsys, system, use,
                                                          message):
    names = {"fmu_dir": fmu_dir, **user_fmus}
    code, err = _simulate(capsys, fmu_dir, tmp_path, system, use.format(**names))
    assert code == 2 and err.count("\n") == 1 and message.format(**names) in err, err
    assert not (tmp_path / "run.csv").exists()


def test_the_check_reads_the_design_of_a_system_file(fmu_dir, user_fmus, tmp_path, capsys):
    """An SSP file's connections are written out: a replacement must still feed the plant's u."""
    ssp = fmu_dir.parent / "systems" / "lqr.ssp"
    code, err = _simulate(capsys, fmu_dir, tmp_path, str(ssp), f"controller={user_fmus['PdTypo']}")
    assert code == 2 and err.count("\n") == 1 and "has no output u, which the system connects to plant.u" in err


def test_compare_refuses_what_simulate_refuses(fmu_dir, user_fmus, tmp_path, capsys):
    """A controller without u is refused; one that cannot be told a move is refused the moves (it is scored on the
    scenarios that hold the crane where it is: test_compare.py), here every scenario asked for."""
    for fmu, message, chosen in (
            (user_fmus["PdTypo"], "PdTypo is not a crane controller: of CranePlant, it misses output u", "S1,S2"),
            (user_fmus["PdRegulator"], "PdRegulator: no scenario of S2, S3 applies to it: n/a (needs x_d or x_ref); "
                                       "it can run S1, S6", "S2,S3")):
        assert main(["compare", "--controller", str(fmu), "--only", "--quick", "--fmu-dir", str(fmu_dir),
                     "--scenario", chosen, "--out", str(tmp_path / "board")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "board").exists()


def test_one_rule_for_what_a_controller_is_told():
    measured, plant, move = list(CRANE.state), components.get("CranePlant"), {"x": 2.0}
    tracker = told("T", measured + ["x_ref", "dx_ref", "ddx_ref", "theta1_ref"], ["u"], ["x_d"], plant, move)
    assert tracker.references == ("x_ref", "dx_ref", "ddx_ref", "theta1_ref") and tracker.targets == {}
    assert told("R", measured, ["u"], ["x_d"], plant, move) == ((), {"x_d": 2.0})  # no references: x_d
    assert told("R", measured, ["u"], ["x_d"], plant) == ((), {})  # regulation: nothing but the state
    assert told("N", measured, ["u"], [], plant) == ((), {})  # regulation needs no target
    with pytest.raises(ValueError, match=r"^N cannot be told where the load goes \(2 m\): it misses a parameter x_d"):
        told("N", measured, ["u"], [], plant, move)
    with pytest.raises(ValueError, match=r"^H is not a controller of CranePlant: it misses dtheta2, output u "):
        told("H", measured[:5], ["acc"], ["x_d"], plant)


def test_simulate_and_compare_give_a_controller_without_references_the_same_move(fmu_dir, tmp_path, capsys):
    """The energy law has x_d and no reference inputs: in `transport` it is told the planner's target, as
    the scoreboard's S2 tells it; on the scoreboard's plant (its drive limits set) both runs are the same."""
    mine = tmp_path / "mine" / "EnergyController.fmu"
    mine.parent.mkdir()
    mine.write_bytes((fmu_dir / "EnergyController.fmu").read_bytes())  # a user's file, not the built-in name
    stop = 3.0
    code, err = _simulate(capsys, fmu_dir, tmp_path, "transport", f"controller={mine}", "--stop-time", str(stop),
                          *[f"--set=plant.{k}={v}" for k, v in planar.DRIVE.items()])
    assert code == 0, err
    assert "it is told the move's target, controller.x_d = 2 m (planner.x_d)" in err
    simulated = read_csv(tmp_path / "run.csv")
    contender, = contenders([str(mine)], fmu_dir, only=True)
    (_, system, step, *_), = scenarios.systems_for(contender, "S2")
    assert system.parameters["controller"]["x_d"] == systems.get("transport").parameters["planner"]["x_d"]
    scored = run(systems.prepare(system, step), fmu_dir, recorder=ArrayRecorder(), stop_time=stop).columns()
    assert simulated["plant.x"][-1] > 0.2  # moving towards 2 m (untold, it would stay at 0)
    np.testing.assert_array_equal(simulated["plant.x"], scored["plant.x"])
    np.testing.assert_array_equal(simulated["plant.theta1"], scored["plant.theta1"])


@pytest.mark.parametrize("system", ["lqr3d-move", "lqr3d-path"])
def test_a_3d_controller_without_references_is_told_each_axiss_target(fmu_dir, tmp_path, capsys, system):
    """The crane in three dimensions as the planar one: a controller with the targets x_d and y_d and no reference
    inputs (a user's copy of the MPC in 3-D) in a system that moves the load gets x_d from the x axis's planner and
    y_d from the y axis's (a one-axis planner: its own x_d), and takes the load there. On main it was refused ("cannot
    be told where the load goes"), the message naming only planner.x_d."""
    native = fmu_dir.parent / "native"
    mine = tmp_path / "mine" / "MpcController3D.fmu"
    mine.parent.mkdir()
    mine.write_bytes((native / "MpcController3D.fmu").read_bytes())
    x_d, y_d = 1.5, 0.75
    code, err = _simulate(capsys, native, tmp_path, system, f"controller={mine}", "--set", f"planner.x_d={x_d}",
                          "--set", f"planner_y.x_d={y_d}", "--stop-time", "8")
    assert code == 0, err
    assert (f"it is told the move's target, controller.x_d = {x_d:g} m (planner.x_d), controller.y_d = {y_d:g} m "
            "(planner_y.x_d)") in err, err
    run = read_csv(tmp_path / "run.csv")
    assert abs(run["plant.x"][-1] - x_d) < 0.01 and abs(run["plant.y"][-1] - y_d) < 0.01


def test_a_controller_is_told_the_target_as_set_and_its_own_value_wins(fmu_dir, tmp_path, capsys):
    """`--set planner.x_d=1.5` moves the load to 1.5 m with a controller told the target (the MPC's copy in
    `transport`), as it does the LQR that tracks the planner; on main it was told the system's 2 m and took the load
    there. A value the user gives the controller itself (`--set controller.x_d=1.2`) is the one it runs with."""
    native = fmu_dir.parent / "native"
    mine = tmp_path / "mine" / "MpcController.fmu"
    mine.parent.mkdir()
    mine.write_bytes((native / "MpcController.fmu").read_bytes())
    for sets, where in [(["--set", "planner.x_d=1.5"], 1.5),
                        (["--set", "planner.x_d=1.5", "--set", "controller.x_d=1.2"], 1.2)]:
        code, err = _simulate(capsys, native, tmp_path, "transport", f"controller={mine}", "--stop-time", "6", *sets)
        assert code == 0 and "controller.x_d = 1.5 m (planner.x_d)" in err, err
        assert abs(read_csv(tmp_path / "run.csv")["plant.x"][-1] - where) < 0.01, sets


@pytest.mark.parametrize("kind, controller", [("python", "EnergyController"), ("native", "MpcController")])
def test_a_study_of_the_planners_target_tells_each_case_its_target(fmu_dir, tmp_path, capsys, dask_scheduler, kind,
                                                                   controller):
    """A study of `planner.x_d` with a controller told the target (`use`, no reference inputs): each case's controller
    is told the case's target, and its figures are simulate's with `--set planner.x_d` (the per-case path and the
    native batch path). On main every case was told the system's 2 m: the same figures for every target."""
    pytest.importorskip("distributed")
    import pyarrow.parquet as pq

    folder = fmu_dir if kind == "python" else fmu_dir.parent / "native"
    mine = tmp_path / "mine" / f"{controller}.fmu"
    mine.parent.mkdir()
    mine.write_bytes((folder / f"{controller}.fmu").read_bytes())
    study = tmp_path / "targets.toml"
    study.write_text(f'system = "transport"\nstop_time = 3.0\nstep = 0.001\nmetrics = ["trolley_final_m"]\n'
                     f'[parameters]\n"planner.x_d" = [1.0, 1.5]\n[use]\ncontroller = "{mine}"\n')
    assert main(["sweep", str(study), "--out", str(tmp_path / "study"), "--fmu-dir", str(folder), "--scheduler",
                 dask_scheduler, "--no-progress"]) == 0
    rows = pq.read_table(tmp_path / "study" / "results.parquet").to_pydict()
    for x_d, final in zip(rows["planner.x_d"], rows["trolley_final_m"]):
        code, err = _simulate(capsys, folder, tmp_path, "transport", f"controller={mine}", "--stop-time", "3",
                              "--set", f"planner.x_d={x_d}")
        assert code == 0 and read_csv(tmp_path / "run.csv")["plant.x"][-1] == final, (x_d, final)
    assert rows["trolley_final_m"][0] != rows["trolley_final_m"][1]


def test_the_built_in_controllers_fit_every_built_in_system(fmu_dir):
    """The rule refuses none of the built-in systems: each controller is told what the system gives it."""
    for system in systems.registered():
        told_system, notes = systems.tell_controllers(system, fmu_dir)
        assert told_system.parameters == system.parameters and notes == [], system.name


def test_the_plot_of_a_use_run_names_the_fmu_in_its_title(fmu_dir, tmp_path, capsys, monkeypatch):
    from crane_fmu.analysis import plots

    titles = []
    monkeypatch.setattr(plots, "plot_run", lambda result, path, title: (titles.append(title),
                                                                         Path(path).write_bytes(b"png")))
    code, err = _simulate(capsys, fmu_dir, tmp_path, "lqr", f"controller={fmu_dir / 'EnergyController.fmu'}",
                          "--stop-time", "0.1", "--plot", str(tmp_path / "run.png"))
    assert code == 0, err
    assert titles == ["lqr with controller=EnergyController.fmu (gauss-seidel, h=0.001 s)"]
