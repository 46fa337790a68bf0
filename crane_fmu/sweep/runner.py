"""Runs a study's cases on Dask: a local cluster by default, or any existing scheduler.

The FMU files travel to the workers once (scattered, then cached on each
worker's disk by content hash), so workers need no shared file system. Every
finished case is appended to ``cases.jsonl`` in the output folder at once; a
re-run reads it back and skips the cases already done. A case that fails is a
row with its status and message, never the end of the study; a worker that
dies has its running cases rescheduled by Dask on the others.
"""

import hashlib
import math
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from crane_fmu import DEFAULT_FMU_DIR, crane_parameters, laws, native_batch, systems
from crane_fmu.analysis import metrics
from crane_fmu.batch import JOURNAL, Progress, run_batch
from crane_fmu.cosim import ArrayRecorder, FmiError, simulate
from crane_fmu.cosim.system import read_fmu, split_name, unfed_inputs

from .plots import plot_study
from .results import JournalIndex, write_results
from .spec import case_id


def shippable(system, fmu_dir, binding=None, told=None):
    """What a worker needs to run cases of a prepared ``system``: FMU bytes by instance, connections, parameter
    values, ``binding``, the instances each crane parameter binds, and ``told``, the values a controller was told
    and their sources (:func:`case_parameters`).

    ``blobs`` is ``{instance: (sha256, bytes)}``; workers cache each FMU once by its hash.
    """
    fmus, connections = system.resolve(fmu_dir)
    blobs = {}
    for name, path in fmus.items():
        law = laws.is_law(path)  # a law file: its bytes, named <digest>.py[:NAME] (local_fmus)
        data = Path(laws.law_file(path) if law else path).read_bytes()
        suffix = str(path)[len(str(laws.law_file(path).with_suffix(""))):] if law else ""
        blobs[name] = (hashlib.sha256(data).hexdigest()[:20] + suffix, data)
    return {"blobs": blobs, "connections": connections, "parameters": system.parameters, "binding": binding or {},
            "told": told or {}}


def local_fmus(blobs):
    """Write each FMU once into this machine's cache; return ``{instance: path}``."""
    cache = Path(tempfile.gettempdir()) / "crane_fmu_sweep_cache"
    cache.mkdir(exist_ok=True)
    paths = {}
    for name, (digest, data) in blobs.items():
        digest, dot, law = digest.partition(".")  # a law file's: "<digest>.py" or "<digest>.py:NAME"
        path = cache / (f"{digest}.py" if dot else f"{digest}.fmu")
        if not path.exists():
            partial = cache / f".{digest}.{os.getpid()}.partial"
            partial.write_bytes(data)
            os.replace(partial, path)
        paths[name] = f"{path}{law[2:]}" if dot else path
    return paths


def case_parameters(case, base=None, binding=None, told=None):
    """``{"plant.l1": 1.5}`` -> ``{"plant": {"l1": 1.5}}``, over the system's own values ``base``; a crane value
    (``"crane.l2"``) set on the instances ``binding`` names for it (:func:`shippable`) that the case gives no
    value of their own; a value a controller was told (``told``: ``{"controller.x_d": "planner.x_d"}``) follows the
    case's value of its source, unless the case gives the controller's own."""
    values = {}
    followed = {key: case[source] for key, source in (told or {}).items() if source in case}
    for key, value in {**followed, **case}.items():
        instance, _, variable = key.partition(".")
        values.setdefault(instance, {})[variable] = value
    crane = values.pop(crane_parameters.CRANE, {})
    parameters = {name: dict(v) for name, v in (base or {}).items()}
    for instance, own in crane_parameters.bind_values(values, crane, binding or {}).items():
        parameters.setdefault(instance, {}).update(own)
    return parameters


def _invalid_row(case, settings, error, metric_names):
    return {"case_id": case_id(case, settings), **case, "status": "invalid", "error": error,
            "metrics_version": settings.get("metrics_version"), **dict.fromkeys(metric_names), "duration_s": 0.0}


def run_case(case, system, settings, metric_names):
    """Co-simulate one case of a :func:`shippable` system; return its row: parameters, metrics, status, error.

    Status is ``ok`` (ran to the stop time) or ``failed`` (an FMU stopped the
    run; the metrics cover the run up to there).
    """
    start = time.perf_counter()
    recorder, error = ArrayRecorder(), None
    try:
        simulate(local_fmus(system["blobs"]), system["connections"], settings["stop_time"], settings["step"],
                 settings["algorithm"], case_parameters(case, system["parameters"], system["binding"],
                                                        system["told"]), recorder)
    except FmiError as exc:
        error = exc
    row = case_row(case, settings, metric_names, recorder.columns() if recorder.names else None, error)
    row["duration_s"] = time.perf_counter() - start
    return row


