"""Benchmarks: the hot path per communication step, sweeps, endurance, controllers.

``run_bench`` times the crane pair through the master against the same models in
a plain Python loop (what FMI costs) and against a fixed anchor that this
project's changes cannot move: two trivial FMUs built by stock pythonfmu, with
the crane pair's 6+1 signals, driven by a bare ctypes loop. The in-process runs
are timed from initialisation to the last step (loading excluded); the whole
``crane-fmu simulate`` process is timed against the anchor's whole process.
"""

import os
import statistics
import subprocess
import sys
import tempfile
import time
from array import array
from contextlib import ExitStack
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.cosim import CsvRecorder, Master, open_instance
from crane_fmu.cosim.master import communication_points
from crane_fmu.sweep import spec
from crane_fmu.sweep.runner import run_case, shippable


def _open(system, fmu_dir):
    """``(instances, connections)`` of a system, instantiated."""
    fmus, connections = system.resolve(fmu_dir)
    return {name: open_instance(path, name) for name, path in fmus.items()}, connections


def _timed_run(system, fmu_dir, csv_path):
    """The prepared system through the master, every step to CSV: ``(seconds, steps)``."""
    instances, connections = _open(system, fmu_dir)
    try:
        recorder = CsvRecorder(csv_path)
        master = Master(instances, connections)
        start = time.perf_counter()
        n = master.run(system.start_time, system.stop_time, system.step, [recorder])
        recorder.close()
        elapsed = time.perf_counter() - start
        master.terminate()
    finally:
        for inst in instances.values():
            inst.free()
    return elapsed, n


# The fixed anchor: two trivial FMUs built by stock pythonfmu (its own binary, not this project's)
# with the crane pair's 6+1 signals, driven by a bare ctypes loop without recording.
ANCHOR_SLAVES = {
    "AnchorPlant": """
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class AnchorPlant(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        for i in range(6):
            setattr(self, f"y{i}", 0.0)
            self.register_variable(Real(f"y{i}", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y0 = self.y1 = self.y2 = self.y3 = self.y4 = self.y5 = (current_time + step_size) / 3.0 + 1e-3 * self.u
        return True
""",
    "AnchorController": """
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class AnchorController(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        for i in range(6):
            setattr(self, f"x{i}", 0.0)
            self.register_variable(Real(f"x{i}", causality=Fmi2Causality.input))
        self.register_variable(Real("u", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.u = -self.x0
        return True
"""}

ANCHOR_LOOP = """
import ctypes, sys, time
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


def open_fmu(path):
    md = read_model_description(path)
    unzip = extract(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=md.coSimulation.modelIdentifier)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    bare = ctypes.CDLL(f"{unzip}/binaries/linux64/{md.coSimulation.modelIdentifier}.so")  # no argtypes
    refs = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, bare, refs


plant, plant_dll, plant_vr = open_fmu(sys.argv[1])
ctrl, ctrl_dll, ctrl_vr = open_fmu(sys.argv[2])
n, h = int(sys.argv[3]), float(sys.argv[4])
ys_vr = (ctypes.c_uint * 6)(*(plant_vr[f"y{i}"] for i in range(6)))
xs_vr = (ctypes.c_uint * 6)(*(ctrl_vr[f"x{i}"] for i in range(6)))
u_out, u_in = (ctypes.c_uint * 1)(ctrl_vr["u"]), (ctypes.c_uint * 1)(plant_vr["u"])
ys, u = (ctypes.c_double * 6)(), (ctypes.c_double * 1)()
pc, cc = ctypes.c_void_p(plant.component), ctypes.c_void_p(ctrl.component)
pget, pset, pstep = plant_dll.fmi2GetReal, plant_dll.fmi2SetReal, plant_dll.fmi2DoStep
cget, cset, cstep = ctrl_dll.fmi2GetReal, ctrl_dll.fmi2SetReal, ctrl_dll.fmi2DoStep
start = time.perf_counter()
for k in range(n):
    t, dt = ctypes.c_double(k * h), ctypes.c_double(h)
    pget(pc, ys_vr, 6, ys)
    cset(cc, xs_vr, 6, ys)
    cget(cc, u_out, 1, u)
    pset(pc, u_in, 1, u)
    pstep(pc, t, dt, 1)
    cstep(cc, t, dt, 1)
print(time.perf_counter() - start, ys[0])
"""


def build_anchor(out_dir):
    """The anchor's two FMUs, built by stock pythonfmu with its own binary; ``(plant, controller)``."""
    from pythonfmu import FmuBuilder  # build time only, as in build_fmus.py

    out_dir = Path(out_dir)
    paths = []
    for name, source in ANCHOR_SLAVES.items():
        script = out_dir / "src" / f"{name.lower()}.py"
        script.parent.mkdir(parents=True, exist_ok=True)
        script.write_text(source)
        paths.append(FmuBuilder.build_FMU(script, dest=out_dir, needsExecutionTool=False))
    return tuple(paths)


