"""The local pool of a batch's chunks (a local board's): a process killed in a chunk loses none of the cases it
finished and the batch goes on; a case that kills its process every time is a row that says so, or one line."""

import json
import os
import signal
import threading
import time
from pathlib import Path

import psutil
import pytest
from helpers import chunk_waiting_once

from crane_fmu.batch import JOURNAL, run_batch
from crane_fmu.pool import STRIKES

PD_SWAY = Path(__file__).parent.parent / "examples" / "my_controller" / "pd_sway.py"
CHUNKS = [("batch", [0, 1, 2]), ("batch", [3, 4, 5])]
EVERY = [f"{k:016x}" for k in range(6)]


def _crashing_on(item, crash):
    """Each case's row; the case ``crash`` ends its process as a segmentation fault in an FMU's binary would."""
    for case in item[1]:
        if case == crash:
            os.kill(os.getpid(), signal.SIGSEGV)
        yield {"case_id": f"{case:016x}", "status": "ok", "pid": os.getpid()}


def _failing_on(item, fail):
    for case in item[1]:
        if case == fail:
            raise ValueError(f"case {case}: no such crane")
        yield {"case_id": f"{case:016x}", "status": "ok", "pid": os.getpid()}


def _journal(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_a_process_killed_in_a_chunk_loses_none_of_the_cases_it_finished_and_the_batch_goes_on(tmp_path):
    """The process running a chunk is killed after the chunk's first case finished: that case's row (made by the
    killed process) is kept, the rest of the chunk runs in another process, and no case is kept twice."""
    killed = []

    def kill_the_waiting_process():
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            rows = _journal(tmp_path / JOURNAL) if (tmp_path / JOURNAL).exists() else []
            first = [r for r in rows if r["case_id"] == EVERY[0]]
            if first:
                os.kill(first[0]["pid"], signal.SIGKILL)
                killed.append(first[0]["pid"])
                return
            time.sleep(0.02)

    killer = threading.Thread(target=kill_the_waiting_process)
    killer.start()
    start = time.monotonic()
    rows = run_batch(chunk_waiting_once, CHUNKS, workers=2, journal=tmp_path / JOURNAL, chunked=True,
                     folder=str(tmp_path))
    killer.join()
    assert killed, "the process was not killed"
    assert time.monotonic() - start < 60, "the batch waited for the killed process's sleep"
    journal = _journal(tmp_path / JOURNAL)
    assert sorted(r["case_id"] for r in journal) == EVERY == sorted(r["case_id"] for r in rows)
    by_case = {r["case_id"]: r for r in journal}
    assert by_case[EVERY[0]]["pid"] == killed[0]  # finished before the kill, and kept
    assert killed[0] not in {by_case[k]["pid"] for k in EVERY[1:3]}  # the rest of its chunk: run elsewhere


def test_a_case_that_kills_its_process_every_time_is_a_row_that_says_so_and_the_batch_goes_on(tmp_path):
    rows = run_batch(_crashing_on, CHUNKS, workers=2, journal=tmp_path / JOURNAL, chunked=True, crash=4,
                     lost=lambda case, why: {"case_id": f"{case:016x}", "status": "failed", "error": why})
    by_case = {r["case_id"]: r for r in _journal(tmp_path / JOURNAL)}
    assert sorted(by_case) == EVERY == sorted(r["case_id"] for r in rows)
    assert by_case[EVERY[4]] == {"case_id": EVERY[4], "status": "failed", "error": (
        f"its worker process died {STRIKES} times running it (killed by SIGSEGV)")}
    assert all(by_case[k]["status"] == "ok" for k in EVERY if k != EVERY[4])


def test_without_a_row_for_it_such_a_case_ends_the_batch_in_one_line_naming_it(tmp_path):
    with pytest.raises(RuntimeError, match=r"^a case killed its worker process 2 times \(killed by SIGSEGV\): 1$"):
        run_batch(_crashing_on, CHUNKS, workers=2, journal=tmp_path / JOURNAL, chunked=True, crash=1)
    assert EVERY[0] in {r["case_id"] for r in _journal(tmp_path / JOURNAL)}  # finished before: kept


def _pool_processes():
    """The live processes the fork server started (the pool's, and any other batch's in this process)."""
    import multiprocessing.forkserver

    multiprocessing.forkserver.ensure_running()
    server = psutil.Process(multiprocessing.forkserver._forkserver._forkserver_pid)
    return {p.pid for p in server.children() if p.status() != psutil.STATUS_ZOMBIE}


def test_an_exception_a_task_raises_ends_the_batch_as_itself_and_leaves_no_process(tmp_path):
    before = _pool_processes()
    with pytest.raises(ValueError, match="^case 4: no such crane$"):
        run_batch(_failing_on, CHUNKS, workers=2, journal=tmp_path / JOURNAL, chunked=True, fail=4)
    assert {r["pid"] for r in _journal(tmp_path / JOURNAL)} and _pool_processes() <= before


def test_a_board_scores_a_controller_whose_case_crashes_its_process_failed_and_is_written(native, tmp_path):
    """A controller of one's own (a law file) that crashes the process it runs in during S1's run, as
    a fault in an FMU's binary would: the local board scores that case failed, saying why, and the rest of the
    board (the LQR beside it) is run and written."""
    from crane_fmu.compare import compare

    law = tmp_path / "crashing_law.py"
    text = PD_SWAY.read_text().replace('"PdSway", "controller"', '"CrashingLaw", "controller"')
    text = text.replace("    x, dx, theta1, dtheta1, theta2, dtheta2 = inputs\n",
                        "    x, dx, theta1, dtheta1, theta2, dtheta2 = inputs\n"
                        "    if abs(theta1) < 0.1:  # less than the start's swing (0.17 rad): the run is under way\n"
                        "        os.kill(os.getpid(), signal.SIGSEGV)\n")
    law.write_text("import os\nimport signal\n\n" + text)
    rows = compare(tmp_path / "board", [str(law), "LqrController"], fmu_dir=native[2], only=True, scenarios=("S1",),
                   workers=2, progress=False, animate=(), log=lambda line: None)
    by = {row["controller"]: row for row in rows}
    assert by["CrashingLaw"]["status"] == "failed"
    assert by["CrashingLaw"]["error"] == f"its worker process died {STRIKES} times running it (killed by SIGSEGV)"
    assert by["LqrController"]["status"] == "ok"
    assert "CrashingLaw" in (tmp_path / "board" / "scoreboard.md").read_text()

