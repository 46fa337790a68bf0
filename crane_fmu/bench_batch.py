"""``crane-fmu bench --sweep``, the batch path of native FMUs: where the time goes, against the C host's limit.

In one run, on the native FMUs of ``native_dir`` (``build/native``):

1. the native pair (``paper``: plant and backstepping law) through our master on the batch path, per step (a case of
   ``stop_time`` run on reused instances, its sweep figures computed, no rows written), against the same pair in
   the C host (``fmu_src/host/host.c pair-bench``);
2. cases per second of a sweep of LQR transport cases (the ``transport`` system, plants of the paired design's
   ranges) on a local Dask cluster of 1 and of 2 workers, and the C host's limit for the same cases: ``host cases``
   makes the batch path's FMI calls for them, nothing recorded, in one process per worker;
3. a study of ``study_cases`` cases of that kind (S3's ranges, native LQR, 10 s each) by ``crane-fmu sweep`` with 2
   workers: its wall time and the peak memory of all its processes;
4. the full board (``crane-fmu compare --fmu-dir NATIVE``) from an empty folder: its wall time (``board_cases``: of
   that many paired cases; 0: not measured), cold (an empty temporary folder: no picture, floor or study stored by an
   earlier run) and warm (the same board again into another empty folder, with what the cold one stored).
"""

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from crane_fmu import native_batch, systems
from crane_fmu.analysis import metrics
from crane_fmu.analysis.planar_scenarios import FACTORS
from crane_fmu.build_scripts.native import HOST, compilers
from crane_fmu.build_scripts.wrapper import fmi_headers
from crane_fmu.cosim.master import communication_points
from crane_fmu.cosim.reused import ReusedRunner
from crane_fmu.sweep import spec
from crane_fmu.sweep.runner import case_parameters, case_row, shippable

SWEEP_SYSTEM = "transport"  # the LQR transport: plant, planner, LqrController


def _command():
    command = Path(sys.executable).parent / "crane-fmu"
    return [str(command)] if command.exists() else [sys.executable, "-m", "crane_fmu"]


def paired_cases(n, seed=53):
    """``n`` plants of the paired design's ranges (:data:`~crane_fmu.analysis.planar_scenarios.FACTORS`), as sweep
    cases of the ``plant`` instance: a Latin hypercube."""
    from scipy.stats import qmc

    return [{f"plant.{f.name}": float(f.low + u * (f.high - f.low)) for f, u in zip(FACTORS, point)}
            for point in qmc.LatinHypercube(d=len(FACTORS), seed=seed).random(n)]


def study_text(samples, stop_time=10.0, step=1e-3):
    """A study file of ``samples`` LQR transport cases on plants sampled in S3's ranges."""
    ranges = "\n".join(f'"plant.{f.name}" = {{low = {f.low!r}, high = {f.high!r}}}' for f in FACTORS)
    return (f'system = "{SWEEP_SYSTEM}"\nstop_time = {stop_time!r}\nstep = {step!r}\n[parameters]\n{ranges}\n'
            f'[sampling]\nmethod = "latin-hypercube"\nsamples = {samples}\nseed = 53\n')


def compile_host(folder):
    """The C host (``fmu_src/host/host.c``) compiled into ``folder``."""
    host = Path(folder) / "host"
    subprocess.run([compilers()["linux"], "-O2", "-ffp-contract=off", f"-I{fmi_headers()}", str(HOST), "-o",
                    str(host), "-ldl", "-lpthread", "-lm"], check=True)
    return host


