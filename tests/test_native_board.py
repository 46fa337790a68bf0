"""``crane-fmu compare --fmu-dir build/native`` scores the built-in controllers as the Python FMUs do.

A module of its own, beside test_compare.py: it needs the run's quick board of the built-in controllers (made once
for every worker, conftest.py's ``builtin_quick_board``), not test_compare's full board, so the two boards run on
two workers at once.
"""

import math

from helpers import BOARD_CASES, BOARD_CONTROLLERS

from crane_fmu.analysis import board_tables, scenarios
from crane_fmu.compare import compare


def _close(a, b):
    """Equal to 1e-9 (relative above 1) in every number, NaN as NaN, recursively through lists and dicts."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b)) or abs(a - b) <= 1e-9 * max(1.0, abs(a))
    return a == b


def test_the_native_fmus_give_the_python_board(builtin_quick_board, native, dask_scheduler, tmp_path):
    """The components ported to C native, the others the Python FMUs copied beside them: every controller of the
    run's quick board (BOARD_CONTROLLERS: every built-in one but the MPC, whose native runs test_native_mpc.py holds
    to the Python ones bit for bit) on every scenario (BOARD_CASES paired cases) gives every figure to 1e-9, the
    same statuses and the same board. (Not the case identities, which hash the FMU files, nor run times, nor the
    failed runs' log text.)"""
    _, python_rows = builtin_quick_board
    rows = compare(tmp_path, BOARD_CONTROLLERS, native[2], scheduler=dask_scheduler, quick=True, progress=False,
                   animate=(), log=lambda _: None, cases=BOARD_CASES, only=True)
    key = lambda r: (r["scenario"], r["controller"], r["case"])  # noqa: E731
    theirs = {key(r): r for r in python_rows}
    assert sorted(map(key, rows)) == sorted(theirs)
    assert {r["scenario"] for r in rows} == set(scenarios.scenarios())
    for row in rows:
        ours, other = ({k: v for k, v in r.items() if k not in ("case_id", "duration_s", "error", "fmus_sha256",
                                                                  "date")}
                       for r in (row, theirs[key(row)]))
        assert _close(ours, other), (key(row), {k: (ours.get(k), other.get(k)) for k in ours.keys() | other.keys()
                                                if not _close({k: ours.get(k)}, {k: other.get(k)})})
    assert board_tables.render_summary(rows) == board_tables.render_summary(python_rows)


def test_a_board_drawn_as_its_rows_come_in_is_the_one_drawn_at_the_end(native, dask_scheduler, tmp_path,
                                                                        monkeypatch):
    """Each scenario's statistics, picture and animations begun as its rows come in (the scenarios run out of the
    board's order) give the board's rows in its order, and the very scoreboard, PNG and GIF bytes that drawing them
    all from the finished rows gives (as the board did before), drawn again here, not copied from the first."""
    import json
    import tempfile

    from crane_fmu.analysis import ranking, score_plots
    from crane_fmu.analysis.floor import stored_scenario_floors
    from crane_fmu.compare import _provenance_lines, contenders, plan

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # the board's store of pictures: its own
    chosen, chosen_scenarios = ["LqrController", "BacksteppingController"], ["S1", "S2", "S3", "S7"]
    board = tmp_path / "board" / "quick"
    rows = compare(tmp_path / "board", chosen, native[2], scheduler=dask_scheduler, quick=True, cases=2,
                   scenarios=chosen_scenarios, animate=("S2",), only=True, progress=False, log=lambda _: None)
    planned, _, refused = plan(contenders(chosen, native[2], True), native[2], chosen_scenarios, 2)
    assert [r["case_id"] for r in rows] == [c["case_id"] for c in planned] + [r.get("case_id") for r in refused]

    end = tmp_path / "end"
    end.mkdir()
    stats = ranking.board_statistics(rows)
    drawn = score_plots.plot_all(rows, end, (), stats, store=tmp_path / "again")
    drawn += score_plots.animate_all(rows, "S2", end / "animations", store=tmp_path / "again")
    assert sorted(p.relative_to(end).as_posix() for p in drawn) == [
        "S1.png", "S2.png", "S7.png", "animations/S2_BacksteppingController.gif", "animations/S2_LqrController.gif",
        "summary.png"]
    for path in drawn:
        assert (board / path.relative_to(end)).read_bytes() == path.read_bytes(), path.name
    manifest = json.loads((board / "board.json").read_text())
    assert (board / "scoreboard.md").read_text() == board_tables.render(
        rows, contenders(chosen, native[2], True), True, 2, _provenance_lines(manifest), stats,
        stored_scenario_floors())


def test_a_board_in_a_local_process_pool_gives_the_bits_of_one_on_dask(native, dask_scheduler, tmp_path):
    """Without --scheduler the board's cases run in a local process pool, not on Dask: every row the same bits
    (but when it was made and how long it took), in the same order. (As JSON: Dask hands the kept signals back as
    tuples, the pool as lists.)"""
    import json

    chosen, chosen_scenarios = ["LqrController", "BacksteppingController"], ["S1", "S2", "S3", "S9"]
    boards = [compare(tmp_path / on, chosen, native[2], quick=True, cases=2, scenarios=chosen_scenarios, animate=(),
                      only=True, progress=False, log=lambda _: None, **settings)
              for on, settings in (("dask", {"scheduler": dask_scheduler}), ("pool", {"workers": 2}))]
    assert len(boards[0]) == len(boards[1]) > 8
    for ours, theirs in zip(*boards):
        assert json.dumps({k: v for k, v in ours.items() if k not in ("date", "duration_s")}, sort_keys=True) == (
            json.dumps({k: v for k, v in theirs.items() if k not in ("date", "duration_s")}, sort_keys=True)), (
            ours["scenario"], ours["case"])
