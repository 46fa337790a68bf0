"""The scoreboard's rules on made-up rows: ranking, the interface check, quick boards, the targets' reasons.

No FMU runs here: each rule is shown on rows written to isolate it (test_compare.py runs real boards).
"""

import itertools
import math

import numpy as np
import pytest
import scipy.linalg

from crane_fmu.analysis import scoreboard
from crane_fmu.analysis.scoreboard import SCENARIOS, Contender


def _row(controller, scenario="S2", case="nominal", status="ok", **metrics):
    """A case row as compare writes it; metrics default to None (never)."""
    names = ("settling_0.5deg_s", "settling_0.1deg_s", "position_1cm_s", "arrival_s", "residual_deg", "overshoot_m",
             "final_error_m", "peak_abs_u", "peak_abs_v", "effort", "end_swing_deg")
    return {"controller": controller, "scenario": scenario, "case": case, "status": status,
            "error": None if status == "ok" else f"{controller}: fmi2DoStep returned discard",
            **dict.fromkeys(names), **metrics}


def _ranked(rows, scenario="S2"):
    return [line["controller"] for line in scoreboard.summarise(rows, scenario)]


# S2: arrival <= 4.0 s and residual <= 0.1 deg; it ranks by arrival
FAST_BOTH = {"arrival_s": 3.0, "residual_deg": 0.05}


def test_a_failed_case_ranks_last():
    """A controller that failed in one case ranks below one that met nothing, whatever its figures."""
    rows = [_row("A", case="one", **FAST_BOTH), _row("A", case="two", status="failed", **FAST_BOTH),
            _row("B", case="one", arrival_s=None, residual_deg=9.0), _row("B", case="two", residual_deg=9.0)]
    assert _ranked(rows) == ["B", "A"]


def test_more_targets_met_ranks_higher_than_a_better_figure():
    """The issue's S7 case: a faster arrival that misses the residual target ranks below a slower one that meets
    both."""
    rows = [_row("Fast", arrival_s=3.0, residual_deg=0.5), _row("Slow", arrival_s=3.9, residual_deg=0.05)]
    assert _ranked(rows) == ["Slow", "Fast"]


def test_then_the_scenario_metric_lower_first():
    rows = [_row("A", arrival_s=3.9, residual_deg=0.05), _row("B", arrival_s=3.1, residual_deg=0.09)]
    assert _ranked(rows) == ["B", "A"]
    s3 = [_row("A", "S3", residual_deg=0.7, arrival_s=9.0), _row("B", "S3", residual_deg=0.8, arrival_s=9.0)]
    assert _ranked(s3, "S3") == ["A", "B"]  # S3 ranks by the residual swing


def test_never_ranks_after_every_finite_value():
    rows = [_row("Never", arrival_s=None, residual_deg=0.5, end_swing_deg=0.0),
            _row("Late", arrival_s=1e9, residual_deg=0.5, end_swing_deg=50.0)]
    assert _ranked(rows) == ["Late", "Never"]


def test_equal_figures_rank_by_the_swing_left():
    """Two that never arrive: the one whose swing dies out ranks above the one that keeps swinging or diverges."""
    rows = [_row("Aaa", residual_deg=30.0, end_swing_deg=25.0), _row("Zzz", residual_deg=2.0, end_swing_deg=2.0),
            _row("Mmm", residual_deg=9.0, end_swing_deg=None)]  # the run ended before the last quarter
    assert _ranked(rows) == ["Zzz", "Aaa", "Mmm"]


def test_ties_are_broken_by_name():
    rows = [_row(name, **FAST_BOTH) for name in ("Charlie", "alpha", "Bravo")]
    assert _ranked(rows) == sorted(["Charlie", "alpha", "Bravo"])


def test_permuting_contenders_changes_nothing():
    """Every order of the rows and of the contenders gives the same board, character for character."""
    rows = [_row("A", arrival_s=None, residual_deg=3.0, end_swing_deg=3.0), _row("B", **FAST_BOTH),
            _row("C", **FAST_BOTH), _row("D", arrival_s=None, residual_deg=3.0, end_swing_deg=3.0),
            _row("E", status="failed", **FAST_BOTH), _row("A", "S1"), _row("B", "S1", status="failed"),
            _row("C", "S1", **{"settling_0.1deg_s": 3.0}), _row("D", "S1"), _row("E", "S1")]
    contenders = [Contender(n, n, [], [], n == "D") for n in "ABCDE"]
    boards = {scoreboard.render(list(itertools.chain(*[[r for r in rows if r["controller"] == n] for n in order])),
                                [contenders["ABCDE".index(n)] for n in order])
              for order in itertools.permutations("ABCDE")}
    assert len(boards) == 1
    board = boards.pop()
    assert "`D` (yours)" in board and scoreboard.RULES in board


