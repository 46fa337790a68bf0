"""Studies on the batch path of native FMUs, on real Dask clusters: rows streamed as cases finish, interrupted and
resumed, a worker killed in a chunk, a cluster started with Dask's own command line; and the progress bar."""

import io
import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from helpers import chunk_waiting_once

from crane_fmu import batch, systems
from crane_fmu.analysis import metrics
from crane_fmu.batch import JOURNAL, Progress, run_batch
from crane_fmu.sweep import spec
from crane_fmu.sweep.runner import run_case, run_study, shippable
from crane_fmu.sweep.spec import case_id

# 240 cases of the paper system on the native FMUs: the plant and the backstepping law, 30 s each (a few seconds of
# work on 2 workers; long enough to be interrupted in the middle)
STUDY = ('stop_time = 30.0\nstep = 0.001\n[parameters]\n"plant.theta1_0" = {start = 0.01, stop = 0.2, num = 40}\n'
         '"plant.l1, controller.l1" = [0.8, 0.9, 1.0, 1.1, 1.2, 1.3]\n[fixed]\n"controller.w_theta2" = 0.0\n')


def _journal_ids(path):
    """The case ids of the journal's whole lines, in order (duplicates kept)."""
    ids = []
    for line in Path(path).read_text().splitlines():
        try:
            ids.append(json.loads(line)["case_id"])
        except ValueError:
            pass
    return ids


def _same_as_per_case(study, rows, native, sample):
    """Every ``sample``-th row of a study's table has the per-case path's figures, bit for bit."""
    settings = {**study.settings(), "metrics_version": metrics.VERSION}
    system = shippable(systems.prepare(systems.get(study.system), study.step, study.stop_time, check=False), native)
    for case, row in list(zip(study.cases(), rows, strict=True))[::sample]:
        expected = run_case(case, system, settings, study.metrics)
        assert row["case_id"] == expected["case_id"]
        assert all(row[k] == expected[k] or (isinstance(row[k], float) and math.isnan(row[k]) and math.isnan(
            expected[k])) for k in ("status", "error", *study.metrics)), case


def test_a_study_interrupted_and_resumed_loses_and_repeats_no_case(native, dask_scheduler, tmp_path):
    """Ctrl-C in the middle of a study on the batch path, then the same command again: the second run runs exactly
    the cases the journal lacks; every case is in the journal once and in the table once, with its figures."""
    (tmp_path / "s.toml").write_text(STUDY)
    study = spec.load(tmp_path / "s.toml")
    out = tmp_path / "o"
    command = [sys.executable, "-m", "crane_fmu", "sweep", str(tmp_path / "s.toml"), "--out", str(out), "--workers",
               "2", "--fmu-dir", str(native[2]), "--no-progress"]
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 300
    while not (out / JOURNAL).exists() or len(_journal_ids(out / JOURNAL)) < 20:
        assert time.monotonic() < deadline and run.poll() is None, run.communicate()
        time.sleep(0.02)
    os.killpg(run.pid, signal.SIGINT)
    _, err = run.communicate(timeout=120)
    assert (run.returncode, err) == (130, "crane-fmu: interrupted\n")
    before = _journal_ids(out / JOURNAL)
    assert 20 <= len(before) < study.case_count(), "the study was not interrupted in the middle"
    assert len(set(before)) == len(before)
    summary = run_study(study, out, native[2], scheduler=dask_scheduler, progress=False)
    assert (summary["skipped"], summary["ran"]) == (len(before), study.case_count() - len(before))
    after = _journal_ids(out / JOURNAL)
    settings = {**study.settings(), "metrics_version": metrics.VERSION}
    assert after[:len(before)] == before and sorted(after) == sorted(case_id(c, settings) for c in study.cases())
    rows = pq.read_table(out / "results.parquet").to_pylist()
    assert [r["case_id"] for r in rows] == [case_id(c, settings) for c in study.cases()]
    _same_as_per_case(study, rows, native[2], 23)


