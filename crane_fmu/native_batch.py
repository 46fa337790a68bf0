"""The batch path of native FMUs: many cases of one system per task, on instances reused through reset.

The sweep runner and ``compare`` hand their cases to :func:`crane_fmu.batch.run_batch` as the items
of :func:`items`: the cases whose FMUs are all native (C with no Python inside: :func:`native`) in
chunks of cases of one system, every other case alone. For a chunk, a worker keeps a
:class:`~crane_fmu.cosim.reused.ReusedRunner` of the system: its instances are reset from case to
case, each run is one call into the master's compiled loop, and only the outputs the case's
figures are made from are kept (:func:`kept_outputs`). Each case's row is made by the per-case
path's own function (``crane_fmu.sweep.runner.case_row``, ``crane_fmu.compare.score_row``) from
the same numbers, its figures by the metrics' C twin (:mod:`crane_fmu.analysis.fast_metrics`), so
every figure is the per-case path's bit for bit (tested). A case alone runs as before
(``run_case``, ``run_score_case``): the Python FMUs keep their path. Rows are reported as each case
finishes, so a worker that dies in a chunk loses none of the cases it finished.
"""

import functools
import hashlib
import io
import math
import threading
import time
import zipfile
from collections import OrderedDict

from crane_fmu.cosim import Connection
from crane_fmu.cosim.reused import ReusedRunner, can_reuse

CASES_PER_CHUNK = 64  # at most: a task's share of Dask's per-task cost (about 2 ms) is then small
RUNNERS_KEPT = 8  # systems a worker keeps instances of (compare sends chunks of many systems)


@functools.lru_cache(maxsize=256)
def _native(digest, data):
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        names = z.namelist()
    return not any(n.endswith("slavemodule.txt") for n in names) and any(n.startswith("binaries/") for n in names)


def native(data, digest=None):
    """Whether the FMU of the bytes ``data`` (its sha256 ``digest``, if known) is native: its binaries hold the
    model, with no Python inside (a pythonfmu FMU, ours or stock, and a container FMU holding one, have a
    ``slavemodule.txt``)."""
    return _native(digest or hashlib.sha256(data).hexdigest(), data)


def batchable(blobs, algorithm):
    """Whether the cases of a system of the FMUs ``blobs`` (``[(digest, bytes)]``) take the batch path: every FMU
    native, and runs of ``algorithm`` can reuse instances (:func:`~crane_fmu.cosim.reused.can_reuse`)."""
    return can_reuse(algorithm) and all(native(data, digest) for digest, data in blobs)


def items(cases, batched, system_of=lambda case: None, size=None):
    """The items of :func:`~crane_fmu.batch.run_batch` (``chunked``) for ``cases``: ``("batch", chunk)`` of the
    cases of one system that take the batch path, ``("case", [case])`` of every other case, in their order.

    Parameters
    ----------
    batched : callable
        Whether a case takes the batch path (:func:`batchable` of its FMUs and master).
    system_of : callable
        A case's system, hashable (its FMUs, connections, master, step and stop time): a chunk is of one system.
    size : int, optional
        Cases per chunk: by default a sixteenth of those of the batch path, at most :data:`CASES_PER_CHUNK`, which
        leaves every worker several chunks, so that the last ones end together.
    """
    groups, alone = OrderedDict(), []
    for case in cases:
        if batched(case):
            groups.setdefault(system_of(case), []).append(case)
        else:
            alone.append(("case", [case]))
    size = size or max(1, min(CASES_PER_CHUNK, math.ceil(sum(map(len, groups.values())) / 16)))
    return [("batch", group[i:i + size]) for group in groups.values() for i in range(0, len(group), size)] + alone


def chunked(cases, batched, count):
    """:func:`items` of the ``count`` cases of one system that ``cases`` gives, made as they are taken (a study of any
    size): chunks of them where ``batched``, else each case alone."""
    size = max(1, min(CASES_PER_CHUNK, math.ceil(count / 16)))
    chunk = []
    for case in cases:
        if not batched:
            yield "case", [case]
            continue
        chunk.append(case)
        if len(chunk) == size:
            yield "batch", chunk
            chunk = []
    if chunk:
        yield "batch", chunk


_THREAD = threading.local()  # each thread's runners (a Dask worker may run chunks in several threads)


def runner(fmus, connections, algorithm):
    """This thread's :class:`ReusedRunner` of the system (made at its first case; the least recently used of more
    than :data:`RUNNERS_KEPT` is closed)."""
    runners = _THREAD.__dict__.setdefault("runners", OrderedDict())  # by system: the most recently used last
    key = (tuple(sorted((name, str(path)) for name, path in fmus.items())), tuple(map(tuple, connections)),
           algorithm)
    if key in runners:
        runners.move_to_end(key)
        return runners[key]
    while len(runners) >= RUNNERS_KEPT:
        runners.popitem(last=False)[1].close()
    runners[key] = made = ReusedRunner(fmus, [Connection(*c) for c in connections], algorithm)
    return made


