"""``crane-fmu bench --native``: the native CranePlant FMU's speed, next to the benchmark's fixed anchor.

Medians of ``repeat`` alternating runs, 20 s at h = 1 ms by default:

1. the native plant with the Python BacksteppingController FMU through our master, CSV of every step;
2. the native plant alone (the free swing) through our master, CSV of every step: there is no
   native controller yet (issue 27), so this stands where the native pair would;
3. the native plant in the C host (``fmu_src/native/host.c``), closed by the paper's law written
   in C in the host, no recording: what a C tool pays per step for the plant;
4. the whole ``crane-fmu simulate --fmu-dir build/native`` process (the paper system: native plant,
   Python controller) and that of ``--system free`` (the native plant alone) against the anchor's
   whole process (:data:`crane_fmu.bench.ANCHOR_LOOP`).
"""

import statistics
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from crane_fmu import systems
from crane_fmu.bench import ANCHOR_LOOP, _process_seconds, _timed_run, build_anchor
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.build_scripts.native import NATIVE, compilers, native_dir
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cosim.master import communication_points


def _c_host(folder, native):
    """The compiled C host and the native plant's ``(library, guid)`` unpacked into ``folder``."""
    host = folder / "host"
    subprocess.run([compilers()["linux"], "-O2", "-ffp-contract=off", f"-I{fmi_headers()}", f"-I{NATIVE}",
                    str(NATIVE / "host.c"), "-o", str(host), "-ldl", "-lpthread", "-lm"], check=True)
    with zipfile.ZipFile(native / "CranePlant.fmu") as z:
        z.extract("binaries/linux64/CranePlant.so", folder)
        guid = z.read("modelDescription.xml").decode().split('guid="', 1)[1].split('"', 1)[0]
    return host, folder / "binaries" / "linux64" / "CranePlant.so", guid


def run_native_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the native benchmark, print its figures and return them."""
    n = communication_points(0.0, stop_time, step)
    with tempfile.TemporaryDirectory(prefix="crane_bench_native_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        build_all(built, ["CranePlant", "BacksteppingController"], systems=(), fmi3=False, native=True,
                  log=lambda _: None)
        native = native_dir(built)
        anchor = [str(p) for p in build_anchor(tmp / "anchor")]
        host, library, guid = _c_host(tmp, native)
        paper, free = (systems.at_step(systems.get(name), native, step) for name in ("paper", "free"))
        command = Path(sys.executable).parent / "crane-fmu"
        command = [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]
        simulate = [*command, "simulate", "--fmu-dir", str(native), "--stop-time", repr(stop_time), "--step",
                    repr(step), "--out", str(tmp / "process.csv")]
        simulate_free = [*simulate, "--system", "free"]
        anchor_loop = [sys.executable, "-c", ANCHOR_LOOP, *anchor, str(n), repr(step)]
        times = {name: [] for name in ("with_python", "plant_csv", "c_host", "process", "free_process",
                                       "anchor_process")}
        for _ in range(repeat):  # alternate, so drifts in machine load hit all
            times["with_python"].append(_timed_run(paper, native, stop_time, step, tmp / "pair.csv")[0] / n)
            times["plant_csv"].append(_timed_run(free, native, stop_time, step, tmp / "plant.csv")[0] / n)
            done = subprocess.run([str(host), "bench", str(library), guid, str(n), repr(step)], check=True,
                                  capture_output=True, text=True)
            times["c_host"].append(float(done.stdout))
            times["process"].append(_process_seconds(simulate))
            times["free_process"].append(_process_seconds(simulate_free))
            times["anchor_process"].append(_process_seconds(anchor_loop))
    med = {name: statistics.median(t) for name, t in times.items()}
    figures = {"steps": n, "with_python_us": 1e6 * med["with_python"], "plant_csv_us": 1e6 * med["plant_csv"],
               "c_host_us": 1e6 * med["c_host"], "process_s": med["process"], "anchor_process_s": med["anchor_process"],
               "process_ratio": med["process"] / med["anchor_process"], "free_process_s": med["free_process"],
               "free_process_ratio": med["free_process"] / med["anchor_process"]}
    out(f"{n} steps of h = {step:g} s, medians of {repeat} alternating runs")
    out(f"1. native plant + Python BacksteppingController FMU, our master, CSV: "
        f"{figures['with_python_us']:6.2f} us/step")
    out(f"2. native plant alone (free swing), our master, CSV of every step:    {figures['plant_csv_us']:6.2f} us/step"
        "  (no native controller yet: the native pair is not measured; its target is <= 4)")
    out(f"3. native plant in the C host, the paper's law in C, no recording:   {figures['c_host_us']:6.3f} us/step"
        "  (the native pair's target is <= 0.5)")
    out(f"4. whole processes: crane-fmu simulate --fmu-dir build/native {med['process']:.2f} s (paper), "
        f"{med['free_process']:.2f} s (--system free), anchor {med['anchor_process']:.2f} s: ratios "
        f"{figures['process_ratio']:.2f} and {figures['free_process_ratio']:.2f}  (target <= 1.0)")
    return figures