def test_a_worker_killed_in_a_chunk_loses_none_of_the_cases_it_finished(tmp_path):
    """On a real local cluster, the worker running a chunk is killed after the chunk's first case finished: that
    case's row (made by the killed worker) is kept, Dask runs the chunk again on the other worker, whose rows of the
    other cases complete the batch; no case is kept twice."""
    from distributed import Client, LocalCluster

    killed = []
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0", silence_logs=50) as cluster, \
            Client(cluster) as client:
        def kill_the_waiting_worker():
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                rows = [json.loads(line) for line in (tmp_path / JOURNAL).read_text().splitlines()] if (
                    tmp_path / JOURNAL).exists() else []
                first = [r for r in rows if r["case_id"] == f"{0:016x}"]
                if first:
                    pids = client.run(os.getpid)
                    worker = next(w for w, pid in pids.items() if pid == first[0]["pid"])
                    client.run(os._exit, 1, workers=[worker], on_error="ignore")
                    killed.append(first[0]["pid"])
                    return
                time.sleep(0.05)

        killer = threading.Thread(target=kill_the_waiting_worker)
        killer.start()
        rows = run_batch(chunk_waiting_once, [("batch", [0, 1, 2]), ("batch", [3, 4, 5])], on="dask",
                         scheduler=cluster.scheduler_address, journal=tmp_path / JOURNAL, chunked=True,
                         folder=str(tmp_path))
        killer.join()
    assert killed, "the worker was not killed"
    journal = [json.loads(line) for line in (tmp_path / JOURNAL).read_text().splitlines()]
    every = [f"{k:016x}" for k in range(6)]
    assert sorted(r["case_id"] for r in journal) == every == sorted(r["case_id"] for r in rows)
    by_case = {r["case_id"]: r for r in journal}
    assert by_case[f"{0:016x}"]["pid"] == killed[0]  # finished before the kill, and kept
    assert {by_case[f"{k:016x}"]["pid"] for k in (1, 2)} != {killed[0]}  # run again elsewhere


def test_a_cluster_started_with_dasks_command_line_gives_the_same_bits(native, tmp_path):
    """`dask scheduler` and `dask worker --nworkers 2` (Dask's own command line, as docs/guide/sweeps.md shows): a
    native study on that cluster gives every figure of the per-case path."""
    from distributed import Client

    (tmp_path / "s.toml").write_text(STUDY.replace("num = 40", "num = 4"))
    study = spec.load(tmp_path / "s.toml")
    dask = Path(sys.executable).parent / "dask"
    scheduler = subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--dashboard-address", ":0"], stderr=subprocess.PIPE, text=True)
    workers = None
    try:
        address, deadline = None, time.monotonic() + 120
        while address is None:
            line = scheduler.stderr.readline()
            assert line and time.monotonic() < deadline, "the scheduler did not say its address"
            found = re.search(r"Scheduler at:\s+(tcp://\S+)", line)
            address = found and found.group(1)
        workers = subprocess.Popen([str(dask), "worker", address, "--nworkers", "2", "--nthreads", "1",
                                    "--no-dashboard"], stderr=subprocess.DEVNULL)
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        summary = run_study(study, tmp_path / "o", native[2], scheduler=address, progress=False)
        assert summary["ran"] == study.case_count() == 24
        _same_as_per_case(study, pq.read_table(tmp_path / "o" / "results.parquet").to_pylist(), native[2], 1)
    finally:
        for process in (workers, scheduler):
            if process is not None:
                process.terminate()
                process.wait(timeout=60)


@pytest.mark.quick
def test_the_progress_bar_gives_the_rate_of_the_cases_run_now_and_the_time_left(monkeypatch):
    """A resumed batch: 5 of 20 cases done before, then 5 run now in 10 s: 0.5 cases/s, and the 10 left take 20 s."""
    clock = iter(range(0, 100, 2))
    monkeypatch.setattr(batch.time, "perf_counter", lambda: float(next(clock)))
    stream = io.StringIO()
    bar = Progress(20, 5, stream=stream, failed=1)
    for status in ("ok", "ok", "failed", "ok", "ok"):
        bar.update({"status": status})
    last = stream.getvalue().splitlines()[-1]
    assert last == "[###############...............] 10/20 cases, 2 not ok, 0.5/s, 20 s left"


