"""``crane-fmu bench --native``: the native FMUs' speed, next to the benchmark's fixed anchor.

Medians of ``repeat`` alternating runs, 20 s at h = 1 ms by default:

1. the native plant with the Python BacksteppingController FMU through our master, CSV of every step;
2. the native pair (plant and BacksteppingController) through our master, CSV of every step; and on the batch path
   of sweeps and the board (:mod:`crane_fmu.native_batch`: instances reset, the outputs of the sweep's figures kept
   and the figures computed, no rows written);
3. the native pair in the C host (``fmu_src/host/host.c pair-bench``), the two FMUs exchanged by
   value references at each step, no recording;
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

from fmpy import read_model_description

from crane_fmu import components, systems
from crane_fmu.bench import ANCHOR_LOOP, _process_seconds, _timed_run, build_anchor
from crane_fmu.bench_batch import pair_per_step
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.build_scripts.native import (
    DERIVATIVE_BENCH,
    FMI_DERIVATIVE_BENCH,
    HOST,
    MODELS_DIR,
    build_native_fmu,
    compilers,
    native_dir,
)
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cosim.master import communication_points


def _unpack(folder, native, name):
    """A native FMU's Linux library unpacked into ``folder``, its GUID and the value references of its x and u:
    ``[library, guid], [x, u]``."""
    with zipfile.ZipFile(native / f"{name}.fmu") as z:
        z.extract(f"binaries/linux64/{name}.so", folder)
    md = read_model_description(str(native / f"{name}.fmu"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    axis = components.get("CranePlant").crane.axes[0]  # the benchmark's pair: the planar crane
    return [str(folder / "binaries" / "linux64" / f"{name}.so"), md.guid], [str(vr[axis.position]),
                                                                          str(vr[axis.demand])]


def _c_host(folder, native):
    """The compiled C host and its ``pair-bench`` arguments before STEPS (the native plant and controller unpacked
    into ``folder``) and after H (their value references)."""
    host = folder / "host"
    subprocess.run([compilers()["linux"], "-O2", "-ffp-contract=off", f"-I{fmi_headers()}", str(HOST), "-o",
                    str(host), "-ldl", "-lpthread", "-lm"], check=True)
    (plant, plant_vrs), (controller, controller_vrs) = (_unpack(folder, native, name)
                                                        for name in ("CranePlant", "BacksteppingController"))
    return host, [*plant, *controller], [*plant_vrs, *controller_vrs]


def run_native_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the native benchmark, print its figures and return them."""
    n = communication_points(0.0, stop_time, step)
    with tempfile.TemporaryDirectory(prefix="crane_bench_native_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        pair = ["CranePlant", "BacksteppingController"]
        build_all(built, pair, systems=(), fmi3=False, native=False, log=lambda _: None)
        native = native_dir(built)
        for name in pair:  # FMI 2.0, the Linux binary: all the benchmark runs
            build_native_fmu(components.get(name), native, 2, {"linux": compilers()["linux"]})
        mixed = tmp / "mixed"  # the native plant with the Python controller
        mixed.mkdir()
        shutil.copy(native / "CranePlant.fmu", mixed)
        shutil.copy(built / "BacksteppingController.fmu", mixed)
        anchor = [str(p) for p in build_anchor(tmp / "anchor")]
        host, libraries, vrs = _c_host(tmp, native)
        paper = systems.prepare(systems.get("paper"), step, stop_time)
        command = Path(sys.executable).parent / "crane-fmu"
        command = [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]
        simulate = [*command, "simulate", "--fmu-dir", str(native), "--stop-time", repr(stop_time), "--step",
                    repr(step), "--out", str(tmp / "process.csv")]
        anchor_loop = [sys.executable, "-c", ANCHOR_LOOP, *anchor, str(n), repr(step)]
        times = {name: [] for name in ("with_python", "pair_csv", "pair_batch", "c_host_pair", "process",
                                       "anchor_process")}
        for _ in range(repeat):  # alternate, so drifts in machine load hit all
            times["with_python"].append(_timed_run(paper, mixed, tmp / "mixed.csv")[0] / n)
            times["pair_csv"].append(_timed_run(paper, native, tmp / "pair.csv")[0] / n)
            times["pair_batch"].append(pair_per_step(native, stop_time, step)[0])
            done = subprocess.run([str(host), "pair-bench", *libraries, str(n), repr(step), *vrs], check=True,
                                  capture_output=True, text=True)
            times["c_host_pair"].append(float(done.stdout.split()[0]))
            times["process"].append(_process_seconds(simulate))
            times["anchor_process"].append(_process_seconds(anchor_loop))
    med = {name: statistics.median(t) for name, t in times.items()}
    figures = {"steps": n, "with_python_us": 1e6 * med["with_python"], "pair_csv_us": 1e6 * med["pair_csv"],
               "pair_batch_us": 1e6 * med["pair_batch"],
               "c_host_pair_us": 1e6 * med["c_host_pair"],
               "process_s": med["process"], "anchor_process_s": med["anchor_process"],
               "process_ratio": med["process"] / med["anchor_process"]}
    out(f"{n} steps of h = {step:g} s, medians of {repeat} alternating runs")
    out(f"1. native plant + Python BacksteppingController FMU, our master, CSV: "
        f"{figures['with_python_us']:6.2f} us/step")
    out(f"2. native pair (plant + controller), our master, CSV of every step:  {figures['pair_csv_us']:6.2f} us/step"
        "  (target <= 4)")
    out(f"   the same on the batch path (reset, the sweep's figures, no rows written): {figures['pair_batch_us']:6.3f} "
        f"us/step = {med['pair_batch'] / med['c_host_pair']:.2f}x the C host's  (target <= 2.0)")
    out(f"3. native pair in the C host, exchanged by value references, no recording: "
        f"{figures['c_host_pair_us']:6.3f} us/step  (target <= 0.5)")
    out(f"4. whole processes: crane-fmu simulate --fmu-dir build/native (paper, both native) {med['process']:.2f} s, "
        f"anchor {med['anchor_process']:.2f} s: ratio {figures['process_ratio']:.2f}  (target <= 1.0)")
    return figures


def run_derivative_bench(evaluations=1_000_000, repeat=5, out=print):
    """The cost of the native plant's Model Exchange derivatives, medians of ``repeat`` runs of C loops.

    ``fmu_src/host/derivative_bench.c`` calls the model's C functions (no FMI layer) at Section V's
    plant swinging: the derivatives, one directional derivative (with the derivatives), and the
    whole Jacobian (one per state and input); ``fmi_derivative_bench.c`` makes the same calls through
    the native CranePlant FMU's FMI 2.0 Model Exchange interface (states set, derivatives got; every
    derivative and output along one state; the Jacobian of the derivatives and outputs). Microseconds
    per evaluation.
    """
    tools = {"linux": compilers()["linux"], "windows": None}
    with tempfile.TemporaryDirectory(prefix="crane_bench_derivatives_") as tmp:
        program, fmi_program = Path(tmp) / "derivative_bench", Path(tmp) / "fmi_derivative_bench"
        subprocess.run([tools["linux"], "-O2", "-ffp-contract=off", f"-I{MODELS_DIR}", str(DERIVATIVE_BENCH),
                        *(str(MODELS_DIR / f) for f in ("plant_continuous.c", "plant_equations.c")),
                        "-o", str(program), "-lm"], check=True)
        subprocess.run([tools["linux"], "-O2", f"-I{fmi_headers()}", str(FMI_DERIVATIVE_BENCH), "-o",
                        str(fmi_program), "-ldl"], check=True)
        fmu = build_native_fmu(components.get("CranePlant"), Path(tmp), 2, tools)
        with zipfile.ZipFile(fmu) as z:
            library = Path(z.extract("binaries/linux64/CranePlant.so", tmp))
        md = read_model_description(str(fmu))
        inputs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
        outputs = [u.variable.valueReference for u in md.outputs]
        states = [d.variable.derivative.valueReference for d in md.derivatives]
        derivatives = [d.variable.valueReference for d in md.derivatives]
        arguments = [str(library), str(evaluations), *map(str, (len(states), len(inputs), len(outputs))),
                     *map(str, states + inputs + derivatives + outputs)]
        runs = [subprocess.run([str(program), str(evaluations)], check=True, capture_output=True,
                               text=True).stdout.split() for _ in range(repeat)]
        fmi_runs = [subprocess.run([str(fmi_program), *arguments], check=True, capture_output=True,
                                   text=True).stdout.split() for _ in range(repeat)]
    names = ("derivatives_us", "directional_us", "jacobian_us")
    figures = {name: statistics.median(float(r[i]) for r in runs) for i, name in enumerate(names)}
    figures.update({f"fmi_{name}": statistics.median(float(r[i]) for r in fmi_runs) for i, name in enumerate(names)})
    out(f"native CranePlant, Model Exchange ({evaluations} evaluations, medians of {repeat} runs):")
    out(f"  through FMI 2.0: states set and derivatives got {figures['fmi_derivatives_us']:.3f} us; one directional "
        f"derivative of the {len(derivatives)} derivatives and {len(outputs)} outputs "
        f"{figures['fmi_directional_us']:.3f} us; the whole Jacobian ({len(states) + len(inputs)} calls) "
        f"{figures['fmi_jacobian_us']:.3f} us")
    out(f"  the model's C functions: derivatives {figures['derivatives_us']:.3f} us; with one directional derivative "
        f"{figures['directional_us']:.3f} us; the whole Jacobian (13 directional derivatives) "
        f"{figures['jacobian_us']:.3f} us")
    return figures