def host_plan(runs, parameter_sets, stop_time, step):
    """The text of ``host cases``' plan: the FMI calls of a :class:`ReusedRunner`'s runs with ``parameter_sets`` (one
    ``{instance: {variable: value}}`` per case), Gauss-Seidel (see ``run_cases`` in host.c)."""
    wiring = runs.master.wiring
    names = list(runs.instances)
    lines = [str(len(names))]
    for name, inst in runs.instances.items():
        identifier = inst.md.coSimulation.modelIdentifier
        lines.append(f"{Path(inst._unzip) / 'binaries' / 'linux64' / identifier}.so {inst.md.guid} {name}")
    ports = wiring.ports
    vr = {name: {v: inst.variables[v].valueReference for v in inst.variables} for name, inst in runs.instances.items()}
    reads = [f"{names.index(n)} {len(p.instance.outputs)} " + " ".join(str(vr[n][o]) for o in p.instance.outputs)
             + f" {p.offset}" for n, p in ports.items()]
    links = {n: [] for n in names}
    for c in wiring.connections:
        source = ports[c.source]
        links[c.target].append((source.instance.outputs.index(c.output), c.input, source.offset))
    writes, write_index = [], {}
    for n in names:
        if links[n]:
            ordered = sorted(links[n])  # as the master's port orders them: by the source's output
            write_index[n] = len(writes)
            writes.append(f"{names.index(n)} {len(ordered)} " + " ".join(str(vr[n][i]) for _, i, _ in ordered) + " "
                          + " ".join(str(offset + position) for position, _, offset in ordered))
    exchange = [f"r {names.index(n)}" if op == "read" else f"w {write_index[n]}"
                for op, n in wiring._calls.exchange if op == "read" or n in write_index]
    lines += [str(len(wiring.output_names)), str(len(reads)), *reads, str(len(writes)), *writes,
              str(len(exchange)), *exchange,
              f"{len(wiring.order)} " + " ".join(str(names.index(p.instance.name)) for p in wiring.order),
              f"{communication_points(0.0, stop_time, step)} {step!r} {stop_time!r} {len(parameter_sets)}"]
    for parameters in parameter_sets:
        for n in names:
            variables = runs.instances[n].variables
            values = [(variables[k], v) for k, v in parameters.get(n, {}).items()]
            reals = [(var.valueReference, v) for var, v in values if var.type == "Real"]
            texts = [(var.valueReference, v) for var, v in values if var.type != "Real"]
            lines.append(" ".join([str(len(reals)), *(f"{r} {v!r}" for r, v in reals), str(len(texts)),
                                   *(f"{r} {v}" for r, v in texts)]))
    return "\n".join(lines) + "\n"


