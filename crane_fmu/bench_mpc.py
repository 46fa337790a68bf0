"""``crane-fmu bench --mpc``: what the MpcController's optimisation costs, Python and native (C).

1. the solve: the 2 m move of ``mpc-transport`` (10 s) with the model called directly, every solve timed
   (one every 50 ms): the median, the 90th percentile and the longest, and apart from them the first,
   which plans the whole move;
2. the same solves of the native MpcController FMU (Linux binary), each timed as the fmpy call that asks for
   ``u`` at a solve's step (the solve happens in it; the step after reuses it), the plant the Python model;
   beside it the same call at the steps between solves (the call alone: what the figure holds besides the solve);
3. whole processes: ``crane-fmu simulate --system mpc-transport`` against ``--system transport`` (the LQR
   tracking a ZV-shaped reference), medians of ``repeat`` alternating runs, and their ratio: on the Python FMUs,
   and with ``--fmu-dir`` a folder of native ones (as ``build/native``).
"""

import statistics
import sys
import tempfile
import time
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.bench import _process_seconds
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.build_scripts.native import NativeUnavailable, build_native_fmu, compilers, native_dir

SOLVE_TARGET_US, PROCESS_TARGET = 300.0, 4.0  # the Python MPC's targets: median solve, whole-process ratio
NATIVE_SOLVE_TARGET_US, NATIVE_PROCESS_TARGET = 50.0, 1.5  # the native MPC's
SYSTEMS = ("mpc-transport", "transport")


def solve_times(system_name="mpc-transport", step=1e-3):
    """Seconds of every solve of the system's MpcController over its run, the model called directly (first: the
    plan)."""
    from crane_fmu.model.component import Step

    system = systems.get(system_name)
    plant, mpc = components.get("CranePlant"), components.get("MpcController")
    roles = components.by_role(system.instances)
    pc = plant.check({**system.parameters.get(roles["plant"], {})})
    cc = mpc.check({**system.parameters.get(roles["controller"], {}), "h": step})
    ps, cs = plant.initial_state(pc), mpc.initial_state(cc)
    inputs_at = [plant.names("output").index(name) for name in mpc.names("input")
                 if name in plant.names("output")]  # by name: the force estimates (F2_hat, F1_hat) unconnected, 0
    times = []
    for k in range(round(system.stop_time / step) + 1):
        out = plant.output(pc, ps, (0.0,) * 4)
        inputs = tuple(out[i] for i in inputs_at) + (0.0, 0.0)  # F2_hat, F1_hat
        start = time.perf_counter()
        u = mpc.output(cc, cs, inputs)[0]
        if k % cc.every == 0:
            times.append(time.perf_counter() - start)
        ps = plant.update(pc, ps, (u, 0.0, 0.0, 0.0), k * step, step)
        cs = mpc.update(cc, cs, inputs, k * step, step)
        if isinstance(cs, Step):
            cs = cs.state
    return times


def native_solve_times(fmu, system_name="mpc-transport", step=1e-3):
    """``(solves, between)``: seconds of the native MpcController FMU's fmpy call that gives ``u`` at each solve's
    step over the system's run (first: the plan), and of the same call at the steps between solves."""
    import fmpy
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    system = systems.get(system_name)
    plant, mpc = components.get("CranePlant"), components.get("MpcController")
    roles = components.by_role(system.instances)
    pc = plant.check({**system.parameters.get(roles["plant"], {})})
    ps = plant.initial_state(pc)
    settings = {**system.parameters.get(roles["controller"], {}), "h": step}
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="mpc")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr[name] for name in settings], list(settings.values()))
    slave.exitInitializationMode()
    every = mpc.check(settings).every
    inputs_at = [plant.names("output").index(name) for name in mpc.names("input")
                 if name in plant.names("output")]  # by name: the force estimates (F2_hat, F1_hat) unconnected, 0
    inputs, output = [vr[name] for name in mpc.names("input") if name in plant.names("output")], [vr["u"]]
    solves, between = [], []
    try:
        for k in range(round(system.stop_time / step) + 1):
            out = plant.output(pc, ps, (0.0,) * 4)
            slave.setReal(inputs, [out[i] for i in inputs_at])
            start = time.perf_counter()
            u = slave.getReal(output)[0]
            (solves if k % every == 0 else between).append(time.perf_counter() - start)
            ps = plant.update(pc, ps, (u, 0.0, 0.0, 0.0), k * step, step)
            slave.doStep(k * step, step)
    finally:
        slave.terminate()
        slave.freeInstance()
    return solves, between


