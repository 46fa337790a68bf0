"""``crane-fmu bench --native``: the native FMUs' speed, next to the benchmark's fixed anchor.

Medians of ``repeat`` alternating runs, 20 s at h = 1 ms by default:

1. the native plant with the Python BacksteppingController FMU through our master, CSV of every step;
2. the native pair (plant and BacksteppingController) through our master, CSV of every step;
3. the native pair in the C host (``fmu_src/native/host.c pair-bench``), the two FMUs exchanged by
   value references at each step, no recording; beside it the native plant closed by the paper's
   law written in C in the host (``bench``);
4. the whole ``crane-fmu simulate --fmu-dir build/native`` process (the paper system: both native)
   against the anchor's whole process (:data:`crane_fmu.bench.ANCHOR_LOOP`).
"""

import shutil
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


def _unpack(folder, native, name):
    """A native FMU's Linux library unpacked into ``folder``, and its GUID: ``[library, guid]``."""
    with zipfile.ZipFile(native / f"{name}.fmu") as z:
        z.extract(f"binaries/linux64/{name}.so", folder)
        guid = z.read("modelDescription.xml").decode().split('guid="', 1)[1].split('"', 1)[0]
    return [str(folder / "binaries" / "linux64" / f"{name}.so"), guid]


def _c_host(folder, native):
    """The compiled C host and the ``[library, guid]`` of the native plant and controller unpacked into ``folder``."""
    host = folder / "host"
    subprocess.run([compilers()["linux"], "-O2", "-ffp-contract=off", f"-I{fmi_headers()}", f"-I{NATIVE}",
                    str(NATIVE / "host.c"), "-o", str(host), "-ldl", "-lpthread", "-lm"], check=True)
    return host, _unpack(folder, native, "CranePlant"), _unpack(folder, native, "BacksteppingController")


def run_native_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the native benchmark, print its figures and return them."""
    n = communication_points(0.0, stop_time, step)
    with tempfile.TemporaryDirectory(prefix="crane_bench_native_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        build_all(built, ["CranePlant", "BacksteppingController"], systems=(), fmi3=False, native=True,
                  log=lambda _: None)
        native = native_dir(built)
        mixed = tmp / "mixed"  # the native plant with the Python controller
        mixed.mkdir()
        shutil.copy(native / "CranePlant.fmu", mixed)
        shutil.copy(built / "BacksteppingController.fmu", mixed)
        anchor = [str(p) for p in build_anchor(tmp / "anchor")]
        host, plant_lib, controller_lib = _c_host(tmp, native)
        paper = systems.at_step(systems.get("paper"), native, step)
        command = Path(sys.executable).parent / "crane-fmu"
        command = [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]
        simulate = [*command, "simulate", "--fmu-dir", str(native), "--stop-time", repr(stop_time), "--step",
                    repr(step), "--out", str(tmp / "process.csv")]
        anchor_loop = [sys.executable, "-c", ANCHOR_LOOP, *anchor, str(n), repr(step)]
        times = {name: [] for name in ("with_python", "pair_csv", "c_host_pair", "c_host_law", "process",
                                       "anchor_process")}
        for _ in range(repeat):  # alternate, so drifts in machine load hit all
            with_python = systems.at_step(systems.get("paper"), mixed, step)
            times["with_python"].append(_timed_run(with_python, mixed, stop_time, step, tmp / "mixed.csv")[0] / n)
            times["pair_csv"].append(_timed_run(paper, native, stop_time, step, tmp / "pair.csv")[0] / n)
            for name, args in (("c_host_pair", ["pair-bench", *plant_lib, *controller_lib]),
                               ("c_host_law", ["bench", *plant_lib])):
                done = subprocess.run([str(host), *args, str(n), repr(step)], check=True, capture_output=True,
                                      text=True)
                times[name].append(float(done.stdout))
            times["process"].append(_process_seconds(simulate))
            times["anchor_process"].append(_process_seconds(anchor_loop))
    med = {name: statistics.median(t) for name, t in times.items()}
    figures = {"steps": n, "with_python_us": 1e6 * med["with_python"], "pair_csv_us": 1e6 * med["pair_csv"],
               "c_host_pair_us": 1e6 * med["c_host_pair"], "c_host_law_us": 1e6 * med["c_host_law"],
               "process_s": med["process"], "anchor_process_s": med["anchor_process"],
               "process_ratio": med["process"] / med["anchor_process"]}
    out(f"{n} steps of h = {step:g} s, medians of {repeat} alternating runs")
    out(f"1. native plant + Python BacksteppingController FMU, our master, CSV: "
        f"{figures['with_python_us']:6.2f} us/step")
    out(f"2. native pair (plant + controller), our master, CSV of every step:  {figures['pair_csv_us']:6.2f} us/step"
        "  (target <= 4)")
    out(f"3. native pair in the C host, exchanged by value references, no recording: "
        f"{figures['c_host_pair_us']:6.3f} us/step  (target <= 0.5); the plant with the law in the host: "
        f"{figures['c_host_law_us']:.3f}")
    out(f"4. whole processes: crane-fmu simulate --fmu-dir build/native (paper, both native) {med['process']:.2f} s, "
        f"anchor {med['anchor_process']:.2f} s: ratio {figures['process_ratio']:.2f}  (target <= 1.0)")
    return figures


def run_derivative_bench(evaluations=1_000_000, repeat=5, out=print):
    """The cost of the native plant's Model Exchange derivatives, medians of ``repeat`` runs of a C loop.

    ``fmu_src/native/derivative_bench.c`` calls the model's C functions (no FMI layer) at Section V's
    plant swinging: the derivatives, one directional derivative (with the derivatives), and the
    whole Jacobian (one per state and input); microseconds per evaluation.
    """
    with tempfile.TemporaryDirectory(prefix="crane_bench_derivatives_") as tmp:
        program = Path(tmp) / "derivative_bench"
        subprocess.run([compilers()["linux"], "-O2", "-ffp-contract=off", f"-I{NATIVE}",
                        *(str(NATIVE / f) for f in ("derivative_bench.c", "plant_continuous.c", "plant_equations.c")),
                        "-o", str(program), "-lm"], check=True)
        runs = [subprocess.run([str(program), str(evaluations)], check=True, capture_output=True,
                               text=True).stdout.split() for _ in range(repeat)]
    names = ("derivatives_us", "directional_us", "jacobian_us")
    figures = {name: statistics.median(float(r[i]) for r in runs) for i, name in enumerate(names)}
    out(f"native CranePlant, Model Exchange, the model's C functions ({evaluations} evaluations, medians of {repeat} "
        f"runs):")
    out(f"  derivatives {figures['derivatives_us']:.3f} us; with one directional derivative "
        f"{figures['directional_us']:.3f} us; the whole Jacobian (13 directional derivatives) "
        f"{figures['jacobian_us']:.3f} us")
    return figures
