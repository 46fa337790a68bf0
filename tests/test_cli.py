"""The crane-fmu command line, run in-process through main(argv)."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from crane_fmu.cli import main
from crane_fmu.cosim import read_csv


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_build_writes_every_component_and_every_builtin_system(build_record, fmu_dir):
    """The run's one ``crane-fmu build --bench`` (it made ``fmu_dir``): every component's FMU, FMI 2.0 and 3.0,
    every built-in system's SSP and OSP files, the containers; each file it wrote printed once, and nothing else."""
    code, printed = build_record
    assert code == 0
    build = fmu_dir.parent
    fmus = ["BacksteppingController.fmu", "CranePlant.fmu", "CranePlant3D.fmu", "CraneSensor.fmu",
            "EnergyController.fmu", "Gust.fmu", "HardHitController.fmu", "LqrController.fmu", "LqrController3D.fmu",
            "MpcController.fmu", "MpcController3D.fmu", "Sensor.fmu", "StateEstimator.fmu", "TrajectoryPlanner.fmu",
            "TrivialController.fmu", "TrivialPlant.fmu", "Wind.fmu"]
    names = ["energy", "free", "hard-hit", "hoist-transport", "lqg", "lqg-transport", "lqr", "lqr3d", "lqr3d-move",
             "lqr3d-path", "mpc", "mpc-transport", "mpc3d", "mpc3d-move", "mpc3d-path", "open-loop-3d", "paper",
             "transport"]
    assert sorted(p.name for p in (build / "fmus").iterdir()) == sorted(
        fmus + [f"{n}.OspSystemStructure.xml" for n in names])
    assert sorted(p.name for p in (build / "fmi3").iterdir()) == fmus
    assert sorted(p.name for p in (build / "systems").iterdir()) == sorted(f"{n}.ssp" for n in names)
    assert sorted(p.name for p in (build / "containers").iterdir()) == [
        "CraneEnergy.fmu", "CraneLqr.fmu", "CranePaper.fmu", "CraneTransport.fmu"]
    written = sorted(p for p in build.rglob("*") if p.is_file() and p.parent != build)
    *files, summary = [line for line in printed if not line.startswith(("note:", "warning:"))]
    assert sorted(map(Path, files)) == written
    assert summary == f"{len(written)} made, 0 up to date in {build}"


@pytest.mark.quick
def test_build_leaves_out_the_benchmarks_trivial_fmus_unless_asked(tmp_path, monkeypatch, capsys):
    """Which components ``crane-fmu build`` builds (the build itself is checked once, above)."""
    from crane_fmu import components
    from crane_fmu.build_scripts import build_fmus

    asked = []
    def build_all(out, kinds, **_):
        asked.append(list(kinds))
        return build_fmus.Built([])

    monkeypatch.setattr(build_fmus, "build_all", build_all)
    assert main(["build", "--out", str(tmp_path / "fmus")]) == 0
    assert main(["build", "--bench", "--out", str(tmp_path / "fmus")]) == 0
    every = [c.model_identifier for c in components.registered()]
    assert sorted(asked[1]) == sorted(every)
    assert sorted(asked[0]) == sorted(set(every) - {"TrivialPlant", "TrivialController"})
    assert not list(tmp_path.iterdir())


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
                      "--algorithm", "jacobi", "--out", str(csv))
    assert code == 0
    data = read_csv(csv)
    assert "controller.u" not in data
    assert data["plant.theta1"][0] == 0.2
    assert data["plant.y2"][0] == pytest.approx(-math.cos(0.2) - 0.25, rel=1e-15)


@pytest.mark.parametrize("argv, message", [
    (["--set", "crane.x0=1"], "crane has no parameter or input 'x0'; valid: m1, m2, l1, l2, g"),
    (["--set", "plnat.l1=1"], "unknown instance 'plnat'; instances: plant, controller, crane"),
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
    (["--algorithm", "euler"], "argument --algorithm: invalid choice: 'euler'"),
    (["--parameters", "my.ssv"], "--parameters my.ssv: not found (an SSP parameter set, e.g. "
                                 "examples/parameters.ssv)"),
])
def test_simulate_user_errors_give_one_line_and_status_2(fmu_dir, tmp_path, capsys, argv, message):
    out_file = tmp_path / "keep.csv"
    out_file.write_text("previous result\n")
    code, out, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--out", str(out_file), *argv)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("crane-fmu: error: ") and message in err
    assert out_file.read_text() == "previous result\n"  # nothing the user had is lost


