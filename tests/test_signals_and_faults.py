"""A run ended by a signal or met with a broken FMU says so in one line and keeps what it wrote (issues 49, 50).

The runs are `crane-fmu simulate` processes on the Python FMUs (conftest.fmu_dir), as a user starts them; every
process is waited for with a timeout and killed if it does not end.
"""

import _ctypes
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

from crane_fmu.cosim import read_csv
from crane_fmu.cosim.binary_check import check_library


def _simulate(fmu_dir, out, *args):
    return subprocess.Popen([sys.executable, "-m", "crane_fmu", "simulate", "--fmu-dir", str(fmu_dir), "--out",
                             str(out), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _rows_written(partial, timeout=60):
    """Wait until the run's partial file holds some rows (its first chunk of 2048 has been written)."""
    ends = time.monotonic() + timeout
    while time.monotonic() < ends:
        if partial.exists() and partial.stat().st_size > 100_000:
            return
        time.sleep(0.02)
    raise AssertionError(f"{partial} never grew")


@pytest.mark.parametrize("signum, delay", [(signal.SIGINT, 0.0), (signal.SIGINT, 0.3), (signal.SIGINT, 0.7),
                                           (signal.SIGTERM, 0.0), (signal.SIGTERM, 0.5), (signal.SIGHUP, 0.3)],
                         ids=["SIGINT-1", "SIGINT-2", "SIGINT-3", "SIGTERM-1", "SIGTERM-2", "SIGHUP"])
def test_a_signal_ends_simulate_in_one_line_and_keeps_the_rows(fmu_dir, tmp_path, signum, delay):
    """Ctrl-C (SIGINT), SIGTERM or SIGHUP (the terminal closed) in the middle of a long run on the Python FMUs, at
    several moments: exit 130, 143 or 129, one line on stderr naming the signal and the file, the rows so far in
    run.cut-short.csv with a trailer naming the signal (no FMU blamed), no .partial left, no run.csv (it would claim a
    whole run). SIGHUP left the .partial (tens of MB) on main."""
    out = tmp_path / "run.csv"
    proc = _simulate(fmu_dir, out, "--system", "lqr", "--stop-time", "2000")
    try:
        _rows_written(Path(str(out) + ".partial"))
        time.sleep(delay)
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    cut = tmp_path / "run.cut-short.csv"
    name = signal.Signals(signum).name
    assert (proc.returncode, err) == (128 + signum, f"crane-fmu: interrupted ({name}); the rows so far are in {cut}\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.cut-short.csv"]
    assert cut.read_text().splitlines()[-1] == f"# run cut short: interrupted ({name})"
    times = read_csv(cut)["time"]
    assert len(times) > 2048 and all(b > a for a, b in zip(times, times[1:]))


def _truncated_copy(fmu, folder, library):
    """``fmu`` copied into ``folder`` with the shared library whose name ends with ``library`` cut to half."""
    copy = Path(folder) / Path(fmu).name
    with zipfile.ZipFile(fmu) as z, zipfile.ZipFile(copy, "w") as out:
        for info in z.infolist():
            data = z.read(info)
            if info.filename.endswith(library):
                data = data[:len(data) // 2]
            out.writestr(info, data)
    return copy


@pytest.mark.parametrize("library", ["LqrController.so", "PythonWrapper.so"])
def test_an_fmu_with_a_truncated_binary_is_one_line(fmu_dir, tmp_path, library):
    """On main a truncated library was loaded and crashed the process: "Bus error", status 135, no message, a
    0-byte .partial. Now: status 2, one line naming the FMU file and the library, nothing written."""
    broken = _truncated_copy(Path(fmu_dir) / "LqrController.fmu", tmp_path, library)
    out = tmp_path / "r.csv"
    proc = _simulate(fmu_dir, out, "--system", "lqr", "--stop-time", "1", "--use", f"controller={broken}")
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, err
    assert err.count("\n") == 1 and str(broken) in err and f"its binary {library} is truncated" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == [broken.name]


@pytest.mark.quick
def test_the_library_check_refuses_every_cut_of_a_real_library(tmp_path):
    """An ELF library cut anywhere (inside its headers, its segments or its section table) is refused in one line;
    the whole one passes. The library is one of this Python's own extension modules."""
    whole = Path(_ctypes.__file__)
    check_library(whole)
    data = whole.read_bytes()
    for cut in (0, 3, 40, 63, 1000, len(data) // 3, len(data) // 2, len(data) - 1):
        part = tmp_path / f"cut{cut}.so"
        part.write_bytes(data[:cut])
        with pytest.raises(ValueError, match=r"is truncated \(\d+ bytes, its headers need \d+\)"):
            check_library(part)
    shutil.copy(whole, tmp_path / "copy.so")
    check_library(tmp_path / "copy.so")


# --- a run that cannot write: a file-size limit (ulimit -f) or a full disk (issue 50) ---


def _file_size_limit(limit):
    import resource

    return lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


@pytest.fixture
def small_disk(tmp_path):
    """A 128 KiB tmpfs at ``tmp_path/small``: a disk that fills (root's mount; skips, saying so, where it is not
    permitted)."""
    folder = tmp_path / "small"
    folder.mkdir()
    mount = shutil.which("mount")
    done = subprocess.run([mount or "mount", "-t", "tmpfs", "-o", "size=128k", "tmpfs", str(folder)],
                          capture_output=True, text=True) if mount else None
    if done is None or done.returncode != 0:
        pytest.skip(f"mount -t tmpfs not permitted here ({done.stderr.strip() if done else 'no mount'}): no full disk")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], capture_output=True)


def _whole_rows(cut):
    """The rows of a .cut-short.csv: every line whole (the same number of fields), times increasing."""
    lines = cut.read_text().splitlines()
    rows = [line for line in lines[1:] if not line.startswith("#")]
    width = lines[0].count(",")
    assert all(line.count(",") == width for line in rows)
    times = [float(line.split(",", 1)[0]) for line in rows]
    assert all(b > a for a, b in zip(times, times[1:]))
    return rows


@pytest.mark.parametrize("fault", ["ulimit -f", "full disk"])
def test_simulate_that_cannot_write_says_so_and_keeps_the_rows(fmu_dir, tmp_path, fault, request):
    """A file-size limit of 1 MB (RLIMIT_FSIZE, as `ulimit -f` sets it) or a disk of 128 KiB in the middle of a
    20 s run: exit 1, one line naming the file and the reason, the whole rows written before it in
    run.cut-short.csv (a torn last line cut off), no .partial, no run.csv."""
    if fault == "full disk":
        folder, limit = request.getfixturevalue("small_disk"), None
        reason = "No space left on device"
    else:
        folder, limit = tmp_path / "out", 1_000_000
        reason = "File too large"
    out = folder / "run.csv"
    done = subprocess.run([sys.executable, "-m", "crane_fmu", "simulate", "--fmu-dir", str(fmu_dir), "--system", "lqr",
                           "--out", str(out)], capture_output=True, text=True, timeout=300,
                          preexec_fn=_file_size_limit(limit) if limit else None)
    cut = folder / "run.cut-short.csv"
    assert (done.returncode, done.stderr) == (
        1, f"crane-fmu: cannot write {out}: {reason}; the rows written before are in {cut}\n")
    assert sorted(p.name for p in folder.iterdir()) == ["run.cut-short.csv"]
    assert len(_whole_rows(cut)) > 100


@pytest.mark.parametrize("command", ["sweep", "compare"])
def test_sweep_and_compare_on_a_full_disk_say_so_and_keep_the_finished_cases(fmu_dir, tmp_path, small_disk, command):
    """Their results folder on a disk of 128 KiB that fills while the cases are recorded: exit 1, one line, and the
    journal keeps every case recorded before (whole JSON lines, a torn last one aside: a re-run resumes)."""
    import json

    (tmp_path / "s.toml").write_text("stop_time = 1.0\nstep = 0.01\n[parameters]\n\"plant.theta1_0\" = ["
                                     + ", ".join(f"{0.01 * k:.2f}" for k in range(1, 1201)) + "]\n")
    out = small_disk / "o"
    argv = {"sweep": ["sweep", str(tmp_path / "s.toml")], "compare": ["compare", "--quick"]}[command]
    done = subprocess.run([sys.executable, "-m", "crane_fmu", *argv, "--out", str(out), "--workers", "2",
                           "--fmu-dir", str(fmu_dir), "--no-progress"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 1, done.stderr[-2000:]
    assert done.stderr.count("\n") == 1 and "No space left on device" in done.stderr, done.stderr[-2000:]
    journal = out / ("quick" if command == "compare" else "") / "cases.jsonl"
    lines = journal.read_text().split("\n")
    kept = [json.loads(line) for line in lines[:-1]]  # every line but a torn last one
    assert kept and all("case_id" in row for row in kept)
