"""crane-fmu compare: a user's controller FMU (built from examples/) scored next to the built-in ones on Dask."""

import math
import re
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from once import made_once

from crane_fmu import components, systems
from crane_fmu.analysis import board_tables, ranking, scenarios
from crane_fmu.analysis import planar_scenarios as planar
from crane_fmu.cli import main
from crane_fmu.compare import check, compare, contenders
from crane_fmu.cosim import ArrayRecorder, read_csv, run
from crane_fmu.sweep.runner import JOURNAL

ROOT = Path(__file__).resolve().parent.parent


# The boards are made once per run (once.made_once); the tests that add to a board run in this module's order, on one
# worker (--dist loadscope keeps a module on one worker).

@pytest.fixture(scope="session")
def template_fmu(tmp_path_factory):
    """examples/my_controller built with pythonfmu alone, as its README recipe does."""
    from pythonfmu import FmuBuilder

    def make(folder):
        FmuBuilder.build_FMU(ROOT / "examples" / "my_controller" / "my_controller.py", dest=folder)

    return made_once(tmp_path_factory, "template_fmu", make) / "MyController.fmu"


QUICK_CASES = 3  # of the paired design on the tests' quick board: the smallest that has pairs to rank
FULL_CASES = 6  # on the tests' board of every built-in controller: the fewest where one controller lower in every
# case is significantly lower (Wilcoxon: p = 2 / 2^6 = 0.031; with 5 cases 0.0625 at best)


@pytest.fixture(scope="module")
def user_lqr(tmp_path_factory):
    """A user's regulation-only controller (tests/user_lqr.py: no x_d, no planner inputs), built by stock pythonfmu."""
    from pythonfmu import FmuBuilder

    return FmuBuilder.build_FMU(ROOT / "tests" / "user_lqr.py", dest=tmp_path_factory.mktemp("user"))


@pytest.fixture(scope="module")
def board_dir(native):
    """The built-in FMUs of the quick board's tests: the native ones (held to the Python FMUs' board to 1e-9 by
    test_native_board.py), the Python FMUs of the kinds not ported beside them. The user's controller is a
    Python FMU."""
    return native[2]


@pytest.fixture(scope="module")
def quick_board(template_fmu, board_dir, dask_scheduler, tmp_path_factory):
    """The template and the LQR alone (--only), quick, 3 paired cases: the board is in OUT/quick."""
    out = tmp_path_factory.mktemp("compare")
    log = []
    rows = compare(out, [str(template_fmu), "LqrController"], board_dir, scheduler=dask_scheduler, quick=True,
                   progress=False, animate=(), only=True, log=log.append, cases=QUICK_CASES)
    return out / "quick", rows, log


@pytest.fixture(scope="module")
def full_board(native, dask_scheduler, tmp_path_factory):
    """Every built-in controller on every scenario, FULL_CASES cases of the paired design, on the native FMUs (which
    give the Python FMUs' board to 1e-9 in every figure: test_native_board.py; the Python MPC alone would take most
    of the run): ``(folder, rows, FMU folder)``."""
    out = tmp_path_factory.mktemp("full")
    rows = compare(out, (), native[2], scheduler=dask_scheduler, progress=False, animate=(), log=lambda _: None,
                   cases=FULL_CASES)
    return out, rows, native[2]


def test_every_controller_scenario_and_case_is_a_row(quick_board):
    out, rows, log = quick_board
    table = pq.read_table(out / "scores.parquet").to_pylist()
    cases_per_controller = {"S1": 1, "S2": 1, "S3": 3, "S4": 1, "S5": 1, "S6": 3, "S7": 1, "S8": 2, "S9": 3,
                            "S10": 3}
    for name in ("MyController", "LqrController"):
        mine = [r for r in table if r["controller"] == name]
        assert {s: sum(r["scenario"] == s for r in mine) for s in cases_per_controller} == cases_per_controller
    # 2 controllers x the 19 cases above; the one not ok is MyController's S6 at h = 50 ms (see the next test)
    assert log[-1].startswith("38 cases: 38 run now, 0 already done, 1 not ok")
    for name in ("scoreboard.md", "index.html", "board.json", "S1.png", "S2.png", "S7.png", "summary.png"):
        assert (out / name).stat().st_size > 1000