def _solve_figures(times):
    solves = sorted(times[1:])
    return {"solves": len(times), "plan_ms": 1e3 * times[0], "median_us": 1e6 * statistics.median(solves),
            "p90_us": 1e6 * solves[int(0.9 * (len(solves) - 1))], "longest_ms": 1e3 * solves[-1]}


def _process_ratio(folder, tmp, repeat):
    """Medians of ``repeat`` alternating whole ``crane-fmu simulate --system`` processes on the FMUs of ``folder``:
    ``{system: seconds}``."""
    command = Path(sys.executable).parent / "crane-fmu"
    command = [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]
    runs = {name: [*command, "simulate", "--system", name, "--fmu-dir", str(folder), "--out",
                   str(Path(tmp) / f"{name}.csv")] for name in SYSTEMS}
    seconds = {name: [] for name in runs}
    for _ in range(repeat):  # alternate, so drifts in machine load hit both
        for name, argv in runs.items():
            seconds[name].append(_process_seconds(argv))
    return {name: statistics.median(s) for name, s in seconds.items()}


def run_mpc_bench(repeat=5, out=print):
    """Print the solve's cost and the whole-process ratio, Python and native; return the figures."""
    figures = _solve_figures(solve_times())
    with tempfile.TemporaryDirectory(prefix="crane_bench_mpc_") as tmp:
        built = Path(tmp) / "fmus"
        kinds = {kind for name in SYSTEMS for kind in systems.get(name).instances.values()}
        build_all(built, kinds, systems=(), fmi3=False, native=False, log=lambda _: None)
        med = _process_ratio(built, tmp, repeat)
        try:
            linux = {"linux": compilers()["linux"]}
        except NativeUnavailable as exc:
            linux = None
            out(f"warning: {exc}; no native figures")
        native = {}
        if linux:
            folder = native_dir(built)  # the native FMUs (FMI 2.0, Linux), as build/native holds them
            for kind in kinds:
                build_native_fmu(components.get(kind), folder, 2, linux)
            solves, between = native_solve_times(folder / "MpcController.fmu")
            native = _solve_figures(solves)
            native["call_us"] = 1e6 * statistics.median(between)
            native.update({f"{name}_process_s": s for name, s in _process_ratio(folder, tmp, repeat).items()})
            native["process_ratio"] = native["mpc-transport_process_s"] / native["transport_process_s"]
    figures.update(mpc_process_s=med["mpc-transport"], transport_process_s=med["transport"],
                   process_ratio=med["mpc-transport"] / med["transport"], native=native)
    out(f"1. MpcController solves over the 2 m move of mpc-transport (10 s, one every 50 ms, model called "
        f"directly): median {figures['median_us']:.0f} us (target <= {SOLVE_TARGET_US:.0f}), 90th percentile "
        f"{figures['p90_us']:.0f} us, longest {figures['longest_ms']:.1f} ms; the first (it plans the move) "
        f"{figures['plan_ms']:.0f} ms")
    out(f"2. whole processes, medians of {repeat} alternating runs: crane-fmu simulate --system mpc-transport "
        f"{med['mpc-transport']:.2f} s, --system transport {med['transport']:.2f} s: ratio "
        f"{figures['process_ratio']:.2f} (target <= {PROCESS_TARGET:g})")
    if native:
        out(f"3. native MpcController FMU, the same solves (the fmpy call that gives u at a solve's step): median "
            f"{native['median_us']:.1f} us (target <= {NATIVE_SOLVE_TARGET_US:.0f}), 90th percentile "
            f"{native['p90_us']:.1f} us, longest {native['longest_ms']:.2f} ms; the first (it plans the move) "
            f"{native['plan_ms']:.1f} ms; the same call between solves {native['call_us']:.1f} us")
        out(f"4. whole processes on native FMUs (--fmu-dir build/native), medians of {repeat} alternating runs: "
            f"--system mpc-transport {native['mpc-transport_process_s']:.2f} s, --system transport "
            f"{native['transport_process_s']:.2f} s: ratio {native['process_ratio']:.2f} (target <= "
            f"{NATIVE_PROCESS_TARGET:g})")
    return figures