def test_a_limit_set_to_inf_is_no_limit_as_1e60_is(fmu_dir, tmp_path, capsys):
    """The drive's u_max is documented as "1e60 or INF: no limit": --set takes INF, and the run is 1e60's, bit for
    bit (limits.py); a length set to INF is refused by the plant's own rule, in one line."""
    runs = {}
    for text in ("INF", "1e60"):
        out = tmp_path / f"{text}.csv"
        code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr", "--stop-time", "0.5",
                            "--set", f"plant.u_max={text}", "--set", "controller.u_max=INF", "--out", str(out))
        assert code == 0, err
        runs[text] = out.read_text()
    assert runs["INF"] == runs["1e60"]
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr", "--set", "plant.l1=INF",
                        "--out", str(tmp_path / "no.csv"))
    assert code == 2 and err == "crane-fmu: error: plant: l1 must be > 0 and finite, got inf\n"


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
    """The paper's law at h = 10 ms diverges; the plant discards the step where its state overflows.

    The rows up to there go beside the result under a clear name; an earlier good result is left as it was
    (issue 29: a failed run turned a 20,002-row file into 7 rows)."""
    csv = tmp_path / "diverged.csv"
    good = "time,plant.x\n0,0\n"
    csv.write_text(good)
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--step", "0.01", "--out", str(csv))
    assert code == 1
    assert err.count("\n") == 1 and "plant: fmi2DoStep returned discard at t=" in err
    cut = tmp_path / "diverged.cut-short.csv"
    assert f"in {cut}; {csv} is as it was)" in err
    assert csv.read_text() == good  # the earlier result, untouched
    lines = cut.read_text().splitlines()
    assert lines[-1].startswith("# run cut short: plant: fmi2DoStep returned discard")
    data = read_csv(cut)
    assert 0 < data["time"][-1] < 20 and all(math.isfinite(v) for v in data["plant.x"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["diverged.csv", "diverged.cut-short.csv"]


def test_an_input_made_non_finite_during_the_run_is_a_failed_run_naming_its_source(fmu_dir, tmp_path, capsys):
    """A controller (a law file) that gives u = nan once the trolley moves: the plant refuses the input during the run.
    That is a run that failed (status 1, the rows so far kept and named, the input's source named), not a mistake in
    the arguments (status 2, as a refused parameter is; it was before). A law that fails at t = 0 leaves no rows: the
    line says so (it said "in None")."""
    law = tmp_path / "nan_law.py"
    law.write_text("def law(config, state, inputs):\n    return (float('nan') if inputs[0] > 0.01 else 0.5,)\n")
    csv = tmp_path / "run.csv"
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr", "--use",
                        f"controller={law}:law", "--out", str(csv))
    cut = tmp_path / "run.cut-short.csv"
    assert code == 1 and err.count("\n") == 1, err
    assert "plant: fmi2SetReal returned error at t=" in err and "input u must be finite, got nan" in err, err
    assert "(plant.u is controller.u) (results up to t=" in err and f"in {cut}; {csv} is not written)" in err, err
    assert read_csv(cut)["time"][-1] > 0
    law.write_text("def law(config, state, inputs):\n    return 1 / 0\n")
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr", "--use",
                        f"controller={law}:law", "--out", str(csv))
    assert code == 1 and "(no results: it failed at t=0 s; " in err and "None" not in err, err