def test_a_quick_board_cannot_be_mistaken_for_a_full_one(quick_board):
    out, _, _ = quick_board
    table = pq.read_table(out / "scores.parquet").to_pylist()
    assert all(r["quick"] for r in table)
    s3 = [r for r in table if r["scenario"] == "S3"]
    assert {(r["scenario_plants"], r["scenario_steps"], r["scenario_cases"]) for r in s3} == {(3, 1, 3)}
    board = (out / "scoreboard.md").read_text()
    assert board.startswith("# Controller scoreboard (QUICK")
    assert "| S3 (QUICK: 3 cases): " in board and "## S3 (QUICK: 3 cases): " in board
    assert not (out.parent / "scoreboard.md").exists()  # the quick board has a folder of its own


def test_a_full_board_survives_a_quick_run_in_the_same_folder(full_board, dask_scheduler):
    out, rows, fmus = full_board
    before = {name: (out / name).read_bytes() for name in ("scoreboard.md", "scores.parquet", JOURNAL)}
    compare(out, ["LqrController"], fmus, scheduler=dask_scheduler, quick=True, only=True, progress=False,
            animate=(), log=lambda _: None, scenarios=("S1",))
    assert {name: (out / name).read_bytes() for name in before} == before
    assert (out / "quick" / "scoreboard.md").read_text().startswith("# Controller scoreboard (QUICK")
    table = pq.read_table(out / "scores.parquet").to_pylist()
    controllers = {r["controller"] for r in table}
    assert controllers == {c.model_identifier for c in components.registered("controller")}
    assert not any(r["quick"] for r in table)
    # each controller of the planar crane: 10 cases of S1, S2 and S4-S8, FULL_CASES each of S3, S9 and S10, a row
    # n/a of each of S11-S14; each of the crane in three dimensions: a case of each of S11-S14, a row n/a of S1-S10
    spatial = {"LqrController3D", "MpcController3D"}
    assert spatial < controllers
    assert len(table) == (len(controllers) - 2) * (10 + 3 * FULL_CASES + 4) + 2 * (4 + 10)
    assert {r["scenario_plants"] for r in table if r["scenario"] == "S3"} == {FULL_CASES}


def test_the_paper_law_ranks_below_the_converging_laws_in_every_scenario(full_board):
    """The paper's law limit-cycles or diverges; the energy law converges (slowly) and the LQR converges: the
    board says so in every scenario, not the alphabet (on the paired design by Wilcoxon's test over 6 cases)."""
    _, rows, _ = full_board
    for sid in (sid for sid, s in scenarios.scenarios().items() if s.plant == "CranePlant"):  # theirs: S1-S10
        rank = {line["controller"]: line["rank"] for line in ranking.summarise(rows, sid)}
        assert rank["BacksteppingController"] > max(rank["EnergyController"], rank["LqrController"]), sid


def test_any_order_of_controllers_gives_the_same_board(quick_board, template_fmu, board_dir, tmp_path):
    """The quick board again, from the command line, with the controllers in the other order, in a new folder."""
    out, _, _ = quick_board
    assert main(["compare", "--controller", "LqrController", "--controller", str(template_fmu), "--only", "--quick",
                 "--out", str(tmp_path), "--fmu-dir", str(board_dir), "--workers", "2", "--no-progress",
                 "--animate", "none", "--cases", str(QUICK_CASES)]) == 0

    def board(folder):  # but the date of the board
        return re.sub(r"- date: \S+", "", (folder / "scoreboard.md").read_text())

    assert board(tmp_path / "quick") == board(out)

    def table(folder):
        return [{k: v for k, v in r.items() if k not in ("duration_s", "date")}
                for r in pq.read_table(folder / "scores.parquet").to_pylist()]

    assert table(tmp_path / "quick") == table(out)