def _children_cpu():
    """CPU seconds of this process's children that ended (and theirs)."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def _own_cpu():
    used = resource.getrusage(resource.RUSAGE_SELF)
    return used.ru_utime + used.ru_stime


def host_cases_per_s(host, runs, parameter_sets, stop_time, step, workers, folder):
    """``(cases per second, CPU seconds a case)`` of ``host cases`` on ``parameter_sets`` split among ``workers``
    processes run at once."""
    plans = []
    for i in range(workers):
        plan = Path(folder) / f"plan{i}.txt"
        plan.write_text(host_plan(runs, parameter_sets[i::workers], stop_time, step))
        plans.append(plan)
    start = time.perf_counter()
    processes = [subprocess.Popen([str(host), "cases", str(p)], stdout=subprocess.PIPE, text=True) for p in plans]
    cpu = 0.0
    for p in processes:
        out, _ = p.communicate()
        if p.returncode != 0:
            raise RuntimeError(f"host cases failed with status {p.returncode}")
        cpu += float(out.split()[2])  # from its first instantiation to its last terminate, as the batch path's
    return len(parameter_sets) / (time.perf_counter() - start), cpu / len(parameter_sets)


def pair_per_step(native_dir, stop_time, step):
    """``(seconds, CPU seconds)`` per step of the native pair (``paper``) on the batch path: a case run on reused
    instances and its sweep figures computed, no rows written."""
    system = systems.prepare(systems.get("paper"), step, stop_time)
    fmus, connections = system.resolve(native_dir)
    study = spec.parse({"stop_time": stop_time, "step": step})
    settings = {**study.settings(), "metrics_version": metrics.VERSION}
    with ReusedRunner(fmus, connections) as runs:
        kept = native_batch.kept_outputs(runs.output_names)
        native_batch.run(runs, stop_time, step, system.parameters, kept)  # the first run: made, not reset
        start, cpu = time.perf_counter(), time.process_time()
        columns, error = native_batch.run(runs, stop_time, step, system.parameters, kept)
        case_row({}, settings, study.metrics, columns, error, native_batch.measure())
        n = communication_points(0.0, stop_time, step)
        return (time.perf_counter() - start) / n, (time.process_time() - cpu) / n


def _tree_rss_mb(pid):
    """Resident memory of a process and all its descendants [MB] (psutil, which Dask brings)."""
    import psutil

    try:
        root = psutil.Process(pid)
        return sum(p.memory_info().rss for p in [root, *root.children(recursive=True)]) / 1e6
    except psutil.Error:
        return 0.0


def _adopt_orphans(adopt=True):
    """Make this process the reaper of its descendants' orphans (Linux; ``adopt`` False: no longer): the processes a
    command leaves when it ends (its fork server, which has reaped the workers it forked) become this process's
    children, so that their CPU time is counted with the command's once reaped; elsewhere nothing (their CPU time is
    then not counted)."""
    if sys.platform.startswith("linux"):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(36, int(adopt), 0, 0, 0)  # PR_SET_CHILD_SUBREAPER


def _reap_adopted(before, timeout=60.0):
    """Wait for this process's children but those of the pids ``before`` (the orphans a command left, adopted), and
    for those they leave in turn, each at most ``timeout`` seconds: their CPU time is then counted as its children's."""
    import psutil

    while True:
        adopted = [p for p in psutil.Process().children() if p.pid not in before]
        for child in adopted:
            try:
                child.wait(timeout)
            except (psutil.Error, ChildProcessError):  # gone, or still running after the timeout: not counted
                before.add(child.pid)
        if not adopted:
            return


def timed_process(command, sample=0.1, env=None):
    """``(wall seconds, peak resident memory of the process tree [MB], CPU seconds of the tree)`` of a command run to
    its end (in the environment ``env``: default this one's). The tree's CPU time counts the processes that outlive
    the command (:func:`_adopt_orphans`), waited for after it ends; the wall time is the command's."""
    import psutil

    _adopt_orphans()
    before = {p.pid for p in psutil.Process().children()}
    start, peak, cpu = time.perf_counter(), 0.0, _children_cpu()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    stop = threading.Event()

    def watch():
        nonlocal peak
        while not stop.is_set():
            peak = max(peak, _tree_rss_mb(process.pid))
            stop.wait(sample)

    watcher = threading.Thread(target=watch)
    watcher.start()
    _, err = process.communicate()
    seconds = time.perf_counter() - start
    stop.set()
    watcher.join()
    _reap_adopted(before | {process.pid})
    _adopt_orphans(False)
    if process.returncode:
        raise RuntimeError(f"{' '.join(command[-6:])}: status {process.returncode}: {err.strip()[-500:]}")
    return seconds, peak, _children_cpu() - cpu


