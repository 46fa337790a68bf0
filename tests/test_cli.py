"""The crane-fmu command line, run in-process through main(argv)."""

import math

import numpy as np
import pytest

from crane_fmu.cli import main
from crane_fmu.cosim import read_csv


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_build_writes_every_component_and_every_builtin_system(tmp_path, capsys):
    code, out, _ = _run(capsys, "build", "--out", str(tmp_path / "fmus"))
    assert code == 0
    fmus = ["BacksteppingController.fmu", "CranePlant.fmu", "CraneSensor.fmu", "EnergyController.fmu", "Gust.fmu",
            "HardHitController.fmu", "LqrController.fmu", "Sensor.fmu", "StateEstimator.fmu", "TrajectoryPlanner.fmu"]
    names = ["energy", "free", "hard-hit", "hoist-transport", "lqg", "lqg-transport", "lqr", "paper", "transport"]
    assert sorted(p.name for p in (tmp_path / "fmus").iterdir()) == sorted(
        fmus + [f"{n}.OspSystemStructure.xml" for n in names])
    assert sorted(p.name for p in (tmp_path / "fmi3").iterdir()) == fmus
    assert sorted(p.name for p in (tmp_path / "systems").iterdir()) == sorted(f"{n}.ssp" for n in names)
    assert sorted(p.name for p in (tmp_path / "containers").iterdir()) == [
        "CraneEnergy.fmu", "CraneLqr.fmu", "CranePaper.fmu", "CraneTransport.fmu"]


def test_simulate_writes_csv_and_plot(fmu_dir, tmp_path, capsys):
    csv, png = tmp_path / "run.csv", tmp_path / "run.png"
    code, out, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "1", "--step", "0.01",
                          "--out", str(csv), "--plot", str(png))
    assert (code, err) == (0, "")
    data = read_csv(csv)
    assert list(data)[:3] == ["time", "plant.x", "plant.dx"] and "controller.u" in data
    assert len(data["time"]) == 101 and data["time"][-1] == 1.0
    assert data["plant.theta1"][0] == pytest.approx(math.pi / 18, rel=1e-15)
    assert png.stat().st_size > 10_000
    assert not list(tmp_path.glob("*.partial*"))


def test_simulate_free_swing_and_settings(fmu_dir, tmp_path, capsys):
    csv = tmp_path / "free.csv"
    code, _, _ = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--system", "free", "--stop-time", "0.5",
                      "--step", "0.05", "--set", "plant.theta1_0=0.2", "--set", "plant.l2=0.25",
                      "--master", "jacobi", "--out", str(csv))
    assert code == 0
    data = read_csv(csv)
    assert "controller.u" not in data
    assert data["plant.theta1"][0] == 0.2
    assert data["plant.y2"][0] == pytest.approx(-math.cos(0.2) - 0.25, rel=1e-15)


@pytest.mark.parametrize("argv, message", [
    (["--set", "crane.l1=1"], "unknown instance 'crane'; instances: plant, controller"),
    (["--system", "nowhere"], "no system 'nowhere'; systems: paper, free, lqr, energy, transport, hoist-transport, "
                              "lqg, lqg-transport, hard-hit"),
    (["--system", "free", "--set", "controller.l1=1"], "unknown instance 'controller'; instances: plant"),
    (["--set", "plant.l3=1"], "plant has no parameter or input 'l3'; valid: m1, m2, l1"),
    (["--set", "plant.x=1"], "plant has no parameter or input 'x'"),
    (["--set", "plant.l1=abc"], "'abc' is not a number"),
    (["--set", "plant.l1"], "expected INSTANCE.VARIABLE=VALUE"),
    (["--set", "plant.l1=-1"], "plant: l1 must be > 0 and finite, got -1.0"),
    (["--set", "controller.w_theta2=nan"], "'nan' is not a finite number"),
    (["--set", "controller.b3_form=guessed"], "b3_form must be one of derived, printed, got 'guessed'"),
    (["--set", "plant.max_substep=0"], "max_substep must be > 0 and finite, got 0.0"),
    (["--step", "0.003"], "step 0.003 must divide the interval 20.0 into whole steps"),
    (["--step", "0"], "step must be > 0, got 0.0"),
    (["--stop-time", "-1"], "stop time must be > start time 0.0, got -1.0"),
    (["--step", "x"], "argument --step: 'x' is not a number"),
    (["--master", "euler"], "argument --master: invalid choice: 'euler'"),
])
def test_simulate_user_errors_give_one_line_and_status_2(fmu_dir, tmp_path, capsys, argv, message):
    out_file = tmp_path / "keep.csv"
    out_file.write_text("previous result\n")
    code, out, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--out", str(out_file), *argv)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("crane-fmu: error: ") and message in err
    assert out_file.read_text() == "previous result\n"  # nothing the user had is lost