def test_your_controller_is_scored_beside_every_built_in_one(template_fmu, fmu_dir):
    chosen = contenders([str(template_fmu)], fmu_dir)
    builtin = [c.model_identifier for c in components.registered("controller")]
    assert sorted(c.name for c in chosen) == sorted(builtin + ["MyController"])
    assert [c.name for c in chosen if c.user] == ["MyController"]
    assert [c.name for c in contenders([str(template_fmu)], fmu_dir, only=True)] == ["MyController"]


def test_the_board_marks_your_controller(quick_board):
    out, _, _ = quick_board
    board = (out / "scoreboard.md").read_text()
    assert "Controllers: `LqrController`, `MyController` (yours)" in board
    assert "`MyController` (yours):" in board and "`LqrController` (yours)" not in board


def test_animations_are_drawn_only_when_their_run_changed(quick_board, template_fmu, board_dir, dask_scheduler):
    out, _, _ = quick_board
    chosen = [str(template_fmu), "LqrController"]
    logs = []
    for _ in range(2):
        compare(out.parent, chosen, board_dir, scheduler=dask_scheduler, quick=True, only=True, progress=False,
                animate=("S2",), log=logs.append, cases=QUICK_CASES)
    ends = [line for line in logs if re.match(r"\d+ cases: ", line)]  # each run's last line (the board before it)
    assert ends[0].endswith("4 plots and 2 animations drawn now") and "38 already done" in ends[0]
    assert ends[1].endswith("4 plots and 0 animations drawn now")
    (out / "animations" / "S2_LqrController.gif").unlink()
    compare(out.parent, chosen, board_dir, scheduler=dask_scheduler, quick=True, only=True, progress=False,
            animate=("S2",), log=logs.append, cases=QUICK_CASES)
    ends = [line for line in logs if re.match(r"\d+ cases: ", line)]
    assert ends[2].endswith("4 plots and 1 animations drawn now")
    assert (out / "animations" / "S2_LqrController.gif").stat().st_size > 10_000


def test_a_scenario_of_the_crane_in_three_dimensions_is_animated_in_both_planes_and_from_above(native, tmp_path):
    from PIL import Image

    compare(tmp_path, ["LqrController3D"], native[2], scenarios=["S12"], progress=False, animate=("S12",), workers=1,
            log=lambda _: None)
    gif = Image.open(tmp_path / "animations" / "S12_LqrController3D.gif")
    assert gif.n_frames > 1 and gif.size[0] > 2 * gif.size[1]  # three views side by side


def test_a_controller_that_fails_in_one_case_is_scored_failed_there_only(quick_board):
    """Which case fails follows from the template's own rule, not from today's output: MyController discards
    every step longer than its max_step = 0.02 s, and of all the quick suite's cases only S6's h = 50 ms
    step is longer (S6 runs at 1, 10 and 50 ms; every other scenario at 1 ms)."""
    out, rows, _ = quick_board
    failed = [r for r in rows if r["status"] not in ("ok", "n/a")]  # n/a: the 3-D crane's S11-S14
    assert [(r["controller"], r["scenario"], r["case"]) for r in failed] == [("MyController", "S6", "h=50ms")]
    assert "controller: fmi2DoStep returned discard at t=0 s" in failed[0]["error"]
    board = (out / "scoreboard.md").read_text()
    assert "**failed** in 1 of 3: controller: fmi2DoStep returned discard" in board
    s6 = board.split("## S6")[1].split("## S7")[0]
    assert s6.index("`LqrController`") < s6.index("`MyController`")  # a failed case ranks last