def test_the_interface_is_checked_for_every_scenario_at_once():
    with pytest.raises(ValueError) as caught:
        scoreboard.check_interface("Mine", ["x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"], ["u"], ["k"])
    message = str(caught.value)
    assert "\n" not in message
    assert "Mine is not a crane controller: it misses a parameter x_d or the inputs x_ref, dx_ref, ddx_ref " \
           "(S2, S3, S4, S5, S7, S8, S9)" in message
    with pytest.raises(ValueError, match=r"it misses dtheta2, output u \(every scenario\); a parameter x_d"):
        scoreboard.check_interface("Half", ["x", "dx", "theta1", "dtheta1", "theta2"], [], [])
    scoreboard.check_interface("Tracker", list(scoreboard.MEASURED) + ["x_ref", "dx_ref", "ddx_ref"], ["u"])
    scoreboard.check_interface("Regulator", scoreboard.MEASURED, ["u"], ["x_d"])


def test_a_quick_board_says_so_in_its_title_and_every_scenario_line():
    rows = [_row("A", sid, **FAST_BOTH) for sid in SCENARIOS]
    board = scoreboard.render(rows, [Contender("A", "A", [], [])], quick=True)
    assert board.splitlines()[0] == "# Controller scoreboard (QUICK: a subset of the cases, not the full board)"
    scenario_lines = [line for line in board.splitlines() if line.startswith(("| S", "## S"))]
    assert len(scenario_lines) == 2 * len(SCENARIOS)
    assert all("(QUICK: " in line for line in scenario_lines)
    assert "S3 (QUICK: 3 of 27 plants, 3 cases)" in board
    assert "QUICK" not in scoreboard.render(rows, [Contender("A", "A", [], [])])


def test_quick_and_full_scopes():
    assert scoreboard.scope("S3", quick=True) == {"plants": 3, "steps": 1, "cases": 3}
    assert scoreboard.scope("S3") == {"plants": 27, "steps": 1, "cases": 27}
    assert scoreboard.scope("S6", quick=True) == {"plants": 1, "steps": 3, "cases": 3}


def test_every_target_carries_its_reason():
    for s in SCENARIOS.values():
        for t in s.targets:
            assert len(t.source) > 20, (s.id, t)


def _periods(m1, m2, l1, l2, g):
    mass = np.array([[(m1 + m2) * l1 ** 2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2 ** 2]])
    stiffness = np.diag([(m1 + m2) * g * l1, m2 * g * l2])
    return sorted(2 * math.pi / np.sqrt(scipy.linalg.eigvals(stiffness, mass).real), reverse=True)


@pytest.mark.parametrize("l1, l2, m2", [(1.0, 0.5, 7.0), (2.0, 0.5, 7.0), (1.1, 0.6, 3.5)])
def test_the_targets_physics_the_mode_periods_agree_with_scipy(l1, l2, m2):
    """The periods the transport targets are derived from: the closed form against a generalised eigenproblem."""
    assert scoreboard.mode_periods(3.0, m2, l1, l2, 9.8) == pytest.approx(_periods(3.0, m2, l1, l2, 9.8), rel=1e-12)


def test_the_time_optimal_move():
    assert scoreboard.move_time(2.0, 2.0, 1.0) == pytest.approx(2.5)  # 0.5 s up, 1.5 s coasting, 0.5 s down
    assert scoreboard.move_time(0.5, 2.0, 1.0) == pytest.approx(1.0)  # triangular: the speed limit is never reached


def test_a_controllers_colour_is_its_own_on_every_board():
    """By name: the built-in controllers' colours differ, and a user's never takes one of theirs."""
    from crane_fmu import components
    from crane_fmu.analysis.score_plots import colour

    builtin = [colour(c.model_identifier) for c in components.registered("controller")]
    assert len(set(builtin)) == len(builtin)
    for name in ("MyController", "PdController", "mine", "x"):
        assert colour(name) == colour(name) and colour(name) not in builtin


def test_animate_shows_progress_when_asked(tmp_path, capsys):
    from crane_fmu.analysis.score_plots import animate

    t = np.linspace(0.0, 1.0, 101)
    x = 0.5 * t
    signals = {"time": t, "plant.x": x, "plant.x1": x, "plant.y1": -np.ones_like(t), "plant.x2": x,
               "plant.y2": -1.5 * np.ones_like(t)}
    animate(signals, tmp_path / "a.gif", fps=10, progress=True)
    assert capsys.readouterr().err.endswith("\rframe 11/11\n")
    animate(signals, tmp_path / "b.gif", fps=10)
    assert capsys.readouterr().err == ""


