"""``crane-fmu bench --mpc``: what the MpcController's optimisation costs.

1. the solve: the 2 m move of ``mpc-transport`` (10 s) with the model called directly, every solve timed
   (one every 50 ms): the median, the 90th percentile and the longest, and apart from them the first,
   which plans the whole move;
2. whole processes: ``crane-fmu simulate --system mpc-transport`` against ``--system transport`` (the LQR
   tracking a ZV-shaped reference), medians of ``repeat`` alternating runs, and their ratio.
"""

import statistics
import sys
import tempfile
import time
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.bench import _process_seconds
from crane_fmu.build_scripts.build_fmus import build_all

SOLVE_TARGET_US, PROCESS_TARGET = 300.0, 4.0  # the Python MPC's targets: median solve, whole-process ratio


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
    inputs_at = [plant.names("output").index(name) for name in mpc.names("input")]
    times = []
    for k in range(round(system.stop_time / step) + 1):
        out = plant.output(pc, ps, (0.0,) * 4)
        inputs = tuple(out[i] for i in inputs_at)
        start = time.perf_counter()
        u = mpc.output(cc, cs, inputs)[0]
        if k % cc.every == 0:
            times.append(time.perf_counter() - start)
        ps = plant.update(pc, ps, (u, 0.0, 0.0, 0.0), k * step, step)
        cs = mpc.update(cc, cs, inputs, k * step, step)
        if isinstance(cs, Step):
            cs = cs.state
    return times


def run_mpc_bench(repeat=5, out=print):
    """Print the solve's cost and the whole-process ratio; return the figures."""
    times = solve_times()
    solves = sorted(times[1:])
    figures = {"solves": len(times), "plan_ms": 1e3 * times[0], "median_us": 1e6 * statistics.median(solves),
               "p90_us": 1e6 * solves[int(0.9 * (len(solves) - 1))], "longest_ms": 1e3 * solves[-1]}
    with tempfile.TemporaryDirectory(prefix="crane_bench_mpc_") as tmp:
        built = Path(tmp) / "fmus"
        kinds = {kind for name in ("mpc-transport", "transport") for kind in systems.get(name).instances.values()}
        build_all(built, kinds, systems=(), fmi3=False, native=False, log=lambda _: None)
        command = Path(sys.executable).parent / "crane-fmu"
        command = [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]
        runs = {name: [*command, "simulate", "--system", name, "--fmu-dir", str(built), "--out",
                       str(Path(tmp) / f"{name}.csv")] for name in ("mpc-transport", "transport")}
        seconds = {name: [] for name in runs}
        for _ in range(repeat):  # alternate, so drifts in machine load hit both
            for name, argv in runs.items():
                seconds[name].append(_process_seconds(argv))
    med = {name: statistics.median(s) for name, s in seconds.items()}
    figures.update(mpc_process_s=med["mpc-transport"], transport_process_s=med["transport"],
                   process_ratio=med["mpc-transport"] / med["transport"])
    out(f"1. MpcController solves over the 2 m move of mpc-transport (10 s, one every 50 ms, model called "
        f"directly): median {figures['median_us']:.0f} us (target <= {SOLVE_TARGET_US:.0f}), 90th percentile "
        f"{figures['p90_us']:.0f} us, longest {figures['longest_ms']:.1f} ms; the first (it plans the move) "
        f"{figures['plan_ms']:.0f} ms")
    out(f"2. whole processes, medians of {repeat} alternating runs: crane-fmu simulate --system mpc-transport "
        f"{med['mpc-transport']:.2f} s, --system transport {med['transport']:.2f} s: ratio "
        f"{figures['process_ratio']:.2f} (target <= {PROCESS_TARGET:g})")
    return figures