def test_the_harness_runs_the_same_system_as_simulate(quick_board, board_dir):
    """S2 for the LQR is the built-in transport system on the drive-limited plant: the same figures.

    The expected figures are computed here from the recorded run, by their definitions, without
    crane_fmu.analysis.metrics (which the harness uses): the arrival is the first sample from which on the
    trolley stays within 5 mm of x_d = 2 m and both angles within 0.5 deg; the residual is the largest swing
    of either angle from one slow period (2.368 s, Section V) after the planned move's end on; the bounds
    (|u| <= 2 m/s2, |v| <= 1 m/s, the trolley within -1 m and 3 m) held.
    """
    _, rows, _ = quick_board
    row = next(r for r in rows if r["controller"] == "LqrController" and r["scenario"] == "S2")
    system = systems.get("transport").with_parameters({"plant": {"u_max": 2.0, "v_max": 1.0}})
    c = run(system, board_dir, recorder=ArrayRecorder()).columns()
    from crane_fmu.model import planner

    end = planner.configure({**planner.COMPONENT.defaults(), "x_d": 2.0}).end
    t, theta1, theta2 = c["time"], c["plant.theta1"], c["plant.theta2"]
    half_degree = math.radians(0.5)
    inside = (np.abs(c["plant.x"] - 2.0) <= 0.005) & (np.abs(theta1) <= half_degree) & (np.abs(theta2) <= half_degree)
    assert inside[-1]
    arrival = t[np.nonzero(~inside)[0][-1] + 1]
    after = t >= end + _slow_period()
    residual = math.degrees(max(np.abs(theta1[after]).max(), np.abs(theta2[after]).max()))
    assert row["arrival_s"] == arrival and row["residual_deg"] == pytest.approx(residual, rel=1e-12)
    held = (np.abs(c["controller.u"]).max() <= 2.0 and np.abs(c["plant.dx"]).max() <= 1.0 + 1e-9
            and -1.0 <= c["plant.x"].min() and c["plant.x"].max() <= 3.0)
    assert held and row["bounds_held"] is True and row["bounds_broken"] == ""


def _slow_period():
    """The slow swing period [s] of Section V's double pendulum linearised at rest, from its closed form: the
    smaller root w^2 of det(K - w^2 M) = 0 with M = [[(m1+m2) l1^2, m2 l1 l2], [m2 l1 l2, m2 l2^2]] and
    K = diag((m1+m2) g l1, m2 g l2) (2.36825 s; not the code's own value, which was pasted here before)."""
    m1, m2, l1, l2, g = 3.0, 7.0, 1.0, 0.5, 9.8  # Section V
    a, b = (m1 + m2) * l1 ** 2 * m2 * l2 ** 2 - (m2 * l1 * l2) ** 2, -((m1 + m2) * l1 ** 2 * m2 * g * l2
                                                                       + m2 * l2 ** 2 * (m1 + m2) * g * l1)
    c = (m1 + m2) * g * l1 * m2 * g * l2
    slow = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)  # the smaller w^2
    return 2 * math.pi / math.sqrt(slow)


def test_every_row_records_the_metric_module_that_measured_it(quick_board, board_dir, monkeypatch):
    """Each row and the board name the metrics' version; under another version every case has another id, so
    a journal's rows of the old one are never taken into the new board."""
    from crane_fmu import compare as harness
    from crane_fmu.analysis import metrics

    out, rows, _ = quick_board
    table = pq.read_table(out / "scores.parquet").to_pylist()
    assert {r["metrics_version"] for r in table if r["case_id"] is not None} == {metrics.VERSION}
    assert f"version {metrics.VERSION}" in (out / "scoreboard.md").read_text()
    chosen = contenders(["LqrController"], board_dir, only=True)
    ids = {c["case_id"] for c in harness.plan(chosen, board_dir, ("S1", "S2"))[0]}
    monkeypatch.setattr(metrics, "VERSION", "another version")
    assert ids.isdisjoint(c["case_id"] for c in harness.plan(chosen, board_dir, ("S1", "S2"))[0])


