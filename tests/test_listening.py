"""Nothing the project runs listens beyond this machine unless asked (issue 50): the listening sockets of every
process of `sweep`, `compare` and `serve` (and the processes they start: the Dask scheduler, nannies and
workers), read with psutil while they run. Each command is stopped by the test (its process group killed) once
its cluster has been seen, or at its end."""

import os
import signal
import subprocess
import sys
import time

import psutil
import pytest

from crane_fmu.serve import is_loopback

STUDY = "stop_time = 2.0\nstep = 0.01\n[parameters]\n\"plant.theta1_0\" = [0.0349, 0.0873, 0.1745, 0.2, 0.25, 0.3]\n"


def _listening(command, settle=3.0, limit=120.0):
    """``{(address, port)}`` every process of ``command``'s tree listened on while it ran: polled until some
    socket has been seen for ``settle`` s (the cluster up) or the command ended; then its group is killed."""
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    seen, first, ends = set(), None, time.monotonic() + limit
    try:
        while proc.poll() is None and time.monotonic() < ends:
            try:
                tree = [psutil.Process(proc.pid), *psutil.Process(proc.pid).children(recursive=True)]
            except psutil.NoSuchProcess:
                break
            for p in tree:
                try:
                    seen |= {(c.laddr.ip, c.laddr.port) for c in p.net_connections(kind="inet")
                             if c.status == psutil.CONN_LISTEN}
                except psutil.NoSuchProcess:
                    pass
            if seen and first is None:
                first = time.monotonic()
            if first is not None and time.monotonic() - first > settle:
                break
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(30)
    return seen


@pytest.mark.parametrize("kind", ["sweep", "compare", "serve"])
def test_every_listening_socket_is_on_loopback(fmu_dir, tmp_path, kind):
    """On main the Dask dashboard of sweep and compare listened on 0.0.0.0 at a random port. (compare runs on a local
    Dask cluster when --dashboard is given, else in a process pool that listens nowhere.)"""
    (tmp_path / "s.toml").write_text(STUDY)
    base = [sys.executable, "-m", "crane_fmu"]
    command = {
        "sweep": [*base, "sweep", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o"), "--workers", "2",
                  "--fmu-dir", str(fmu_dir), "--no-progress"],
        "compare": [*base, "compare", "--quick", "--out", str(tmp_path / "board"), "--workers", "2", "--fmu-dir",
                    str(fmu_dir), "--no-progress", "--dashboard", "127.0.0.1:0"],
        "serve": [*base, "serve", "--system", "lqr", "--external", "controller", "--lock-step", "--opcua",
                  "127.0.0.1:0", "--modbus", "127.0.0.1:0", "--fmu-dir", str(fmu_dir), "--out",
                  str(tmp_path / "serve.csv")],
    }[kind]
    seen = _listening(command)
    assert seen, f"{kind}: no listening socket seen (nothing to check)"
    wide = sorted(s for s in seen if not is_loopback(s[0]))
    assert wide == [], f"{kind} listens beyond loopback: {wide}"
    if kind != "serve":  # scheduler, dashboard, two nannies, two workers
        assert len(seen) >= 4, seen


def test_the_dashboard_option_is_checked_in_one_line(capsys):
    from crane_fmu.cli import main

    assert main(["sweep", "s.toml", "--out", "o", "--dashboard", "127.0.0.1:99999"]) == 2
    assert "--dashboard '127.0.0.1:99999': expected HOST:PORT" in capsys.readouterr().err
    assert main(["compare", "--out", "o", "--dashboard", ":8787", "--scheduler", "tcp://127.0.0.1:8786"]) == 2
    assert "--dashboard and --scheduler exclude each other" in capsys.readouterr().err