def test_missing_fmus_and_unwritable_output(tmp_path, fmu_dir, capsys):
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(tmp_path / "nowhere"))
    assert code == 2 and "CranePlant.fmu not found: build the FMUs first (crane-fmu build)" in err
    code, _, err = _run(capsys, "simulate", "--system", str(tmp_path / "nowhere.ssp"))
    assert code == 2 and "nowhere.ssp not found" in err
    blocker = tmp_path / "file"
    blocker.write_text("")
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--out", str(blocker / "r.csv"))
    assert code == 2 and "cannot create folder" in err


def test_fmu_failure_keeps_results_and_exits_1(fmu_dir, tmp_path, capsys):
    """The paper's law at h = 10 ms diverges; the plant discards the step where its state overflows."""
    csv = tmp_path / "diverged.csv"
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--step", "0.01", "--out", str(csv))
    assert code == 1
    assert err.count("\n") == 1 and "plant: fmi2DoStep returned discard at t=" in err
    lines = csv.read_text().splitlines()
    assert lines[-1].startswith("# run cut short: plant: fmi2DoStep returned discard")
    data = read_csv(csv)
    assert 0 < data["time"][-1] < 20 and all(math.isfinite(v) for v in data["plant.x"])


def test_info_lists_every_variable_with_units(capsys):
    code, out, _ = _run(capsys, "info")
    assert code == 0
    assert "theta1_0" in out and "rad (display deg)" in out and "BacksteppingController.fmu" in out
    assert "  paper      plant = CranePlant, controller = BacksteppingController" in out
    assert "  free       plant = CranePlant:" in out
    code, out, _ = _run(capsys, "info", "--markdown")
    assert "| `K2_theta2` | parameter | 310 | 1/s |" in out


@pytest.mark.parametrize("command", ["build", "simulate", "info", "reproduce", "sweep", "bench"])
def test_help_shows_examples(capsys, command):
    with pytest.raises(SystemExit) as exit_:
        main([command, "--help"])
    assert exit_.value.code == 0
    assert "examples:" in capsys.readouterr().out


def test_unknown_command_is_one_line(capsys):
    code, _, err = _run(capsys, "fly")
    assert code == 2 and err.count("\n") == 1


def test_unreadable_fmu_is_one_line(tmp_path, fmu_dir, capsys):
    for name in ("CranePlant.fmu", "BacksteppingController.fmu"):
        (tmp_path / name).write_bytes(b"not a zip file")
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(tmp_path), "--out", str(tmp_path / "r.csv"))
    assert code == 2 and err.count("\n") == 1
    assert "CranePlant.fmu is not a readable FMU" in err


@pytest.mark.parametrize("argv, expect", [
    (["bench", "--stop-time", "0.2", "--repeat", "1"], "4. whole processes: crane-fmu simulate"),
    (["bench", "--endurance", "--stop-time", "2"], "resident memory:"),
    (["bench", "--sweep", "--cases", "2", "--stop-time", "0.2"], "parallel efficiency on 2 workers:"),
])
def test_benchmarks_run_and_print_their_figures(capsys, argv, expect):
    """A smoke test only: the figures themselves are measured with crane-fmu bench, not asserted here."""
    assert main(argv) == 0
    assert expect in capsys.readouterr().out