def test_a_rerun_resumes(quick_board, template_fmu, board_dir, dask_scheduler):
    out, rows, _ = quick_board
    log = []
    again = compare(out.parent, [str(template_fmu), "LqrController"], board_dir, scheduler=dask_scheduler, quick=True,
                    progress=False, animate=(), only=True, log=log.append, cases=QUICK_CASES)
    assert log[-1].startswith("38 cases: 0 run now, 38 already done")
    assert [r.get("case_id") for r in again] == [r.get("case_id") for r in rows]  # n/a rows: none


@pytest.mark.parametrize("argv, message", [
    (["--controller", "Nothing"], "no controller 'Nothing'; controllers: BacksteppingController, LqrController"),
    (["--controller", "{fmu_dir}/CranePlant.fmu"], "CranePlant is not a crane controller: of CranePlant, it misses x, "
                                                  "dx, theta1, dtheta1, theta2, dtheta2, output u (the interface: "),
    (["--controller", "{user_lqr}", "--only", "--scenario", "S2,S3"],
     "UserLqr: no scenario of S2, S3 applies to it: n/a (needs x_d or x_ref); it can run S1, S6"),
    (["--controller", "LqrController3D", "--only", "--scenario", "S1"],
     "LqrController3D: no scenario of S1 applies to it: n/a (no controller of CranePlant); it can run S11, S12"),
    (["--scenario", "S1,S99"], "--scenario S99: no such scenario; the scenarios are S1, S2"),
    (["--cases", "0"], "--cases must be a whole number >= 1, got 0"),
    (["--controller", "{fmu_dir}/LqrController.fmu"],
     "LqrController.fmu and LqrController; rename the FMU file or give --only"),
    (["--workers", "0"], "--workers must be >= 1"),
    (["--animate", "S4"], "--animate S4: choose none, all, S1, S2, S7, S11, S12, S13, S14"),
    (["--only"], "--only scores only the --controller ones: give at least one --controller"),
    (["--scheduler", "tcp://127.0.0.1:9"], "--scheduler tcp://127.0.0.1:9: no Dask scheduler answers there"),
])
def test_compare_mistakes_are_one_line(fmu_dir, user_lqr, tmp_path, capsys, argv, message):
    """Refused before anything runs: nothing is written."""
    argv = [a.format(fmu_dir=fmu_dir, user_lqr=user_lqr) for a in argv]
    assert main(["compare", "--out", str(tmp_path / "o"), "--fmu-dir", str(fmu_dir), *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "o").exists()  # not even an empty folder (issue 29)


def test_a_scenario_of_one_crane_scores_the_controllers_of_that_crane(native, tmp_path):
    """``compare --scenario S1`` (every built-in controller) had been refused because the controllers of the crane in
    three dimensions run no scenario of S1; they are left out, the planar ones scored."""
    rows = compare(tmp_path, (), native[2], scenarios=["S1"], progress=False, animate=(), workers=1,
                   log=lambda _: None)
    spatial = {"LqrController3D", "MpcController3D"}  # the controllers of ux and uy
    builtin = {c.model_identifier for c in components.registered("controller")}
    assert {r["controller"] for r in rows} == builtin - spatial


def test_animate_a_simulate_result(fmu_dir, tmp_path, capsys):
    from PIL import Image

    csv = tmp_path / "move.csv"
    assert main(["simulate", "--system", "transport", "--fmu-dir", str(fmu_dir), "--stop-time", "1",
                 "--out", str(csv)]) == 0
    capsys.readouterr()
    assert main(["animate", str(csv), "--out", str(tmp_path / "move.gif"), "--fps", "10"]) == 0
    out, err = capsys.readouterr()
    assert re.fullmatch(r"wrote \S+move.gif \(\d+\.\d s\)\n", out) and "frame" not in err  # no progress off a terminal
    gif = Image.open(tmp_path / "move.gif")
    assert gif.n_frames == 11 and gif.size[0] > 300
    durations = []
    for k in range(gif.n_frames):
        gif.seek(k)
        durations.append(gif.info["duration"])
    assert sum(durations) == 1100  # real time: 10 frames a second, and the last one shown as long
    assert main(["animate", str(csv), "--out", str(tmp_path / "move.txt")]) == 2
    free = {k: v for k, v in read_csv(csv).items() if k in ("time", "controller.u")}
    from crane_fmu.cosim import write_csv

    write_csv(tmp_path / "no_crane.csv", free)
    assert main(["animate", str(tmp_path / "no_crane.csv"), "--out", str(tmp_path / "x.gif")]) == 2
    err = capsys.readouterr().err
    assert "has no crane to animate: it needs a plant's outputs (CranePlant: x, x1, y1, x2, y2" in err


@pytest.mark.parametrize("every", [32, 7, 250])
def test_a_gif_plays_in_real_time_from_any_output_interval(fmu_dir, tmp_path, every):
    """fmpy writes every 32 ms, the master every 1 ms, a user may keep every 0.25 s: the GIF's delays add up
    to the run's duration (within one frame) and are all equal (issue 29: 32 ms output played at 0.8x)."""
    from PIL import Image

    from crane_fmu.analysis.score_plots import animate
    from crane_fmu.cosim import run

    columns = run(systems.get("transport"), fmu_dir, stop_time=3.0).columns()
    kept = {name: values[::every] for name, values in columns.items()}
    animate(kept, tmp_path / "move.gif", fps=15)
    gif = Image.open(tmp_path / "move.gif")
    durations = []
    for k in range(gif.n_frames):
        gif.seek(k)
        durations.append(gif.info["duration"])
    assert abs(sum(durations) - 1000 * kept["time"][-1]) <= 70, (sum(durations), kept["time"][-1])
    assert all(d % 70 == 0 for d in durations)  # whole frames of 7 cs (identical ones merged)


def test_readme_shows_the_current_scoreboard(full_board):
    """Doc-sync only: every built-in controller, run now, gives the README's table: its header and the rows of
    the scenarios that do not depend on the paired design's size, character for character; the rows of the paired
    design (S3, S9, S10), which the README shows for its 64 cases, are there and say so (this board runs 6).

    The table's figures are this code's output (regenerate with ``crane-fmu compare``); the behaviour
    behind them is held by requirement tests: the LQR's targets (test_controllers.py), the documented
    LQR design against scipy, the metrics' known answers (test_metrics.py) and the ranking rules
    (test_scoreboard.py, test_statistics.py)."""
    _, rows, _ = full_board
    generated = board_tables.render_summary(rows, cases=FULL_CASES).splitlines()
    for page in (ROOT / "README.md", ROOT / "docs" / "guide" / "scoreboard.md"):  # the front door and the guide
        text = page.read_text()
        shown = re.search(r"<!-- scoreboard:start -->\n(.*)\n<!-- scoreboard:end -->", text, re.S).group(1)
        shown = shown.strip().splitlines()
        assert len(shown) == len(generated) and shown[:2] == generated[:2], page
        for ours, theirs in zip(generated[2:], shown[2:]):
            sid = ours[2:].split(" ")[0].rstrip(":")
            if sid in planar.PAIRED:
                assert theirs.startswith(f"| {sid} ({scenarios.CASES} cases): "), (page, sid)
            else:
                assert theirs == ours, (page, sid)


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


# ---- any controller's interface, provenance, the journal, --check, the page ----------------------------------------

@pytest.fixture(scope="module")
def user_board(user_lqr, fmu_dir, tmp_path_factory):
    """The issue's command for a regulation-only controller: ``compare --controller UserLqr.fmu --quick --only``."""
    out = tmp_path_factory.mktemp("user_board")
    assert main(["compare", "--controller", str(user_lqr), "--quick", "--only", "--out", str(out), "--fmu-dir",
                 str(fmu_dir), "--workers", "2", "--no-progress", "--animate", "none"]) == 0
    return out / "quick"


def test_a_regulation_only_controller_is_scored_where_its_interface_allows(user_board):
    """S1 and S6 (4 cases) run and are ranked; every other scenario is a row 'n/a (needs x_d or x_ref)', no rank."""
    table = pq.read_table(user_board / "scores.parquet").to_pylist()
    ran = sorted((r["scenario"], r["case"]) for r in table if r["status"] != "n/a")
    assert ran == [("S1", "nominal"), ("S6", "h=10ms"), ("S6", "h=1ms"), ("S6", "h=50ms")]
    absent = {r["scenario"]: r["error"] for r in table if r["status"] == "n/a"}
    assert absent == {sid: "n/a (needs x_d or x_ref)" if s.plant == "CranePlant" else "n/a (no controller of "
                      "CranePlant3D)" for sid, s in scenarios.scenarios().items() if sid not in ("S1", "S6")}
    board = (user_board / "scoreboard.md").read_text()
    assert "| 1. `UserLqr` (yours): 3.03 s (1.50x floor), all targets met |" in board  # S1: the LQR's figure
    assert "| `UserLqr` (yours): n/a (needs x_d or x_ref) |" in board


def test_every_row_records_its_provenance(quick_board, board_dir, template_fmu):
    """The sha256 of each FMU scored (the files' own), the seeds, the versions, the master, the step and the
    date, in every Parquet row and in the board."""
    import hashlib
    import json

    out, _, _ = quick_board
    table = [r for r in pq.read_table(out / "scores.parquet").to_pylist() if r["case_id"]]
    files = {p.name: p for p in [*Path(board_dir).glob("*.fmu"), Path(template_fmu)]}
    for row in table:
        for name, digest in json.loads(row["fmus_sha256"]).items():
            assert digest == hashlib.sha256(files[name].read_bytes()).hexdigest(), (row["case"], name)
        assert set(json.loads(row["versions"])) == {"crane-antisway-cosim", "python", "fmpy", "numpy", "scipy"}
        assert row["master"] == "gauss-seidel" and row["step"] in (1e-3, 1e-2, 5e-2) and row["date"][:2] == "20"
    design = planar.design(QUICK_CASES)
    s10 = sorted((r for r in table if r["scenario"] == "S10" and r["controller"] == "LqrController"),
                 key=lambda r: r["case"])
    assert [json.loads(r["seeds"]) for r in s10] == [{"wind.seed": c["seed"]} for c in design]
    assert [(r["plant_l1"], r["plant_m1"]) for r in s10] == [(c["l1"], c["m1"]) for c in design]
    board = (out / "scoreboard.md").read_text()
    lqr = hashlib.sha256((Path(board_dir) / "LqrController.fmu").read_bytes()).hexdigest()
    assert "## Provenance" in board and f"LqrController.fmu {lqr}" in board and "- master: gauss-seidel" in board


def test_a_journal_made_with_other_fmus_is_not_resumed(user_board, fmu_dir, user_lqr, dask_scheduler, tmp_path):
    """A journal whose rows were made with another CranePlant.fmu (its sha256 in every row): the board starts
    again, says why, and keeps the old journal."""
    import json
    import shutil

    folder = tmp_path / "out"
    shutil.copytree(user_board.parent, folder)
    journal = folder / "quick" / JOURNAL
    rows = [json.loads(line) for line in journal.read_text().splitlines()]
    for row in rows:
        shas = json.loads(row["fmus_sha256"])
        shas["CranePlant.fmu"] = "0" * 64
        row.update(fmus_sha256=json.dumps(shas), case_id="other" + row["case_id"][5:])
    journal.write_text("".join(json.dumps(r) + "\n" for r in rows))
    log = []
    compare(folder, [str(user_lqr)], fmu_dir, scheduler=dask_scheduler, quick=True, only=True, progress=False,
            animate=(), log=log.append)
    assert re.fullmatch(r"\S+cases.jsonl is not resumed: it was made with other FMUs \(CranePlant.fmu: sha256 "
                        r"000000000000\.\.\., now [0-9a-f]{12}\.\.\.; in UserLqr, S\d, [^)]+\); kept as "
                        r"cases\.jsonl\.\S+\.old, the board starts again", log[0]), log[0]
    assert log[-1].startswith("4 cases: 4 run now, 0 already done")
    assert len(list((folder / "quick").glob("cases.jsonl.*.old"))) == 1


def test_check_confirms_the_figures_bit_for_bit_or_names_the_case_that_differs(user_board, tmp_path, capsys):
    import shutil

    import pyarrow as pa

    assert main(["compare", "--check", str(user_board), "--sample", "2", "--workers", "2"]) == 0
    assert capsys.readouterr().out.endswith("every figure the same, bit for bit\n")
    folder = tmp_path / "board"
    shutil.copytree(user_board, folder)
    table = pq.read_table(folder / "scores.parquet").to_pylist()
    row = next(r for r in table if r["scenario"] == "S1")
    row["settling_0.5deg_s"] += 1e-12
    pq.write_table(pa.Table.from_pylist(table), folder / "scores.parquet")
    assert main(["compare", "--check", str(folder), "--sample", "4", "--workers", "2"]) == 1
    out = capsys.readouterr().out
    assert f"differs: UserLqr, S1, nominal: settling_0.5deg_s: {row['settling_0.5deg_s']!r} recorded, " in out
    assert main(["compare", "--check", str(tmp_path / "nothing")]) == 2
    assert "--check " in capsys.readouterr().err


def test_compare_prints_the_ranking_in_the_terminal(quick_board):
    """Not only file paths: every scenario's line (how long it runs), then its controllers by rank, one a line,
    in the board's order."""
    _, rows, log = quick_board
    printed = "\n".join(log).splitlines()
    for sid in ("S1", "S2", "S3"):
        at = next(i for i, line in enumerate(printed) if line.startswith(f"{sid}") and "ranked by" in line)
        assert "10 s; ranked by" in printed[at]
        ranked = ranking.summarise(rows, sid)
        for k, line in enumerate(ranked, start=1):
            assert printed[at + k].startswith(f"  {line['rank']}. {line['controller']}"), printed[at:at + 4]


def test_check_finds_a_quick_board_in_OUT_quick(quick_board, dask_scheduler):
    """`compare --quick --out OUT` writes OUT/quick; `compare --check OUT` finds it there (OUT holds no full board)."""
    out, _, _ = quick_board
    log = []
    assert check(out.parent, 2, scheduler=dask_scheduler, log=log.append) == []
    assert log[0] == f"no full board in {out.parent}: checking the quick board in {out}"


def test_the_page_is_one_file_that_a_browser_shows_with_its_tables_and_pictures(quick_board, tmp_path):
    """OUT/index.html in headless Chromium from a file URL (no server): a screenshot shows the summary picture
    (pixels of the LQR's own colour) and the tables (rows of the table header's background); the page refers
    to no other file."""
    import shutil
    import subprocess

    from PIL import Image

    from crane_fmu.analysis.score_plots import colour

    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        pytest.skip("needs chromium (Debian's package; .ci/run installs it)")
    out, _, _ = quick_board
    page = (out / "index.html").read_text()
    assert re.findall(r'(?:src|href)="([^"]*)"', page) and all(
        link.startswith("data:image/") for link in re.findall(r'(?:src|href)="([^"]*)"', page))
    shot = tmp_path / "shot.png"
    subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                    "--window-size=1400,2600", f"--screenshot={shot}", (out / "index.html").as_uri()],
                   capture_output=True, timeout=180, check=True)
    pixels = np.asarray(Image.open(shot).convert("RGB")).reshape(-1, 3)
    import matplotlib.colors

    lqr = np.round(np.array(matplotlib.colors.to_rgb(colour("LqrController"))) * 255)
    assert np.sum(np.all(np.abs(pixels - lqr) <= 2, axis=1)) > 2000  # the summary's bars
    header = np.array([0xE8, 0xEE, 0xF4])  # th background in board_page.STYLE
    assert np.sum(np.all(pixels == header, axis=1)) > 5000  # the tables' header rows