def kept_outputs(output_names, signals=False, extra=()):
    """``[(signal, output)]``: the outputs a row is made from, asked of :func:`crane_fmu.analysis.metrics.crane_signals`
    itself on a run of outputs ``output_names`` (the plant's positions, velocities and swing angles, the demands;
    with ``signals`` also its hook, load and cable, which a board keeps for its pictures; the plant's outputs
    ``extra``, which a scenario's own measures read); a signal it makes of zeros is not an output."""
    import numpy as np

    from crane_fmu.analysis import metrics

    names = ["time", *output_names]
    probe = {name: np.array([i + 1.0]) for i, name in enumerate(names)}  # each column holds its place, from 1
    crane = metrics.crane_signals(probe)["crane"]
    extra = ((*crane.hook, *crane.load, *filter(None, [crane.cable])) if signals else ()) + tuple(extra)
    found = []

    def collect(value, signal):
        if isinstance(value, np.ndarray) and value.shape == (1,) and value[0] >= 1:
            found.append((signal, names[int(value[0]) - 1]))
        elif isinstance(value, dict):
            for key, item in value.items():
                collect(item, key)
        elif isinstance(value, (list, tuple)):
            for item in value:
                collect(item, signal)

    collect(metrics.crane_signals(probe, extra), None)
    return list(dict((output, (signal, output)) for signal, output in found if output != "time").values())


def run(runs, stop_time, step, parameters, kept):
    """One case from time 0: ``(columns, error)`` as the per-case path records them: ``{"time": ..., output: ...}``
    of the ``kept`` outputs (views of the runner's block; empty when the run stopped before its first point), and
    the FmiError that stopped it (None: none did)."""
    outputs = [output for _, output in kept]
    rows, error = runs.run(0.0, stop_time, step, parameters, outputs)
    return {name: rows[:, i] for i, name in enumerate(["time", *outputs])}, error


def measure():
    """The module that computes the rows' figures: the metrics' C twin where it gives their bits
    (:func:`crane_fmu.analysis.fast_metrics.available`), else the metrics module."""
    from crane_fmu.analysis import fast_metrics, metrics

    return fast_metrics if fast_metrics.available() else metrics


def sweep_chunk(item, system, settings, metric_names):
    """The rows of ``crane_fmu.sweep.runner.run_case`` of an item of :func:`items` (its cases of a study's
    shippable ``system``), yielded as they finish."""
    from crane_fmu.sweep.runner import case_parameters, case_row, local_fmus, run_case

    kind, cases = item
    if kind == "case":
        yield from (run_case(case, system, settings, metric_names) for case in cases)
        return
    runs = runner(local_fmus(system["blobs"]), system["connections"], settings["algorithm"])
    kept, figures = kept_outputs(runs.output_names), measure()
    for case in cases:
        start = time.perf_counter()
        columns, error = run(runs, settings["stop_time"], settings["step"],
                             case_parameters(case, system["parameters"], system["binding"], system["told"]), kept)
        row = case_row(case, settings, metric_names, columns, error, figures)
        row["duration_s"] = time.perf_counter() - start
        yield row


def score_chunk(item, blobs):
    """The rows of ``crane_fmu.compare.run_score_case`` of an item of :func:`items` (board cases), yielded as they
    finish."""
    from crane_fmu.analysis.scenarios import measured_outputs
    from crane_fmu.compare import run_score_case, score_row
    from crane_fmu.sweep.runner import local_fmus

    kind, cases = item
    if kind == "case":
        yield from (run_score_case(case, blobs) for case in cases)
        return
    figures, last, kept = measure(), (None, None), {}
    for case in cases:
        start = time.perf_counter()
        # the runner of a case of the system of the case before (a chunk of items holds one system) is that case's,
        # not looked up again; the outputs kept of each system's scenario are looked up once a chunk
        system = repr([case[k] for k in ("fmus", "connections", "master")])
        if system != last[0]:
            last = system, runner(local_fmus({name: (digest, blobs[digest]) for name, digest in
                                              case["fmus"].items()}), case["connections"], case["master"])
        runs, which = last[1], (system, case["keep_signals"], case["scenario"])
        if which not in kept:
            kept[which] = kept_outputs(runs.output_names, case["keep_signals"], measured_outputs(case["scenario"]))
        columns, error = run(runs, case["stop_time"], case["step"], case["parameters"], kept[which])
        row = score_row(case, columns, error, figures)
        row["duration_s"] = time.perf_counter() - start
        yield row