def test_bench_sweep_prints_the_batch_paths_figures(native):
    """`crane-fmu bench --sweep`'s part on the native FMUs (tests/test_cli.py runs the rest), at a few cases: each
    figure printed, each a positive number, the ratios to the C host's limit among them (the figures themselves are
    measured at full length, not asserted)."""
    from crane_fmu.bench_batch import run_batch_bench

    lines = []
    run_batch_bench(native[2], n_cases=8, stop_time=0.2, repeat=1, study_cases=4, board_cases=0, out=lines.append)
    out = "\n".join(lines)
    number = r"([0-9]+\.?[0-9]*)"
    for figure in (rf"batch path, per step: {number} us; in the C host {number} us = {number}x",
                   rf"native batch, 1 worker: {number} cases/s = {number}x the C host's limit \({number} cases/s\)",
                   rf"native batch, 2 workers: {number} cases/s = {number}x the C host's limit \({number} cases/s\)",
                   rf"a 4-case study .*: {number} s wall \({number} CPU-s\), peak memory {number} MB",
                   rf"CPU a case: batch path \(its workers\) {number} ms, the C host {number} ms = {number}x"):
        found = re.search(figure, out)
        assert found and all(float(g) > 0 for g in found.groups()), (figure, out)


def test_a_board_on_its_own_cluster_leaves_no_extracted_fmu(native, tmp_path, monkeypatch):
    """A board on the batch path on a local cluster of its own (its workers' instances reused and never freed):
    when it ends, no FMU it extracted is left in the temporary folder, by this process or its workers."""
    import tempfile

    from crane_fmu.compare import compare
    from crane_fmu.cosim.instance import _EXTRACTED

    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setenv("TMPDIR", str(temporary))  # the workers' temporary folder too: they take this environment
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    rows = compare(tmp_path / "board", ["LqrController"], fmu_dir=native[2], workers=2, quick=True, cases=2,
                   scenarios=["S1", "S3"], animate=(), only=True, progress=False, log=lambda *_: None)
    assert [r["status"] for r in rows] == ["ok"] * 3
    ours = {Path(folder) for folder, pid in _EXTRACTED.items() if pid == os.getpid()}  # removed at our exit
    assert [p for p in temporary.glob("*/modelDescription.xml") if p.parent not in ours] == []


def test_bench_sweep_prints_the_boards_cold_and_warm_times():
    """The board's line of `crane-fmu bench --sweep` gives its cold and warm wall and CPU times, each its own."""
    from crane_fmu.bench_batch import _print

    figures = {"pair_us": 1.0, "host_pair_us": 0.5, "pair_cpu_us": 1.0, "host_pair_cpu_us": 0.5, "batch_1": 10.0,
               "host_1": 20.0, "batch_2": 18.0, "host_2": 36.0, "batch_cpu_ms": 5.0, "host_cpu_ms": 4.0,
               "study_s": 50.0, "study_cpu_s": 90.0, "study_mb": 600.0, "board_cold_s": 21.5, "board_cold_cpu_s": 33.0,
               "board_cold_mb": 700.0, "board_warm_s": 12.25, "board_warm_cpu_s": 20.0, "board_warm_mb": 650.0}
    lines = []
    _print(figures, 240, 20.0, 1e-3, 3, 10_000, None, lines.append)
    assert lines[-1] == ("full board on the native FMUs (crane-fmu compare --workers 2): cold 21.5 s (33.0 CPU-s), "
                         "warm 12.2 s (20.0 CPU-s), peak memory 700 MB  (target: cold <= 10 s)")