def run_batch_bench(native_dir="build/native", n_cases=240, stop_time=20.0, step=1e-3, repeat=3, study_cases=10_000,
                    board_cases=None, out=print):
    """Run the batch path's benchmark on the native FMUs of ``native_dir``; print its figures and return them."""
    from distributed import Client  # optional: the dask extra

    from crane_fmu.batch import _chunks_on_dask, local_cluster

    native_dir = Path(native_dir)
    if not all((native_dir / f"{name}.fmu").is_file() for name in ("CranePlant", "LqrController",
                                                                      "BacksteppingController", "TrajectoryPlanner")):
        out(f"native batch path: not measured: no native FMUs in {native_dir} (crane-fmu build, with a C compiler; "
            "or give --native-dir)")
        return None
    figures, pairs, host_pairs = {}, [], []
    study = spec.parse({"system": SWEEP_SYSTEM, "stop_time": stop_time, "step": step})
    settings = {**study.settings(), "metrics_version": metrics.VERSION}
    system = systems.prepare(systems.get(SWEEP_SYSTEM), step, stop_time, check=False)
    shipped = shippable(system, native_dir)
    cases = paired_cases(n_cases)
    walls = {1: [], 2: []}
    with tempfile.TemporaryDirectory(prefix="crane_bench_batch_") as tmp, \
            ReusedRunner(*system.resolve(native_dir)) as runs:
        host = compile_host(tmp)
        pair_bench = [str(host), "pair-bench", *_pair_arguments(runs, native_dir, tmp),
                      str(communication_points(0.0, stop_time, step)), repr(step), *_pair_vrs(native_dir)]
        for _ in range(repeat):  # alternate, so drifts in machine load hit both
            pairs.append(pair_per_step(native_dir, stop_time, step))
            host_pairs.append(tuple(map(float, subprocess.run(pair_bench, check=True, capture_output=True,
                                                              text=True).stdout.split())))
        parameter_sets = [case_parameters(c, system.parameters) for c in cases]
        limits, cpus, host_cpus = {1: [], 2: []}, [], []
        clusters = [local_cluster(w) for w in (1, 2)]  # as a sweep's and a board's: from the fork server
        try:
            clients = {w: Client(c) for w, c in zip((1, 2), clusters)}
            chunks = native_batch.items(cases, lambda _: True)
            for workers, client in clients.items():  # warm: every worker has opened its instances
                list(_chunks_on_dask(native_batch.sweep_chunk, chunks[:workers], (shipped,), None,
                                     client.scheduler.address, {"settings": settings,
                                                                "metric_names": study.metrics}))
            for _ in range(repeat):  # alternate, so drifts in machine load hit all
                for workers, client in clients.items():
                    start, cpu = time.perf_counter(), sum(client.run(_own_cpu).values())
                    rows = list(_chunks_on_dask(native_batch.sweep_chunk, chunks, (shipped,), None,
                                                client.scheduler.address, {"settings": settings,
                                                                           "metric_names": study.metrics}))
                    walls[workers].append(time.perf_counter() - start)
                    cpus.append((sum(client.run(_own_cpu).values()) - cpu) / n_cases)
                    assert len({r["case_id"] for r in rows}) == n_cases
                    rate, host_cpu = host_cases_per_s(host, runs, parameter_sets, stop_time, step, workers, tmp)
                    limits[workers].append(rate)
                    host_cpus.append(host_cpu)
        finally:
            for client in clients.values():
                client.close()
            for cluster in clusters:
                cluster.close()
        for workers in (1, 2):
            figures[f"batch_{workers}"] = n_cases / statistics.median(walls[workers])
            figures[f"host_{workers}"] = statistics.median(limits[workers])
        figures["batch_cpu_ms"], figures["host_cpu_ms"] = 1e3 * statistics.median(cpus), 1e3 * statistics.median(
            host_cpus)
        folder = Path(tmp)
        (folder / "study.toml").write_text(study_text(study_cases))
        figures["study_s"], figures["study_mb"], figures["study_cpu_s"] = timed_process(
            [*_command(), "sweep", str(folder / "study.toml"), "--fmu-dir", str(native_dir), "--out",
             str(folder / "study"), "--workers", "2", "--no-progress"])
        if board_cases != 0:  # cold: an empty folder and an empty temporary folder (no picture, floor or sweep
            # stored from an earlier run); warm: the same board again into another empty folder, those stores filled
            (folder / "board_tmp").mkdir()
            env = {**os.environ, "TMPDIR": str(folder / "board_tmp")}
            for kind in ("cold", "warm"):
                board = [*_command(), "compare", "--fmu-dir", str(native_dir), "--out", str(folder / f"board_{kind}"),
                         "--workers", "2", "--no-progress"] + (["--cases", str(board_cases)] if board_cases else [])
                figures[f"board_{kind}_s"], figures[f"board_{kind}_mb"], figures[f"board_{kind}_cpu_s"] = (
                    timed_process(board, env=env))
    figures.update({name: 1e6 * statistics.median(p[i] for p in runs) for name, runs, i in (
        ("pair_us", pairs, 0), ("pair_cpu_us", pairs, 1), ("host_pair_us", host_pairs, 0),
        ("host_pair_cpu_us", host_pairs, 1))})
    _print(figures, n_cases, stop_time, step, repeat, study_cases, board_cases, out)
    return figures