def test_targets_measures_every_controller_against_its_targets(fmu_dir, capsys):
    """A smoke test of the command: the targets themselves are guarded by test_controllers.py."""
    assert main(["targets", "--quick", "--fmu-dir", str(fmu_dir), "--workers", "2"]) == 0
    assert "Region of attraction, energy: converges from every theta1(0)" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["--out", "{tmp}/"], "is a folder; give a file name"),
    (["--out", "{tmp}/section5.png"], "writes a .csv file; the name must end in .csv"),
    (["--plot", "{tmp}/section5.csv"], "writes a .png file; the name must end in .png"),
    (["--out", "/proc/x.csv"], "--out /proc/x.csv: cannot be written"),
    (["--set", "plant.l1=2deg"], "'2deg': a deg value needs a variable in rad, this one is in m"),
])
def test_output_mistakes_are_refused_before_running(fmu_dir, tmp_path, capsys, argv, message):
    argv = [a.format(tmp=tmp_path) for a in argv]
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), *argv)
    assert code == 2 and err.count("\n") == 1 and message in err and ".partial" not in err
    assert not list(tmp_path.iterdir())  # nothing written, nothing left behind


def test_angles_in_degrees_and_a_warning_for_radians_that_look_like_degrees(fmu_dir, tmp_path, capsys):
    common = ["simulate", "--fmu-dir", str(fmu_dir), "--system", "free", "--stop-time", "0.01", "--step", "0.01"]
    code, _, err = _run(capsys, *common, "--set", "plant.theta1_0=10deg", "--out", str(tmp_path / "deg.csv"))
    assert code == 0 and err == "" and read_csv(tmp_path / "deg.csv")["plant.theta1"][0] == math.radians(10)
    code, _, err = _run(capsys, *common, "--set", "plant.theta1_0=10", "--out", str(tmp_path / "rad.csv"))
    assert code == 0 and "warning: plant.theta1_0 = 10 rad (573 deg); for degrees write 10deg" in err


def test_version_and_time_column(fmu_dir, tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.startswith("crane-fmu 0.")
    _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "0.03", "--out", str(tmp_path / "t.csv"))
    times = [line.split(",")[0] for line in (tmp_path / "t.csv").read_text().splitlines()[1:]]
    assert times[:4] == ["0", "0.001", "0.002", "0.003"]  # the shortest text that reads back exactly


def test_simulate_writes_parquet_with_the_csv_numbers(fmu_dir, tmp_path, capsys):
    """--out FILE.parquet (pyarrow) holds exactly the CSV's columns and values."""
    pytest.importorskip("pyarrow")
    from crane_fmu.cosim import read_result

    for name in ("run.csv", "run.parquet"):
        assert main(["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "2", "--out", str(tmp_path / name)]) == 0
    csv, parquet = read_result(tmp_path / "run.csv"), read_result(tmp_path / "run.parquet")
    assert list(csv) == list(parquet) and len(csv["time"]) == 2001
    for column in csv:
        assert np.array_equal(csv[column], parquet[column]), column
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--out", str(tmp_path / "run.txt")]) == 2
    assert "--out " + str(tmp_path / "run.txt") + ": writes a .csv file" in capsys.readouterr().err


def test_the_iterative_jacobi_master_is_a_choice_and_settles_like_gauss_seidel(fmu_dir, tmp_path, capsys):
    """Selectable by --master; on the paper's loop (no algebraic loop) its fixed point is Gauss-Seidel's
    exchange, so the CSV is the same byte for byte, while plain Jacobi (u one step late) differs."""
    common = ["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "0.5"]
    for master in ("gauss-seidel", "iterative-jacobi", "jacobi"):
        assert main(common + ["--master", master, "--out", str(tmp_path / f"{master}.csv")]) == 0
    assert (tmp_path / "iterative-jacobi.csv").read_bytes() == (tmp_path / "gauss-seidel.csv").read_bytes()
    assert (tmp_path / "jacobi.csv").read_bytes() != (tmp_path / "gauss-seidel.csv").read_bytes()
