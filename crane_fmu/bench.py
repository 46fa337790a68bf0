"""Benchmark: microseconds per communication step, crane pair against the framework floor.

The floor is the same master driving two trivial pythonfmu FMUs with the crane
pair's 6+1 connected signals (``crane_fmu/model/benchmark.py``). Both pairs are
built fresh, run alternately in the same process, record every step to a CSV
file, and are timed from initialisation to the last step (loading excluded).
"""

import os
import statistics
import tempfile
import time
from pathlib import Path

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.cosim import CsvRecorder, Master, System, open_instance
from crane_fmu.cosim.master import communication_points

FLOOR = System("floor", {"plant": "TrivialPlant", "controller": "TrivialController"},
               description="the benchmark floor: the crane pair's signals, next to no computation")


def _open(system, fmu_dir):
    """``(instances, connections)`` of a system, instantiated."""
    fmus, connections = system.resolve(fmu_dir)
    return {name: open_instance(path, name) for name, path in fmus.items()}, connections


def _timed_run(system, fmu_dir, stop_time, step, csv_path):
    instances, connections = _open(system, fmu_dir)
    try:
        recorder = CsvRecorder(csv_path)
        master = Master(instances, connections)
        start = time.perf_counter()
        n = master.run(0.0, stop_time, step, [recorder])
        recorder.close()
        elapsed = time.perf_counter() - start
        master.terminate()
    finally:
        for inst in instances.values():
            inst.free()
    return elapsed, n


def run_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the benchmark and print its figures; return them as a dict."""
    communication_points(0.0, stop_time, step)
    with tempfile.TemporaryDirectory(prefix="crane_bench_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        paper = systems.get("paper")
        build_all(built, set(paper.instances.values()) | set(FLOOR.instances.values()), systems=(), fmi3=False,
                  log=lambda _: None)
        pairs = {"crane": paper, "floor": FLOOR}
        times = {name: [] for name in pairs}
        for _ in range(repeat):  # alternate, so drifts in machine load hit both
            for name, system in pairs.items():
                elapsed, n = _timed_run(system, built, stop_time, step, tmp / f"{name}.csv")
                times[name].append(elapsed)
    med = {name: statistics.median(t) for name, t in times.items()}
    us = {name: 1e6 * m / n for name, m in med.items()}
    figures = {
        "steps": n,
        "crane_us_per_step": us["crane"],
        "floor_us_per_step": us["floor"],
        "ratio": us["crane"] / us["floor"],
        "realtime_factor": stop_time / med["crane"],
    }
    out(f"{n} steps of h = {step:g} s, median of {repeat} runs each, recording every step to CSV")
    out(f"crane pair (CranePlant + BacksteppingController): {us['crane']:8.1f} us/step")
    out(f"framework floor (two trivial pythonfmu FMUs):     {us['floor']:8.1f} us/step")
    out(f"ratio crane / floor: {figures['ratio']:.2f}  (target <= 1.5)")
    out(f"paper scenario ({stop_time:g} s): {med['crane']:.3f} s wall, "
        f"{figures['realtime_factor']:.1f}x faster than real time  (target >= 25)")
    return figures


def run_sweep_bench(n_cases=16, stop_time=10.0, step=1e-3, out=print):
    """Cases per second of a sweep on a local Dask cluster with 1 and with 2 workers.

    Each cluster is started and warmed up (one case per worker) before the
    clock starts. The per-case overhead is the wall time per case with one
    worker minus the mean time the case itself took inside the worker.
    """
    from distributed import Client, LocalCluster

    from crane_fmu.sweep import spec
    from crane_fmu.sweep.runner import run_case, shippable

    study = spec.parse({"stop_time": stop_time, "step": step, "metrics": ["outcome", "max_theta1_deg"]})
    settings, metrics = study.settings(), study.metrics
    cases = [{"plant.theta1_0": 0.01 * (1 + i % 8), "controller.w_theta2": 0.0} for i in range(n_cases)]
    figures = {}
    with tempfile.TemporaryDirectory(prefix="crane_bench_") as tmp:
        paper = systems.get("paper")
        build_all(Path(tmp) / "fmus", paper.instances.values(), systems=(), fmi3=False, log=lambda _: None)
        system = shippable(paper, Path(tmp) / "fmus")
        for workers in (1, 2):
            with LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None,
                              silence_logs=50) as cluster, Client(cluster) as client:
                shipped = client.scatter([system], broadcast=True)[0]
                client.gather(client.map(run_case, cases[:workers], settings=settings, system=shipped,
                                         metric_names=metrics, pure=False))
                start = time.perf_counter()
                rows = client.gather(client.map(run_case, cases, settings=settings, system=shipped,
                                                metric_names=metrics, pure=False))
                figures[workers] = (time.perf_counter() - start, rows)
    wall1, rows1 = figures[1]
    wall2, _ = figures[2]
    case_time = statistics.mean(r["duration_s"] for r in rows1)
    result = {
        "cases_per_s_1": n_cases / wall1,
        "cases_per_s_2": n_cases / wall2,
        "efficiency": wall1 / (2 * wall2),
        "case_s": case_time,
        "overhead_fraction": (wall1 / n_cases - case_time) / case_time,
    }
    out(f"{n_cases} cases of {stop_time:g} s at h = {step:g} s (crane pair), local Dask cluster")
    out(f"1 worker:  {result['cases_per_s_1']:.2f} cases/s")
    out(f"2 workers: {result['cases_per_s_2']:.2f} cases/s")
    out(f"parallel efficiency on 2 workers: {100 * result['efficiency']:.0f} %  (target >= 85 %)")
    out(f"per-case overhead of shipping work to a worker: {1e3 * (wall1 / n_cases - case_time):.1f} ms "
        f"= {100 * result['overhead_fraction']:.1f} % of a case's {case_time:.3f} s  (target < 10 %)")
    return result


def run_controllers(quick=False, out=print):
    """Build every controller's FMUs fresh and measure them against their targets."""
    from crane_fmu.analysis.controller_bench import run_controller_bench

    with tempfile.TemporaryDirectory(prefix="crane_bench_") as tmp:
        build_all(Path(tmp) / "fmus", systems=(), fmi3=False, log=lambda _: None)
        return run_controller_bench(Path(tmp) / "fmus", quick, out=out)