def _pair_arguments(runs, native_dir, folder):
    """``pair-bench``'s libraries and GUIDs of the native plant and backstepping law, unpacked into ``folder``."""
    import zipfile

    from fmpy import read_model_description

    arguments = []
    for name in ("CranePlant", "BacksteppingController"):
        with zipfile.ZipFile(native_dir / f"{name}.fmu") as z:
            z.extract(f"binaries/linux64/{name}.so", folder)
        arguments += [str(Path(folder) / "binaries" / "linux64" / f"{name}.so"),
                      read_model_description(str(native_dir / f"{name}.fmu")).guid]
    return arguments


def _pair_vrs(native_dir):
    from fmpy import read_model_description

    vrs = []
    for name in ("CranePlant", "BacksteppingController"):
        vr = {v.name: v.valueReference for v in read_model_description(str(native_dir / f"{name}.fmu")).modelVariables}
        vrs += [str(vr["x"]), str(vr["u"])]
    return vrs


def _print(f, n_cases, stop_time, step, repeat, study_cases, board_cases, out):
    load = os.getloadavg()[0]
    out(f"native batch path (load average {load:.1f} at the end; medians of {repeat})")
    out(f"native pair (paper) through our master, batch path, per step: {f['pair_us']:.3f} us; in the C host "
        f"{f['host_pair_us']:.3f} us = {f['pair_us'] / f['host_pair_us']:.2f}x the C host's  (target <= 2.0); CPU "
        f"{f['pair_cpu_us']:.3f} us and {f['host_pair_cpu_us']:.3f} us = "
        f"{f['pair_cpu_us'] / f['host_pair_cpu_us']:.2f}x")
    out(f"{n_cases} LQR transport cases of {stop_time:g} s at h = {step:g} s, plants in S3's ranges, local Dask "
        "cluster:")
    for workers in (1, 2):
        ratio = f[f"batch_{workers}"] / f[f"host_{workers}"]
        out(f"native batch, {workers} worker{'s' if workers > 1 else ''}: {f[f'batch_{workers}']:.1f} cases/s = "
            f"{ratio:.2f}x the C host's limit ({f[f'host_{workers}']:.1f} cases/s)"
            + ("  (target >= 0.5)" if workers == 2 else ""))
    out(f"CPU a case: batch path (its workers) {f['batch_cpu_ms']:.2f} ms, the C host {f['host_cpu_ms']:.2f} ms = "
        f"{f['host_cpu_ms'] / f['batch_cpu_ms']:.2f}x (what load cannot change)")
    out(f"a {study_cases}-case study (S3's ranges, native LQR, 10 s each), crane-fmu sweep --workers 2: "
        f"{f['study_s']:.1f} s wall ({f['study_cpu_s']:.1f} CPU-s), peak memory {f['study_mb']:.0f} MB  "
        "(targets <= 60 s, <= 1000 MB)")
    if board_cases == 0:
        out("the board on the native FMUs: not measured (--board-cases 0)")
        return
    board = "full board" if board_cases is None else f"board of {board_cases} paired cases"
    out(f"{board} on the native FMUs (crane-fmu compare --workers 2): cold {f['board_cold_s']:.1f} s "
        f"({f['board_cold_cpu_s']:.1f} CPU-s), warm {f['board_warm_s']:.1f} s ({f['board_warm_cpu_s']:.1f} CPU-s), "
        f"peak memory {f['board_cold_mb']:.0f} MB  (target: cold <= 10 s)")
