"""Runs a study's cases on Dask: a local cluster by default, or any existing scheduler.

The FMU files travel to the workers once (scattered, then cached on each
worker's disk by content hash), so workers need no shared file system. Every
finished case is appended to ``cases.jsonl`` in the output folder at once; a
re-run reads it back and skips the cases already done. A case that fails is a
row with its status and message, never the end of the study; a worker that
dies has its running cases rescheduled by Dask on the others.
"""

import hashlib
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

from .spec import case_id

JOURNAL = "cases.jsonl"


def shippable(system, fmu_dir):
    """What a worker needs to run cases of ``system``: FMU bytes by instance, connections, parameter values.

    ``blobs`` is ``{instance: (sha256, bytes)}``; workers cache each FMU once by its hash.
    """
    fmus, connections = system.resolve(fmu_dir)
    blobs = {}
    for name, path in fmus.items():
        data = Path(path).read_bytes()
        blobs[name] = (hashlib.sha256(data).hexdigest()[:20], data)
    return {"blobs": blobs, "connections": connections, "parameters": system.parameters}


def local_fmus(blobs):
    """Write each FMU once into this machine's cache; return ``{instance: path}``."""
    cache = Path(tempfile.gettempdir()) / "crane_fmu_sweep_cache"
    cache.mkdir(exist_ok=True)
    paths = {}
    for name, (digest, data) in blobs.items():
        path = cache / f"{digest}.fmu"
        if not path.exists():
            partial = cache / f".{digest}.{os.getpid()}.partial"
            partial.write_bytes(data)
            os.replace(partial, path)
        paths[name] = path
    return paths


def case_parameters(case, base=None):
    """``{"plant.l1": 1.5}`` -> ``{"plant": {"l1": 1.5}}``, over the system's own values ``base``."""
    parameters = {name: dict(values) for name, values in (base or {}).items()}
    for key, value in case.items():
        instance, _, variable = key.partition(".")
        parameters.setdefault(instance, {})[variable] = value
    return parameters


def _invalid_row(case, settings, error, metric_names):
    return {"case_id": case_id(case, settings), **case, "status": "invalid", "error": error,
            **dict.fromkeys(metric_names), "duration_s": 0.0}


def run_case(case, system, settings, metric_names):
    """Co-simulate one case of a :func:`shippable` system; return its row: parameters, metrics, status, error.

    Status is ``ok`` (ran to the stop time) or ``failed`` (an FMU stopped the
    run; the metrics cover the run up to there).
    """
    from crane_fmu.analysis import metrics
    from crane_fmu.cosim import ArrayRecorder, FmiError, simulate

    row = {"case_id": case_id(case, settings), **case, "status": "ok", "error": None}
    start = time.perf_counter()
    recorder = ArrayRecorder()
    try:
        simulate(local_fmus(system["blobs"]), system["connections"], settings["stop_time"], settings["step"],
                 settings["master"], case_parameters(case, system["parameters"]), recorder)
    except FmiError as exc:
        row.update(status="failed", error=str(exc))
    values = dict.fromkeys(metric_names)
    columns = recorder.columns() if recorder.names else None
    if columns and len(columns["time"]):  # else: failed before the first communication point
        s = metrics.crane_signals(columns)
        values = metrics.closed_loop_metrics(s["time"], s["x"], s["theta1"], s["theta2"], s["u"],
                                             row["status"] == "ok")
        values["settling_band_s"] = metrics.settling_time(s["time"], [s["theta1"], s["theta2"]],
                                                          math.radians(settings["settling_band_deg"]))
    row.update({name: values.get(name) for name in metric_names})
    row["duration_s"] = time.perf_counter() - start
    return row


def read_journal(out_dir):
    """Rows already finished in ``out_dir``, by case id (a torn last line is ignored)."""
    rows = {}
    path = Path(out_dir) / JOURNAL
    if path.exists():
        for line in path.read_text().splitlines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            rows[row["case_id"]] = row
    return rows


class Progress:
    """A one-line progress bar on stderr (a line per 10 % when stderr is not a terminal)."""

    def __init__(self, total, done, stream=sys.stderr):
        self.total, self.done, self.failed, self.stream = total, done, 0, stream
        self.start, self.tty = time.perf_counter(), stream.isatty()
        self._shown = -1

    def update(self, row):
        self.done += 1
        self.failed += row["status"] != "ok"
        tenth = 10 * self.done // max(self.total, 1)
        if not self.tty and tenth == self._shown:
            return
        self._shown = tenth
        filled = 30 * self.done // max(self.total, 1)
        rate = self.done / max(time.perf_counter() - self.start, 1e-9)
        text = (f"[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} cases, "
                f"{self.failed} not ok, {rate:.1f}/s")
        self.stream.write(("\r" + text) if self.tty else text + "\n")
        if self.tty and self.done == self.total:
            self.stream.write("\n")
        self.stream.flush()


def _client(workers, scheduler):
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=50)
    return Client(cluster), cluster