def _process_seconds(command):
    """Wall time of a whole process, from start to exit."""
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    return time.perf_counter() - start


def _plain_loop(system, stop_time, step, csv_path):
    """The system's models called directly in a Python loop, recorded like the master's run; seconds."""
    n = communication_points(0.0, stop_time, step)
    models, configs, states, names = {}, {}, {}, []
    for name, identifier in system.instances.items():
        c = models[name] = components.get(identifier)
        values = {v.name: v.start for v in c.variables if v.causality == "parameter"}
        values.update(system.parameters.get(name, {}))
        configs[name] = c.configure(values)
        states[name] = c.initial_state(configs[name]) if c.stateful else None
        names += [f"{name}.{o}" for o in c.names("output")]
    roles = components.by_role(system.instances)
    plant, ctrl = models[roles["plant"]], models[roles["controller"]]
    p_out, c_in = plant.names("output"), ctrl.names("input")
    feed = [p_out.index(i) for i in c_in]  # controller inputs from the plant's outputs, by name
    p_inputs = list(v.start for v in plant.variables if v.causality == "input")
    u_at = plant.names("input").index("u")
    buffer = array("d", bytes(8 * len(names)))
    values = memoryview(buffer)
    recorder = CsvRecorder(csv_path)
    start = time.perf_counter()
    recorder.start(names)
    pc, cc = configs[roles["plant"]], configs[roles["controller"]]
    ps, cs = states[roles["plant"]], states[roles["controller"]]
    width = len(p_out)
    for k in range(n + 1):
        t = k * step
        outputs = plant.output(pc, ps, tuple(p_inputs))
        c_inputs = tuple(outputs[i] for i in feed)
        u = ctrl.output(cc, cs, c_inputs)
        p_inputs[u_at] = u[0]
        buffer[:width] = array("d", outputs)
        buffer[width:] = array("d", u)
        recorder.observe(t, values)
        if k < n:
            ps = plant.update(pc, ps, tuple(p_inputs), t, step)
            if ctrl.stateful:
                cs = ctrl.update(cc, cs, c_inputs, t, step)
    recorder.close()
    return time.perf_counter() - start, n