def _rss_mb():
    """Resident memory of this process [MB] (Linux /proc)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


class _MemoryProbe:
    """Observer sampling the process's resident memory every ``every`` communication points."""

    def __init__(self, every):
        self.every, self.count, self.samples = every, 0, []

    def start(self, names):
        pass

    def observe(self, time, values):
        if self.count % self.every == 0:
            self.samples.append((time, _rss_mb()))
        self.count += 1


def run_endurance(stop_time=3600.0, step=1e-3, out=print):
    """One long closed-loop run recorded to CSV, sampling memory every simulated minute."""
    n = communication_points(0.0, stop_time, step)
    with tempfile.TemporaryDirectory(prefix="crane_endurance_") as tmp:
        built = Path(tmp) / "fmus"
        paper = systems.get("paper")
        build_all(built, paper.instances.values(), systems=(), fmi3=False, log=lambda _: None)
        instances, connections = _open(paper, built)
        probe = _MemoryProbe(max(1, round(60.0 / step)))
        csv_path = Path(tmp) / "endurance.csv"
        try:
            recorder = CsvRecorder(csv_path)
            master = Master(instances, connections)
            # the weighted law (1, 1, 0) converges, so the run stays finite for the whole hour
            start = time.perf_counter()
            master.run(0.0, stop_time, step, [recorder, probe], {"controller": {"w_theta2": 0.0}})
            recorder.close()
            wall = time.perf_counter() - start
        finally:
            for inst in instances.values():
                inst.free()
        size = csv_path.stat().st_size
    rss = [m for _, m in probe.samples]
    steady = rss[1:] or rss  # after the first simulated minute
    out(f"{n} steps ({stop_time:g} s at h = {step:g} s) in {wall:.1f} s wall, CSV of {size / 1e6:.0f} MB")
    out(f"resident memory: {rss[0]:.1f} MB at t = 0, {steady[0]:.1f} MB after 1 min, {rss[-1]:.1f} MB at the end, "
        f"largest {max(rss):.1f} MB: growth after the first minute {max(steady) - steady[0]:.1f} MB")
    return {"wall_s": wall, "rss_mb": probe.samples, "csv_mb": size / 1e6}