def case_row(case, settings, metric_names, columns, error, measure=metrics):
    """A case's row (without ``duration_s``) from its recorded ``columns`` (``{name: array}``, None when the run
    stopped before its first communication point) and the :class:`FmiError` that stopped it (None: none did);
    ``measure``: the metrics module, or its twin of the same figures (``crane_fmu.analysis.fast_metrics``)."""
    row = {"case_id": case_id(case, settings), **case, "status": "ok" if error is None else "failed",
           "error": None if error is None else str(error), "metrics_version": settings.get("metrics_version")}
    values = dict.fromkeys(metric_names)
    if columns and len(columns["time"]):  # else: failed before the first communication point
        s = measure.crane_signals(columns)
        swing = list(s["swing"].values())
        values = measure.closed_loop_metrics(s["time"], s["position"][0], s["swing"], s["demand"][0],
                                             row["status"] == "ok")
        band = math.radians(settings["settling_band_deg"])
        values["settling_band_s"] = measure.settling_time(s["time"], swing, band)
        # "converges" only where the study's settling time exists too (a narrower band than 0.1 deg)
        values["outcome"] = measure.classify(s["time"], swing, row["status"] == "ok", min(band, metrics.SETTLED_BAND))
    row.update({name: values.get(name) for name in metric_names})
    return row


def run_study(study, out_dir, fmu_dir=DEFAULT_FMU_DIR, workers=None, scheduler=None, csv=False, progress=True,
              strict=False, warn=None):
    """Run every case of ``study`` not yet in ``out_dir``; write the results table and plot.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the local cluster (default: one per core).
    scheduler : str, optional
        Address of an existing Dask scheduler; no local cluster is started.
    strict : bool
        Refuse (ValueError) a study whose system has an input that nothing feeds and neither the system nor the
        study gives a value (:func:`crane_fmu.cosim.system.unfed_inputs`); else each is given to ``warn``
        (default: a warning on stderr).

    Returns
    -------
    dict
        ``cases``, ``skipped`` (done before), ``ran``, ``not_ok`` and ``seconds``.
    """
    out_dir = Path(out_dir)
    # in every case's id: rows of another metrics version run again
    settings = {**study.settings(), "metrics_version": metrics.VERSION}
    total, done = study.case_count(), JournalIndex(out_dir / JOURNAL)
    start = time.perf_counter()
    with systems.open_system(study.system) as system:
        told = {}
        if study.use:
            system, settings = _used(system, study.use, fmu_dir, settings, told)
        fmus, connections = systems.resolve(system, fmu_dir)
        units, crane = _check_names(study, system, fmu_dir)
        metric_names = study.metrics_of(crane, f"system {system.name}")
        given = {name: dict(values) for name, values in system.parameters.items()}
        for instance, variable in (name.split(".", 1) for name in units):  # the study's varied and fixed values
            given.setdefault(instance, {})[variable] = None
        lines = unfed_inputs(fmus, connections, given)
        if strict and lines:
            raise ValueError(f"--strict: {'; '.join(lines)}")
        for line in lines:
            (warn or (lambda text: print(f"crane-fmu: warning: {text}", file=sys.stderr)))(line)
        out_dir.mkdir(parents=True, exist_ok=True)  # only now: a refused study leaves no folder behind
        binding = crane_parameters.bound(system, systems.modelled(system))  # before prepare binds the crane's
        shipped = shippable(systems.prepare(system, study.step, study.stop_time, check=False), fmu_dir, binding, told)
        skipped = failed_before = to_run = 0
        invalid, checked = {}, {}
        for case in study.iter_cases():  # the model's parameter rules, before anything is shipped
            key = case_id(case, settings)
            if key in done:
                skipped += 1
                failed_before += not done.ok(key)
                continue
            try:
                systems.check_parameters(replace(system, parameters=case_parameters(
                    case, shipped["parameters"], shipped["binding"], shipped["told"])), checked)
                to_run += 1
            except ValueError as exc:
                invalid[key] = _invalid_row(case, settings, str(exc), metric_names)
        bar = Progress(total, skipped, failed=failed_before) if progress else None
        ran = len(invalid)
        if ran or to_run:
            cases = (c for c in study.iter_cases() if (key := case_id(c, settings)) not in done and key not in invalid)
            # the batch path where the FMUs are native, else a case at a time; the cases made as they are sent
            native = all("." not in d for d, _ in shipped["blobs"].values()) and native_batch.batchable(
                shipped["blobs"].values(), study.algorithm)  # a law file (<digest>.py) runs in Python
            ran += run_batch(native_batch.sweep_chunk, native_batch.chunked(cases, native, to_run), shipped, on="dask",
                             workers=workers, scheduler=scheduler, journal=out_dir / JOURNAL,
                             known=invalid.values(), progress=bar, chunked=True, collect=False, settings=settings,
                             metric_names=metric_names) - len(invalid)
    # the table from the journal, in the study's order, a block at a time
    done = JournalIndex(out_dir / JOURNAL)
    not_ok = write_results(done, lambda: (case_id(c, settings) for c in study.iter_cases()),
                           out_dir / "results.parquet")
    if csv:
        write_results(done, lambda: (case_id(c, settings) for c in study.iter_cases()), out_dir / "results.csv")
    else:  # an earlier run's table would read as this one's
        (out_dir / "results.csv").unlink(missing_ok=True)
    if study.plot or len(study.grid) + len(study.sampled) >= 2:
        plot_study(_plotted(out_dir / "results.parquet", study), study, out_dir / "plot.png", units=units)
    else:
        (out_dir / "plot.png").unlink(missing_ok=True)
    return {"cases": total, "skipped": skipped, "ran": ran, "not_ok": not_ok, "seconds": time.perf_counter() - start}


