"""crane-fmu compare: a user's controller FMU (built from examples/) scored next to the built-in ones on Dask."""

import math
import re
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from crane_fmu import systems
from crane_fmu.analysis import scoreboard
from crane_fmu.cli import main
from crane_fmu.compare import compare
from crane_fmu.cosim import ArrayRecorder, read_csv, run

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def template_fmu(tmp_path_factory):
    """examples/my_controller built with pythonfmu alone, as its README recipe does."""
    from pythonfmu import FmuBuilder

    out = tmp_path_factory.mktemp("mine")
    return FmuBuilder.build_FMU(ROOT / "examples" / "my_controller" / "my_controller.py", dest=out)


@pytest.fixture(scope="module")
def quick_board(template_fmu, fmu_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    log = []
    rows = compare(out, [str(template_fmu), "LqrController"], fmu_dir, workers=2, quick=True, progress=False,
                   animate=(), log=log.append)
    return out, rows, log


def test_every_controller_scenario_and_case_is_a_row(quick_board):
    out, rows, log = quick_board
    table = pq.read_table(out / "scores.parquet").to_pylist()
    cases_per_controller = {"S1": 1, "S2": 1, "S3": 3, "S4": 1, "S5": 1, "S6": 3, "S7": 1}
    for name in ("MyController", "LqrController"):
        mine = [r for r in table if r["controller"] == name]
        assert {s: sum(r["scenario"] == s for r in mine) for s in cases_per_controller} == cases_per_controller
    # 2 controllers x the 11 cases above; the one not ok is MyController's S6 at h = 50 ms (see the next test)
    assert log[-1].startswith("22 cases: 22 run now, 0 already done, 1 not ok")
    for name in ("scoreboard.md", "S1.png", "S2.png", "S7.png", "summary.png"):
        assert (out / name).stat().st_size > 1000


def test_a_controller_that_fails_in_one_case_is_scored_failed_there_only(quick_board):
    """Which case fails follows from the template's own rule, not from today's output: MyController discards
    every step longer than its max_step = 0.02 s, and of all the quick suite's cases only S6's h = 50 ms
    step is longer (S6 runs at 1, 10 and 50 ms; every other scenario at 1 ms)."""
    out, rows, _ = quick_board
    failed = [r for r in rows if r["status"] != "ok"]
    assert [(r["controller"], r["scenario"], r["case"]) for r in failed] == [("MyController", "S6", "h=50ms")]
    assert "controller: fmi2DoStep returned discard at t=0 s" in failed[0]["error"]
    board = (out / "scoreboard.md").read_text()
    assert "**failed** in 1 of 3: controller: fmi2DoStep returned discard" in board
    s2 = board.split("## S2")[1].split("## S3")[0]
    assert s2.index("`LqrController`") < s2.index("`MyController`")  # ranked by arrival


def test_the_harness_runs_the_same_system_as_simulate(quick_board, fmu_dir):
    """S2 for the LQR is the built-in transport system on the drive-limited plant: the same figures.

    The expected figures are computed here from the recorded run, by their definitions, without
    crane_fmu.analysis.metrics (which the harness uses): the arrival is the first sample from which on the
    trolley stays within 5 mm of x_d = 2 m and both angles within 0.5 deg; the residual is the largest swing
    of either angle from the later of the arrival and the planned move's end.
    """
    _, rows, _ = quick_board
    row = next(r for r in rows if r["controller"] == "LqrController" and r["scenario"] == "S2")
    system = systems.get("transport").with_parameters({"plant": {"u_max": 2.0, "v_max": 1.0}})
    c = run(system, fmu_dir, recorder=ArrayRecorder()).columns()
    from crane_fmu.model import planner

    end = planner.setup({**planner.COMPONENT.defaults(), "x_d": 2.0}).end
    t, theta1, theta2 = c["time"], c["plant.theta1"], c["plant.theta2"]
    half_degree = math.radians(0.5)
    inside = (np.abs(c["plant.x"] - 2.0) <= 0.005) & (np.abs(theta1) <= half_degree) & (np.abs(theta2) <= half_degree)
    assert inside[-1]
    arrival = t[np.nonzero(~inside)[0][-1] + 1]
    after = t >= max(arrival, end)
    residual = math.degrees(max(np.abs(theta1[after]).max(), np.abs(theta2[after]).max()))
    assert row["arrival_s"] == arrival and row["residual_deg"] == pytest.approx(residual, rel=1e-12)


def test_a_rerun_resumes(quick_board, template_fmu, fmu_dir):
    out, rows, _ = quick_board
    log = []
    again = compare(out, [str(template_fmu), "LqrController"], fmu_dir, workers=2, quick=True, progress=False,
                    animate=(), log=log.append)
    assert log[-1].startswith("22 cases: 0 run now, 22 already done")
    assert [r["case_id"] for r in again] == [r["case_id"] for r in rows]


@pytest.mark.parametrize("argv, message", [
    (["--controller", "Nothing"], "no controller 'Nothing'; controllers: BacksteppingController, LqrController"),
    (["--controller", "{fmu_dir}/CranePlant.fmu"], "CranePlant is not a crane controller: it misses x, dx, theta1, "
                                                  "dtheta1, theta2, dtheta2, output u"),
    (["--workers", "0"], "--workers must be >= 1"),
])
def test_compare_mistakes_are_one_line(fmu_dir, tmp_path, capsys, argv, message):
    argv = [a.format(fmu_dir=fmu_dir) for a in argv]
    assert main(["compare", "--out", str(tmp_path / "o"), "--fmu-dir", str(fmu_dir), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_animate_a_simulate_result(fmu_dir, tmp_path, capsys):
    from PIL import Image

    csv = tmp_path / "move.csv"
    assert main(["simulate", "--system", "transport", "--fmu-dir", str(fmu_dir), "--stop-time", "1",
                 "--out", str(csv)]) == 0
    assert main(["animate", str(csv), "--out", str(tmp_path / "move.gif"), "--fps", "10"]) == 0
    gif = Image.open(tmp_path / "move.gif")
    assert gif.n_frames == 11 and gif.size[0] > 300
    assert main(["animate", str(csv), "--out", str(tmp_path / "move.txt")]) == 2
    free = {k: v for k, v in read_csv(csv).items() if k in ("time", "controller.u")}
    from crane_fmu.cosim import write_csv

    write_csv(tmp_path / "no_crane.csv", free)
    assert main(["animate", str(tmp_path / "no_crane.csv"), "--out", str(tmp_path / "x.gif")]) == 2
    assert "has no crane to animate: it needs the plant outputs x, x1, y1, x2, y2" in capsys.readouterr().err


def test_readme_shows_the_current_scoreboard(fmu_dir, tmp_path):
    """Doc-sync only: the full suite of every built-in controller, run now, gives the README's table.

    The table's figures are this code's output (regenerate with ``crane-fmu compare``); the behaviour
    behind them is held by requirement tests: the LQR's targets (test_controllers.py), the documented
    LQR design against scipy, and the metrics' known answers (test_metrics.py)."""
    rows = compare(tmp_path, (), fmu_dir, workers=2, progress=False, animate=(), log=lambda _: None)
    readme = (ROOT / "README.md").read_text()
    section = re.search(r"<!-- scoreboard:start -->\n(.*)\n<!-- scoreboard:end -->", readme, re.S).group(1)
    assert section.strip() == scoreboard.render_summary(rows)


def test_only_fmus_that_run_python_here_are_called_holding_the_gil(template_fmu, crane_fmus):
    """Ours say so (crane_fmu_runs_in_host_python); a stock pythonfmu FMU is called as fmpy loads it."""
    import ctypes

    from crane_fmu.cosim import open_instance

    ours, stock = open_instance(crane_fmus["plant"], "plant"), open_instance(template_fmu, "mine")
    try:
        assert isinstance(ours._library, ctypes.PyDLL)
        assert not isinstance(stock._library, ctypes.PyDLL)
    finally:
        ours.free()
        stock.free()