# ---- the residual swing: a window the scenario fixes, and targets a swinging run cannot meet ---------------------

TRACKER = Contender("Tracker", "Tracker", list(scoreboard.MEASURED) + ["x_ref", "dx_ref", "ddx_ref"], [])
REGULATOR = Contender("Regulator", "Regulator", list(scoreboard.MEASURED), ["x_d", "l1"])


def test_the_residual_window_is_fixed_by_the_scenario_not_the_controller():
    """A move's window opens one slow period (of the plant as it ends the run) after the planned move's end,
    whether the controller follows the planner or is given x_d alone; regulation's is the last quarter."""
    from crane_fmu.model import planner

    def windows(contender, sid):
        return {r.label: r.residual_from for r in scoreboard.systems_for(contender, sid)}

    for sid in SCENARIOS:
        assert windows(TRACKER, sid) == windows(REGULATOR, sid), sid
    zv_end = planner.configure({**planner.COMPONENT.defaults(), "x_d": 2.0, "shaper": "zv"}).end
    zvd_end = planner.configure({**planner.COMPONENT.defaults(), "x_d": 2.0, "shaper": "zvd", "l1": 1.5}).end
    slow = _periods(3.0, 7.0, 1.0, 0.5, 9.8)[0]
    assert windows(TRACKER, "S2") == {"nominal": pytest.approx(zv_end + slow, rel=1e-12)}
    assert windows(TRACKER, "S1") == {"nominal": 7.5} and set(windows(TRACKER, "S6").values()) == {7.5}
    assert windows(TRACKER, "S7") == {"l1 2 m -> 1 m": pytest.approx(zvd_end + slow, rel=1e-12)}  # ends at l1 = 1 m
    assert windows(TRACKER, "S8") == {"S1": 7.5, "S2": pytest.approx(zv_end + slow, rel=1e-12)}
    s3 = windows(TRACKER, "S3")
    assert s3["l1=1.1, l2=0.6, m2=3.5"] == pytest.approx(zv_end + _periods(3.0, 3.5, 1.1, 0.6, 9.8)[0], rel=1e-12)
    assert all(w < 10.0 - 2.0 for w in s3.values())  # every window holds at least 2 s of the run


def test_every_residual_target_asks_the_swing_stopped():
    """A swing within 0.1 deg counts as stopped (metrics.SETTLED_BAND); no residual target allows more."""
    from crane_fmu.analysis import metrics

    assert scoreboard.STOPPED_DEG == pytest.approx(math.degrees(metrics.SETTLED_BAND), rel=1e-12)
    limits = [t.limit for s in SCENARIOS.values() for t in s.targets if t.metric == "residual_deg"]
    assert limits and max(limits) <= scoreboard.STOPPED_DEG


def _made_up_rows(sid, amplitude_deg):
    """Rows of hand-made runs of every case of a scenario: the trolley at x_d by 1 s, the swing 5 deg at the start,
    decaying with a time constant of 0.3 s to a sustained oscillation of ``amplitude_deg`` at the slow mode's
    frequency (0: to rest)."""
    from crane_fmu.analysis import metrics

    rows = []
    for r in scoreboard.systems_for(TRACKER, sid):
        dt = max(r.step, 0.01)  # the figures need no finer grid than 10 ms
        t = np.round(np.arange(0.0, r.stop_time + dt / 2, dt), 9)
        x = r.x_d * np.minimum(t, 1.0)
        wave = np.cos(2 * np.pi * t / scoreboard.T_SLOW)
        theta = np.radians((5.0 * np.exp(-t / 0.3) + amplitude_deg) * wave)
        figures = metrics.move_metrics(t, x, np.gradient(x, t), theta, -theta, np.zeros_like(t), r.x_d,
                                       r.residual_from)
        rows.append({"controller": "Made-up", "scenario": sid, "case": r.label, "status": "ok", "error": None,
                     **figures})
    return rows


@pytest.mark.parametrize("sid", SCENARIOS)
def test_no_scenario_is_passed_by_a_run_that_never_stops_the_swing(sid):
    """Runs that keep swinging by 0.11 deg (just above the stopped band) or 0.45 deg (inside the arrival band, the
    swing the old residual hid) miss a target in every scenario; the same runs brought to rest meet them all, so
    the targets can be met."""
    for amplitude in (0.11, 0.45):
        line, = scoreboard.summarise(_made_up_rows(sid, amplitude), sid)
        assert not all(line["targets"]), (sid, amplitude, line)
    line, = scoreboard.summarise(_made_up_rows(sid, 0.0), sid)
    assert all(line["targets"]), (sid, line)