def _used(system, use, fmu_dir, settings, told):
    """``(system, settings)``: the study's system with the FMUs of its ``use`` table in their places, told the
    move as simulate tells them, and the settings (so every case id) naming those files by their sha256."""
    from crane_fmu.commands.common import UsageError
    from crane_fmu.commands.simulate import _keep_known, used_file

    overrides = {}
    for instance, path in use.items():
        if instance not in system.instances:
            raise ValueError(f"use.{instance}: system {system.name} has no instance {instance!r}; instances: "
                             f"{', '.join(system.instances)}")
        try:
            overrides[instance] = used_file(f"{instance}={path}", path)
        except UsageError as exc:
            raise ValueError(str(exc).replace("--use", "use")) from None
    system = system.with_instances(overrides)
    fmus, _ = systems.resolve(system, fmu_dir)
    system = _keep_known(system, fmus, list(system.replaced))
    system, notes = systems.tell_controllers(system, fmu_dir, sources=told)
    for note in notes:
        print(f"crane-fmu: note: {note}" + ("; each case's own where it sets it" if told else ""), file=sys.stderr)
    _, connections = systems.resolve(system, fmu_dir)  # as checked (a controller's optional inputs left out)
    system = replace(system, connections=tuple(connections), match_names=False, replaced={})
    digests = {name: hashlib.sha256(Path(laws.law_file(p) if laws.is_law(p) else p).read_bytes())
               .hexdigest() for name, p in overrides.items()}
    return system, {**settings, "use": digests, **({"told": told} if told else {})}  # in every case's id


def _plotted(path, study):
    """The rows of the results table with only the columns :func:`plot_study` reads."""
    import pyarrow.parquet as pq

    names = [n[0] for n, *_ in list(study.grid.values()) + list(study.sampled.values())]
    wanted = {study.plot.get("metric", "outcome"), *names, *study.plot.values()}
    return pq.read_table(path, columns=[n for n in pq.read_schema(path).names if n in wanted]).to_pylist()


def _check_names(study, system, fmu_dir):
    """Check that every varied or fixed variable is a parameter or input of its instance, and that the
    system has a crane; return ``({"instance.variable": unit}, crane)``: the varied and fixed variables, and the
    crane roles of the system's plant (what the metrics are named after)."""
    fmus = system.fmus(fmu_dir)
    known = systems.settable(system, fmus)
    names = list(study.fixed) + [n for names, *_ in list(study.grid.values()) + list(study.sampled.values())
                                 for n in names]
    for name in names:
        try:
            split_name(name, known)
        except ValueError as exc:
            raise ValueError(f"parameter {name!r}: system {system.name}: {exc}") from None
    outputs = {f"{name}.{v.name}": None for name, path in fmus.items() for v in read_fmu(path).modelVariables
               if v.causality == "output"}
    instance, plant = metrics.find_crane(outputs)
    if instance is None:
        raise ValueError(f"the sweep's metrics need a crane: an instance with a registered plant's outputs; system "
                         f"{system.name} has none")
    return {name: known[name.partition(".")[0]][name.partition(".")[2]][1] for name in names}, plant.crane


def write_table(rows, path):
    """Write the rows as Parquet (``.parquet``) or CSV, under a temporary name then renamed."""
    import pyarrow as pa  # start-up: pyarrow takes about 0.4 s to import

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