def run_study(study, out_dir, fmu_dir="build/fmus", workers=None, scheduler=None, csv=False, progress=True):
    """Run every case of ``study`` not yet in ``out_dir``; write the results table and plot.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the local cluster (default: one per core).
    scheduler : str, optional
        Address of an existing Dask scheduler; no local cluster is started.

    Returns
    -------
    dict
        ``cases``, ``skipped`` (done before), ``ran``, ``not_ok`` and ``seconds``.
    """
    from crane_fmu import systems

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    settings = study.settings()
    cases = study.cases()
    done = read_journal(out_dir)
    pending = [c for c in cases if case_id(c, settings) not in done]
    bar = Progress(len(cases), len(cases) - len(pending)) if progress else None
    start = time.perf_counter()
    rows_ran = []
    with systems.open_system(study.system) as system:
        systems.resolve(system, fmu_dir)
        units = _check_names(study, system, fmu_dir)
        if pending:
            shipped = shippable(systems.at_step(system, fmu_dir, study.step), fmu_dir)
            to_run = []
            for case in pending:  # the model's parameter rules, before anything is shipped
                try:
                    systems.check_parameters(system.with_parameters(case_parameters(case)), fmu_dir)
                    to_run.append(case)
                except ValueError as exc:
                    rows_ran.append(_invalid_row(case, settings, str(exc), study.metrics))
            rows_ran += run_on_dask(run_case, to_run, shipped, out_dir, workers, scheduler, rows_ran, bar,
                                    settings=settings, metric_names=study.metrics)
    done.update({r["case_id"]: r for r in rows_ran})
    rows = [done[case_id(c, settings)] for c in cases]
    write_table(rows, out_dir / "results.parquet")
    if csv:
        write_table(rows, out_dir / "results.csv")
    if study.plot or len(study.grid) + len(study.sampled) >= 2:
        from .plots import plot_study

        plot_study(rows, study, out_dir / "plot.png", units=units)
    return {"cases": len(cases), "skipped": len(cases) - len(pending), "ran": len(rows_ran),
            "not_ok": sum(r["status"] != "ok" for r in rows), "seconds": time.perf_counter() - start}


def run_on_dask(task, items, shared, out_dir, workers=None, scheduler=None, known=(), bar=None, **kwargs):
    """Run ``task(item, shared, **kwargs)`` for every item on Dask; return the rows it gave.

    ``shared`` travels to every worker once. Each finished row is appended to
    the journal in ``out_dir`` at once, after the rows ``known`` without running
    (e.g. cases refused before shipping), so an interrupted run resumes.
    """
    from distributed import as_completed

    rows = []
    with open(Path(out_dir) / JOURNAL, "a") as journal:
        def keep(row):
            journal.write(json.dumps(row, default=_plain) + "\n")
            journal.flush()
            if bar:
                bar.update(row)

        for row in known:
            keep(row)
        if not items:
            return rows
        client, cluster = _client(workers, scheduler)
        try:
            scattered = client.scatter([shared], broadcast=True)[0]
            for future in as_completed(client.map(task, items, [scattered] * len(items), pure=False, **kwargs)):
                rows.append(future.result())
                keep(rows[-1])
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return rows


def _check_names(study, system, fmu_dir):
    """Check that every varied or fixed variable is a parameter or input of its instance, and that the
    system has a crane; return ``{"instance.variable": unit}`` of the varied and fixed variables."""
    from crane_fmu.analysis.metrics import CRANE_OUTPUTS
    from crane_fmu.cosim.system import read_fmu, settable_variables

    fmus = system.fmus(fmu_dir)
    known = {name: settable_variables(path) for name, path in fmus.items()}
    names = list(study.fixed) + [n for names, *_ in list(study.grid.values()) + list(study.sampled.values())
                                 for n in names]
    for name in names:
        instance, _, variable = name.partition(".")
        if instance not in known:
            raise ValueError(f"parameter {name!r}: system {system.name} has no instance {instance!r}; instances: "
                             + ", ".join(known))
        if variable not in known[instance]:
            raise ValueError(f"parameter {name!r}: {instance} has no parameter or input {variable!r}; valid: "
                             + ", ".join(known[instance]))
    outputs = {name: {v.name for v in read_fmu(path).modelVariables if v.causality == "output"}
               for name, path in fmus.items()}
    if not any(set(CRANE_OUTPUTS) <= names for names in outputs.values()):
        raise ValueError(f"the sweep's metrics need an instance with outputs {', '.join(CRANE_OUTPUTS)}; system "
                         f"{system.name} has none")
    units = {}
    for name in names:
        instance, _, variable = name.partition(".")
        units[name] = next(v.unit for v in read_fmu(fmus[instance]).modelVariables if v.name == variable)
    return units


def _plain(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__}")


def write_table(rows, path):
    """Write the rows as Parquet (``.parquet``) or CSV, under a temporary name then renamed."""
    import pyarrow as pa

    path = Path(path)
    table = pa.Table.from_pylist(rows)
    partial = path.with_name(f".{path.name}.partial")
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        pq.write_table(table, partial)
    else:
        import pyarrow.csv as pcsv

        pcsv.write_csv(table, partial)
    os.replace(partial, path)