def run_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the benchmark and print its figures (medians of ``repeat`` alternating runs); return them.

    1. the crane pair (paper system) through the master, every step recorded to CSV;
    2. the same models called in a plain Python loop with the same recording: the FMI tax;
    3. the fixed anchor: stock pythonfmu FMUs in a bare ctypes loop, no recording;
    4. whole processes: ``crane-fmu simulate`` of the case against the anchor's for as many steps.
    """
    n = communication_points(0.0, stop_time, step)
    with tempfile.TemporaryDirectory(prefix="crane_bench_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        paper = systems.get("paper")
        build_all(built, set(paper.instances.values()), systems=(), fmi3=False, native=False,
                  log=lambda _: None)
        anchor = [str(p) for p in build_anchor(tmp / "anchor")]
        timed = systems.prepare(paper, step, stop_time)
        command = Path(sys.executable).parent / "crane-fmu"  # the installed command, else the module
        command = [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]
        simulate = [*command, "simulate", "--fmu-dir", str(built), "--stop-time",
                    repr(stop_time), "--step", repr(step), "--out", str(tmp / "process.csv")]
        anchor_loop = [sys.executable, "-c", ANCHOR_LOOP, *anchor, str(n), repr(step)]
        times = {name: [] for name in ("crane", "plain", "anchor", "crane_process", "anchor_process")}
        for _ in range(repeat):  # alternate, so drifts in machine load hit all
            times["crane"].append(_timed_run(timed, built, tmp / "crane.csv")[0])
            times["plain"].append(_plain_loop(timed, stop_time, step, tmp / "plain.csv")[0])
            done = subprocess.run(anchor_loop, check=True, capture_output=True, text=True)
            times["anchor"].append(float(done.stdout.split()[0]))
            times["crane_process"].append(_process_seconds(simulate))
            times["anchor_process"].append(_process_seconds(anchor_loop))
    med = {name: statistics.median(t) for name, t in times.items()}
    us = {name: 1e6 * med[name] / n for name in ("crane", "plain", "anchor")}
    figures = {"steps": n, **{f"{name}_us_per_step": v for name, v in us.items()},
               "fmi_tax": us["crane"] / us["plain"], "crane_over_anchor": us["crane"] / us["anchor"],
               "process_ratio": med["crane_process"] / med["anchor_process"],
               "process_realtime_factor": stop_time / med["crane_process"],
               "crane_process_s": med["crane_process"], "anchor_process_s": med["anchor_process"]}
    out(f"{n} steps of h = {step:g} s, medians of {repeat} alternating runs")
    out(f"1. crane pair through the master, CSV of every step: {us['crane']:6.1f} us/step  (target <= 15, "
        "ambition <= 10)")
    out(f"2. the same models in a plain Python loop, same CSV: {us['plain']:6.1f} us/step  "
        f"(FMI tax: crane pair / plain loop = {figures['fmi_tax']:.2f})")
    out(f"3. anchor: stock pythonfmu FMUs, bare ctypes loop:  {us['anchor']:6.1f} us/step  "
        f"(crane pair / anchor = {figures['crane_over_anchor']:.2f})")
    out(f"4. whole processes: crane-fmu simulate {med['crane_process']:.2f} s "
        f"({figures['process_realtime_factor']:.1f}x real time), anchor {med['anchor_process']:.2f} s: "
        f"ratio {figures['process_ratio']:.2f}  (target <= 1.0)")
    return figures


def run_sweep_bench(n_cases=16, stop_time=10.0, step=1e-3, repeat=3, out=print):
    """Cases per second of a sweep on a local Dask cluster with 1 and with 2 workers.

    Both clusters are started and warmed up (one case per worker) before the
    clock starts; the batches then alternate between them ``repeat`` times and
    the medians are reported, so drifts in machine speed hit both. The per-case
    overhead is the wall time per case with one worker minus the mean time the
    case itself took inside the worker.
    """
    from distributed import Client  # optional: the dask extra

    from crane_fmu.batch import local_cluster


    study = spec.parse({"stop_time": stop_time, "step": step, "metrics": ["outcome", "max_theta1_deg"]})
    settings, metrics = study.settings(), study.metrics
    cases = [{"plant.theta1_0": 0.01 * (1 + i % 8), "controller.w_theta2": 0.0} for i in range(n_cases)]
    walls, case_times = {1: [], 2: []}, []
    with tempfile.TemporaryDirectory(prefix="crane_bench_") as tmp, ExitStack() as stack:
        paper = systems.get("paper")
        build_all(Path(tmp) / "fmus", paper.instances.values(), systems=(), fmi3=False, native=False,
                  log=lambda _: None)
        system = shippable(paper, Path(tmp) / "fmus")
        clients = {}
        for workers in (1, 2):
            cluster = stack.enter_context(local_cluster(workers))  # as a sweep's: on the loopback, logs silenced
            client = stack.enter_context(Client(cluster))
            shipped = client.scatter([system], broadcast=True)[0]
            clients[workers] = (client, shipped)
            client.gather(client.map(run_case, cases[:workers], settings=settings, system=shipped,
                                     metric_names=metrics, pure=False))
        for _ in range(repeat):
            for workers, (client, shipped) in clients.items():
                start = time.perf_counter()
                rows = client.gather(client.map(run_case, cases, settings=settings, system=shipped,
                                                metric_names=metrics, pure=False))
                walls[workers].append(time.perf_counter() - start)
                if workers == 1:
                    case_times.append(statistics.mean(r["duration_s"] for r in rows))
    wall1, wall2 = statistics.median(walls[1]), statistics.median(walls[2])
    case_time = statistics.median(case_times)
    result = {
        "cases_per_s_1": n_cases / wall1,
        "cases_per_s_2": n_cases / wall2,
        "efficiency": wall1 / (2 * wall2),
        "case_s": case_time,
        "overhead_fraction": (wall1 / n_cases - case_time) / case_time,
    }
    out(f"{n_cases} cases of {stop_time:g} s at h = {step:g} s (crane pair), local Dask cluster, "
        f"medians of {repeat} alternating batches")
    out(f"1 worker:  {result['cases_per_s_1']:.2f} cases/s")
    out(f"2 workers: {result['cases_per_s_2']:.2f} cases/s")
    out(f"parallel efficiency on 2 workers: {100 * result['efficiency']:.0f} %  (target >= 85 %)")
    out(f"per-case overhead of shipping work to a worker: {1e3 * (wall1 / n_cases - case_time):.1f} ms "
        f"= {100 * result['overhead_fraction']:.1f} % of a case's {case_time:.3f} s  (target < 10 %)")
    return result


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
        build_all(built, paper.instances.values(), systems=(), fmi3=False, native=False,
                  log=lambda _: None)
        instances, connections = _open(paper, built)
        probe = _MemoryProbe(max(1, round(60.0 / step)))
        csv_path = Path(tmp) / "endurance.csv"
        try:
            recorder = CsvRecorder(csv_path)
            master = Master(instances, connections)
            # the weighted law (1, 1, 0) converges, so the run stays finite for the whole hour
            start = time.perf_counter()
            controller = components.by_role(paper.instances)["controller"]
            master.run(0.0, stop_time, step, [recorder, probe], {controller: {"w_theta2": 0.0}})
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
