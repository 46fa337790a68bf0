"""Benchmark: microseconds per communication step, crane pair against the framework floor.

The floor is the same master driving two trivial pythonfmu FMUs with the crane
pair's 6+1 connected signals (``fmu_src/trivial_*.py``). Both pairs are built
fresh, run alternately in the same process, record every step to a CSV file,
and are timed from initialisation to the last step (loading excluded).
"""

import statistics
import tempfile
import time
from pathlib import Path

from build_scripts.build_fmus import BENCH_FMUS, CRANE_FMUS, build_all
from crane_fmu.cosim import CRANE_CONNECTIONS, CsvRecorder, FmuInstance, Master
from crane_fmu.cosim.master import communication_points


def _timed_run(fmus, stop_time, step, csv_path):
    instances = {name: FmuInstance(path, name) for name, path in fmus.items()}
    try:
        recorder = CsvRecorder(csv_path)
        master = Master(instances, CRANE_CONNECTIONS)
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
        built = {p.stem: p for p in build_all(tmp / "fmus", CRANE_FMUS + BENCH_FMUS)}
        pairs = {
            "crane": {"plant": built["CranePlant"], "controller": built["BacksteppingController"]},
            "floor": {"plant": built["TrivialPlant"], "controller": built["TrivialController"]},
        }
        times = {name: [] for name in pairs}
        for _ in range(repeat):  # alternate, so drifts in machine load hit both
            for name, fmus in pairs.items():
                elapsed, n = _timed_run(fmus, stop_time, step, tmp / f"{name}.csv")
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
