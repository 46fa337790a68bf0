"""What the benchmark compares is comparable: its plain Python loop computes what the master does."""

import sys

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.bench import _plain_loop
from crane_fmu.cosim import CsvRecorder, read_csv, simulate


def test_plain_loop_records_the_masters_numbers(crane_fmus, connections, tmp_path):
    """The FMI tax is measured against the same models, the same values and the same CSV."""
    paper = systems.get("paper")
    _plain_loop(paper, 1.0, 1e-3, tmp_path / "plain.csv")
    simulate(crane_fmus, connections, 1.0, 1e-3, recorder=CsvRecorder(tmp_path / "master.csv"),
             parameters=paper.parameters)
    plain, master = read_csv(tmp_path / "plain.csv"), read_csv(tmp_path / "master.csv")
    assert list(plain) == list(master)
    for name in master:
        assert np.array_equal(plain[name], master[name]), name


def test_derivative_bench_prints_the_cost_of_the_native_derivatives():
    """A short run: each figure measured, of the model's C functions and through the FMU's FMI 2.0 interface; the
    whole Jacobian (13 directional derivatives) dearer than one."""
    from crane_fmu.bench_native import run_derivative_bench
    from crane_fmu.build_scripts.native import NativeUnavailable, compilers

    try:
        compilers()
    except NativeUnavailable as exc:
        pytest.skip(f"a C compiler: {exc}")
    lines = []
    figures = run_derivative_bench(evaluations=20000, repeat=1, out=lines.append)
    assert all(value > 0 for value in figures.values())
    assert figures["jacobian_us"] > figures["directional_us"]
    assert figures["fmi_jacobian_us"] > figures["fmi_directional_us"]  # through the FMU's FMI 2.0 calls
    assert "through FMI 2.0" in lines[-2] and "the whole Jacobian" in lines[-1]


def test_realtime_bench_prints_the_loops_lateness_and_the_protocols_round_trips(fmu_dir):
    """A short run on the run's FMUs: each pacing figure and each round trip measured, its p99 no less than its
    median. Which round trip is the longer is the benchmark's figure, not asserted here: on a loaded machine the
    ordering of two medians of 20 trips flips."""
    pytest.importorskip("asyncua", reason="the serve extra (asyncua)")
    from crane_fmu.bench_realtime import run_realtime_bench

    lines = []
    figures = run_realtime_bench(seconds=0.1, round_trips=20, out=lines.append, fmu_dir=fmu_dir)
    assert figures["loop_1ms"]["cycles"] == 100 and figures["loop_10ms"]["cycles"] == 10, figures
    for protocol in ("OPC UA", "Modbus TCP"):
        for median, p99 in (figures[f"{protocol}_write_read"], figures[f"{protocol}_cycle"]):
            assert 0 < median <= p99, (protocol, lines)
    assert any("lateness p50" in line and "real-time factor" in line for line in lines), lines


def test_the_spatial_benchmarks_planned_pairs_move_the_trolley_alike(fmu_dir):
    """``bench --spatial``'s planned pairs (crane_fmu/bench_spatial.py), 3 s on the run's FMUs: the planner's
    ddx_ref drives each plant's first axis, so the trolley's x and dx are the same in both (the drive integrates
    the demand whatever the swing), while the spatial plant swings out of the plane."""
    from crane_fmu.bench_spatial import PLANAR, SPATIAL, planned_pair
    from crane_fmu.cosim import run

    planar, spatial = (run(planned_pair(p, 1e-3, 3.0), fmu_dir).columns() for p in (PLANAR, SPATIAL))
    for name in ("x", "dx"):
        assert np.abs(planar[f"plant.{name}"] - spatial[f"plant.{name}"]).max() <= 1e-12, name
    assert planar["plant.x"][-1] > 1.5 and np.abs(spatial["plant.theta1y"]).max() > 0.08


def test_a_timed_command_counts_the_cpu_of_the_processes_it_leaves(tmp_path):
    """A board's fork server outlives the board's process, with its workers' CPU time: it is counted (Linux)."""
    if not sys.platform.startswith("linux"):
        pytest.skip("orphans are adopted on Linux only")
    from crane_fmu.bench_batch import timed_process

    used = tmp_path / "cpu"  # the orphan's own CPU seconds, written as it ends
    orphan = (f"import time\nwhile time.process_time() < 0.3: pass\n"
              f"open({str(used)!r}, 'w').write(repr(time.process_time()))")
    leaving = f"import subprocess, sys; subprocess.Popen([sys.executable, '-c', {orphan!r}])"  # ends at once
    _, _, cpu = timed_process([sys.executable, "-c", leaving])
    assert float(used.read_text()) <= cpu