def test_ctrl_c_in_simulate_is_one_line_and_keeps_the_rows_so_far(fmu_dir, tmp_path, capsys, monkeypatch):
    """Ctrl-C during a run: one line naming where the rows went, status 130; the earlier result untouched."""
    import crane_fmu.cosim.master

    csv = tmp_path / "run.csv"
    csv.write_text("an earlier result\n")
    advance = crane_fmu.cosim.master.Master.advance

    def interrupted(self, start_time, step, first, last, observers=()):
        advance(self, start_time, step, first, min(last, first + 50), observers)
        raise KeyboardInterrupt

    monkeypatch.setattr(crane_fmu.cosim.master.Master, "advance", interrupted)
    code, out, err = _run(capsys, "simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "1", "--out", str(csv))
    cut = tmp_path / "run.cut-short.csv"
    assert (code, out, err) == (130, "", f"crane-fmu: interrupted (SIGINT); the rows so far are in {cut}\n")
    assert csv.read_text() == "an earlier result\n"
    assert cut.read_text().splitlines()[-1] == "# run cut short: interrupted (SIGINT)"
    assert len(read_csv(cut)["time"]) > 1


@pytest.mark.quick
def test_ctrl_c_anywhere_else_is_one_line(capsys, monkeypatch):
    import crane_fmu.commands.info

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(crane_fmu.commands.info, "run", interrupted)
    assert _run(capsys, "info") == (130, "", "crane-fmu: interrupted\n")


@pytest.mark.quick
def test_bare_command_lists_the_commands(capsys):
    code, out, err = _run(capsys)
    assert code == 2 and out == ""
    from crane_fmu.commands import COMMANDS

    assert err.startswith("usage: crane-fmu") and all(f"    {c.NAME} " in err or f"    {c.NAME}\n" in err
                                                       for c in COMMANDS)


def test_simulate_writes_a_mat_file_with_the_csv_columns(fmu_dir, tmp_path, capsys):
    """--out FILE.mat (scipy.io.savemat) for MATLAB: the CSV's column names and values, and a struct per instance."""
    import scipy.io

    from crane_fmu.cosim import read_result

    for name in ("run.csv", "run.mat"):
        assert main(["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "0.5", "--out", str(tmp_path / name)]) == 0
    csv, mat = read_result(tmp_path / "run.csv"), read_result(tmp_path / "run.mat")
    assert list(csv) == list(mat) and len(mat["time"]) == 501
    for column in csv:
        assert np.array_equal(csv[column], mat[column]), column
    content = scipy.io.loadmat(tmp_path / "run.mat")
    assert np.array_equal(content["plant"]["theta1"][0, 0].ravel(), csv["plant.theta1"])
    assert np.array_equal(content["time"].ravel(), csv["time"])


def test_use_swaps_one_instances_fmu(fmu_dir, tmp_path, capsys):
    """--use controller=FILE.fmu runs another FMU as that instance; the system's values it lacks are noted."""
    energy = tmp_path / "mine" / "EnergyController.fmu"
    energy.parent.mkdir()
    energy.write_bytes((fmu_dir / "EnergyController.fmu").read_bytes())
    common = ["simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr", "--stop-time", "0.2"]
    assert main(common + ["--use", f"controller={energy}", "--out", str(tmp_path / "swap.csv")]) == 0
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", "energy", "--stop-time", "0.2",
                 "--out", str(tmp_path / "energy.csv")]) == 0
    capsys.readouterr()
    assert (tmp_path / "swap.csv").read_bytes() == (tmp_path / "energy.csv").read_bytes()
    for item, message in [("controller", "expected INSTANCE=FILE.fmu"),
                          (f"crane={energy}", "system lqr has no instance 'crane'; instances: plant, controller"),
                          (f"controller={tmp_path / 'nowhere.fmu'}", "nowhere.fmu not found"),
                          (f"controller={tmp_path / 'swap.csv'}",
                           "is neither an FMU file (.fmu) nor a law file (.py, .py:NAME)")]:
        code, _, err = _run(capsys, *common, "--use", item, "--out", str(tmp_path / "x.csv"))
        assert code == 2 and err.count("\n") == 1 and message in err, err
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.quick
def test_progress_line_only_on_a_terminal(tmp_path):
    """The progress observer writes t of the stop time on one line; simulate adds it only when stderr is a tty."""
    import io

    from crane_fmu.cosim import ProgressLine

    stream = io.StringIO()
    line = ProgressLine(0.0, 10.0, stream, interval=0.0, check_every=2)
    for k in range(5):
        line.observe(k * 1.0, None)
    line.close()
    assert stream.getvalue() == "\rt = 1 of 10 s (10 %)\rt = 3 of 10 s (30 %)\n"


def test_simulate_shows_progress_on_a_terminal_and_not_in_a_pipe(fmu_dir, tmp_path):
    """A run under a pseudo-terminal gets the line on stderr; with stderr a pipe nothing but the result line."""
    import os
    import pty
    import subprocess
    import sys

    # long enough to pass the line's first second (about 2.5 s of stepping at 1 ms)
    command = [sys.executable, "-m", "crane_fmu", "simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr",
               "--stop-time", "150", "--out", str(tmp_path / "long.parquet")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    leader, follower = pty.openpty()
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=follower, timeout=300)
    os.close(follower)
    try:
        shown = os.read(leader, 100_000).decode()
    except OSError:  # EIO: the terminal is closed and nothing was written
        shown = ""
    os.close(leader)
    assert done.returncode == 0 and "\rt = " in shown and " of 150 s (" in shown, shown


@pytest.mark.quick
def test_info_lists_every_variable_with_units(capsys):
    code, out, _ = _run(capsys, "info")
    assert code == 0
    assert "theta1_0" in out and "rad (display deg)" in out and "BacksteppingController.fmu" in out
    assert "  paper      plant = CranePlant, controller = BacksteppingController" in out
    assert "  free       plant = CranePlant:" in out
    code, out, _ = _run(capsys, "info", "--markdown")
    assert "| `K2_theta2` | parameter | 310 | 1/s |" in out


@pytest.mark.quick
@pytest.mark.parametrize("command", ["build", "simulate", "info", "reproduce", "sweep", "bench", "serve"])
def test_help_shows_examples(capsys, command):
    with pytest.raises(SystemExit) as exit_:
        main([command, "--help"])
    assert exit_.value.code == 0
    assert "examples:" in capsys.readouterr().out


@pytest.mark.quick
def test_unknown_command_is_one_line(capsys):
    code, _, err = _run(capsys, "fly")
    assert code == 2 and err.count("\n") == 1


@pytest.mark.quick
@pytest.mark.parametrize("argv, flags", [
    (["bench", "--sweep", "--mpc"], ("--sweep", "--mpc")),
    (["bench", "--native", "--derivatives"], ("--native", "--derivatives")),
    (["build", "--container", "transport", "--one-fmu", "lqr"], ("--container", "--one-fmu")),
])
def test_two_exclusive_choices_are_one_line_naming_both(capsys, argv, flags):
    """Separate benchmarks (builds) are refused together before anything runs: one line naming both flags."""
    code, out, err = _run(capsys, *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and all(flag in err for flag in flags), err


def test_unreadable_fmu_is_one_line(tmp_path, fmu_dir, capsys):
    for name in ("CranePlant.fmu", "BacksteppingController.fmu"):
        (tmp_path / name).write_bytes(b"not a zip file")
    code, _, err = _run(capsys, "simulate", "--fmu-dir", str(tmp_path), "--out", str(tmp_path / "r.csv"))
    assert code == 2 and err.count("\n") == 1
    assert "CranePlant.fmu is not a readable FMU" in err


NUMBER = r"(\d+(?:\.\d+)?)"


@pytest.mark.parametrize("argv, figures", [
    (["bench", "--stop-time", "0.2", "--repeat", "1"],  # 200 steps
     [rf"CSV of every step: +{NUMBER} us/step", rf"plain Python loop, same CSV: +{NUMBER} us/step",
      rf"bare ctypes loop: +{NUMBER} us/step", rf"crane-fmu simulate {NUMBER} s", rf"anchor {NUMBER} s: ratio"]),
    (["bench", "--endurance", "--stop-time", "0.5"], [rf"resident memory: {NUMBER} MB at t = 0"]),
    (["bench", "--sweep", "--cases", "2", "--stop-time", "0.2", "--repeat", "1"],
     [rf"1 worker: +{NUMBER} cases/s", rf"2 workers: {NUMBER} cases/s", rf"efficiency on 2 workers: {NUMBER} %"]),
    (["bench", "--spatial", "--stop-time", "0.2", "--repeat", "1"],
     [rf"(?m)^1\. LQR pair, the LqrController on x +python +{NUMBER} vs",
      rf"(?m)^2\. planned pair, .* = {NUMBER}x native", rf"(?m)^3\. open-loop-3d .* native +{NUMBER} vs",
      rf"(?m)^3\. open-loop-3d .* = {NUMBER}x$", rf"ratio {NUMBER}$"]),
], ids=["pair", "endurance", "sweep", "spatial"])
def test_benchmarks_run_and_print_their_figures(capsys, argv, figures):
    """Each benchmark at a few hundred steps prints each of its figures, and each is a positive number. The figures
    themselves are measured with crane-fmu bench at full length, not asserted here."""
    assert main(argv) == 0
    out = capsys.readouterr().out
    for figure in figures:
        found = re.search(figure, out)
        assert found and float(found.group(1)) > 0, (figure, out)


def test_targets_measures_every_controller_against_its_targets(native, capsys):
    """A smoke test of the command: the targets themselves are guarded by test_controllers.py (on the Python FMUs;
    here the native ones, which test_native_board.py and test_native_mpc.py hold to them)."""
    assert main(["targets", "--quick", "--fmu-dir", str(native[2]), "--workers", "2"]) == 0
    out = capsys.readouterr().out
    assert "Region of attraction, energy (30 s runs): converges or is decaying from every theta1(0)" in out
    # the words agree (issue 29): the law whose region of attraction is every angle tried is not called a
    # sustained oscillation in its own 10-degree regulation run
    energy = next(line for line in out.splitlines() if line.startswith("  energy   0.5 deg from"))
    assert energy.endswith(("converges", "decaying")), energy
    # the floors with their method, and the MPC's figures against its targets as ratios to them
    assert "  S2: 2.70 s  2 m from rest to rest" in out and "LP feasibility (scipy HiGHS)" in out
    s2 = next(line for line in out.splitlines() if line.startswith("  S2: arrival (5 mm, 0.5 deg): "))
    assert "x floor) (target <= 2.95 s, ambition 2.85 s): " in s2, s2


@pytest.mark.parametrize("argv, message", [
    (["--out", "{tmp}/"], "is a folder; give a file name"),
    (["--out", "{tmp}/section5.png"],
     "writes a .csv, .parquet or .mat file; the name must end in .csv, .parquet or .mat"),
    (["--out", "{tmp}/sub/x.xlsx"], "the name must end in .csv, .parquet or .mat"),
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
    assert "--out " + str(tmp_path / "run.txt") + ": writes a .csv, .parquet or .mat file" in capsys.readouterr().err


def test_the_iterative_jacobi_master_is_a_choice_and_settles_like_gauss_seidel(fmu_dir, tmp_path, capsys):
    """Selectable by --algorithm; on the paper's loop (no algebraic loop) its fixed point is Gauss-Seidel's
    exchange, so the CSV is the same byte for byte, while plain Jacobi (u one step late) differs."""
    common = ["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "0.5"]
    for master in ("gauss-seidel", "iterative-jacobi", "jacobi"):
        assert main(common + ["--algorithm", master, "--out", str(tmp_path / f"{master}.csv")]) == 0
    assert (tmp_path / "iterative-jacobi.csv").read_bytes() == (tmp_path / "gauss-seidel.csv").read_bytes()
    assert (tmp_path / "jacobi.csv").read_bytes() != (tmp_path / "gauss-seidel.csv").read_bytes()


def test_plot_draws_only_what_the_results_hold(fmu_dir, tmp_path, monkeypatch, capsys):
    """No flat "demanded u" line for a result without u (fmpy's output of the plant); with the paper's law
    and the LQR together each u stays readable (symlog beside +-800 m/s2) and each run's peak |u| is named."""
    import crane_fmu.analysis.plots as plots
    from crane_fmu.cosim import write_csv

    drawn = []
    overlay = plots.plot_overlay
    monkeypatch.setattr(plots, "plot_overlay", lambda *a, **k: drawn.append(overlay(*a, **k)))
    free = read_csv(_simulated(fmu_dir, tmp_path, "free", "2"))
    write_csv(tmp_path / "fmpy.csv", {k.removeprefix("plant."): v for k, v in free.items()})  # fmpy's names
    assert main(["plot", str(tmp_path / "fmpy.csv"), "--out", str(tmp_path / "free.png")]) == 0
    assert [label for label, _ in drawn[-1]["panels"]] == ["trolley position x [m]",
                                                          "hook swing angle theta1 [deg]",
                                                          "payload swing angle theta2 [deg]"]
    paper, lqr = _simulated(fmu_dir, tmp_path, "paper", "4"), _simulated(fmu_dir, tmp_path, "lqr", "4")
    assert main(["plot", str(paper), str(lqr), "--out", str(tmp_path / "s5.png")]) == 0
    panels, legend = drawn[-1]["panels"], drawn[-1]["legend"]
    assert panels[3][1] == "symlog" and panels[3][0].startswith("demanded u [m/s2]")
    assert re.fullmatch(r"paper \(peak \|u\| \d{3} m/s2\)", legend[0]) and legend[1] == "lqr (peak |u| 2 m/s2)"
    assert drawn[-1]["title"] == "paper vs lqr"
    assert (tmp_path / "s5.png").stat().st_size > 10_000


def _simulated(fmu_dir, tmp_path, system, stop_time):
    path = tmp_path / f"{system}.csv"
    assert main(["simulate", "--fmu-dir", str(fmu_dir), "--system", system, "--stop-time", stop_time,
                 "--out", str(path)]) == 0
    return path


@pytest.mark.quick
@pytest.mark.parametrize("argv", [["compare", "--quick", "--out", "{tmp}/board"], ["sweep", "study.toml", "--out",
                                                                                  "{tmp}/study"]])
def test_sweep_and_compare_without_dask_are_one_line_and_write_nothing(argv, tmp_path, capsys, monkeypatch):
    """The quick start installs only the plot extra: a command that needs Dask says so before writing anything."""
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "distributed" else real(name, *a))
    code, _, err = _run(capsys, *[a.format(tmp=tmp_path) for a in argv])
    assert code == 2 and err.count("\n") == 1 and "runs its cases on Dask, which is not installed" in err
    assert list(tmp_path.iterdir()) == []
