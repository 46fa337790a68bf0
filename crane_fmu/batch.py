"""One way to run many cases: a local process pool or a Dask cluster, with a journal, resume and progress.

Used by ``crane-fmu sweep``, ``compare``, ``reproduce`` and the controllers' target checks. A
task is a plain function of one item (and, on Dask, of data shared by every item, sent to each
worker once); its results come back in the order they finish. With a journal, each result (a
JSON-able row with a ``case_id``) is appended to it at once, so an interrupted batch resumes
from :func:`read_journal`; a worker that dies has its running items rescheduled (by Dask, or by the
local pool of chunks).
"""

import itertools
import json
import math
import multiprocessing
import multiprocessing.forkserver
import os
import queue
import signal
import sys
import tempfile
import time
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager, nullcontext
from pathlib import Path

from crane_fmu.pool import chunks_in_pool

JOURNAL = "cases.jsonl"
LOOPBACK = "127.0.0.1"  # a local cluster's scheduler, workers and nannies listen here only
DEFAULT_DASHBOARD = "127.0.0.1:0"  # its dashboard: this machine only, a port the OS picks
DASHBOARD = None  # where --dashboard asks it to listen (None: not given, DEFAULT_DASHBOARD)


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
    """A one-line progress bar on stderr (a line per 10 % when stderr is not a terminal): the cases done, those not
    ok, the rate and the time left.

    ``total`` items, ``done`` of them finished before, ``failed`` of those not ok (so that a resumed
    batch counts as its summary does); ``ok(result)`` tells a result that is not counted as "not ok"
    (default: its ``status`` is ``ok``). The rate is of the items run now, and the time left is what the
    items still to run take at that rate.
    """

    def __init__(self, total, done=0, stream=None, ok=lambda result: result.get("status") == "ok", failed=0):
        stream = sys.stderr if stream is None else stream
        self.total, self.done, self.failed, self.stream, self.ok = total, done, failed, stream, ok
        self.start, self.tty, self.done_before = time.perf_counter(), stream.isatty(), done
        self._shown, self._drawn = -1, -1.0

    def update(self, result):
        self.done += 1
        self.failed += not self.ok(result)
        tenth, now = 10 * self.done // max(self.total, 1), time.perf_counter()
        if (tenth == self._shown if not self.tty else now - self._drawn < 0.1) and self.done < self.total:
            return  # a line per tenth in a file, at most ten a second on a terminal
        self._shown, self._drawn = tenth, now
        filled = 30 * self.done // max(self.total, 1)
        rate = (self.done - self.done_before) / max(now - self.start, 1e-9)
        left = f", {_duration((self.total - self.done) / rate)} left" if rate > 0 and self.done < self.total else ""
        text = (f"[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} cases, "
                f"{self.failed} not ok, {rate:.1f}/s{left}")
        self.stream.write(("\r" + text + "\x1b[K") if self.tty else text + "\n")  # on a terminal: the rest cleared
        if self.tty and self.done == self.total:
            self.stream.write("\n")
        self.stream.flush()


def _duration(seconds):
    """``"42 s"``, ``"3 min 05 s"``, ``"2 h 07 min"``."""
    seconds = round(seconds)
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"


def run_batch(task, items, shared=None, *, on="processes", workers=None, scheduler=None, journal=None, known=(),
              progress=None, chunked=False, collect=True, on_row=None, lost=None, **kwargs):
    """Run ``task(item, **kwargs)`` (``task(item, shared, **kwargs)`` with ``shared``) for every item.

    Parameters
    ----------
    on : {"processes", "dask"}
        A local process pool of ``workers`` processes (one per core by default; one runs the
        items in this process), or Dask: a local cluster of ``workers`` processes, or the
        cluster whose scheduler is at ``scheduler``. Tasks and items must pickle.
    journal : path, optional
        A JSON-lines file: the rows ``known`` (finished without running), then each result as
        it finishes, are appended to it at once.
    progress : Progress, optional
        Told of every row (``known`` ones too).
    chunked : bool
        Each item is a chunk ``(kind, cases)`` and ``task`` yields the row of each case (a dict with a
        ``case_id``) as it finishes. Each row is reported the moment it is yielded, so a worker that dies in
        a chunk loses none of the rows it yielded: Dask runs the chunk again elsewhere and the rows already
        kept are not kept twice; a local pool (:func:`crane_fmu.pool.chunks_in_pool`) runs the case it died
        in again alone, then the rest of its chunk. ``items`` may then be any iterable: a few chunks per
        worker are taken at a time, the next as one ends (a batch of any size).
    lost : callable, optional
        In a local pool with ``chunked``: ``lost(case, why)`` is the row of a case whose worker died twice
        running it (None: such a case ends the batch; on Dask, a chunk that kills every worker it is tried on
        ends it: KilledWorker).
    collect : bool
        Return the results; False: only how many there were (the journal has them).
    on_row : callable, optional
        Given each result (``known`` ones too) as it is kept, after the journal.

    Returns
    -------
    list or int
        The results of ``items`` (with ``chunked``: the rows of their cases), in the order they finished,
        ``known`` ones first (their number, without ``collect``).
    """
    extra = () if shared is None else (shared,)
    kept = set()
    with open(journal, "a") if journal else nullcontext() as sink:
        if sink and not _ends_a_line(journal):
            sink.write("\n")  # a line torn when a run was killed: ended, so that the next row is a line of its own
        def keep(result):
            if chunked:
                if result["case_id"] in kept:  # reported by a chunk that then ran again
                    return None
                kept.add(result["case_id"])
            if sink:
                sink.write(json.dumps(result, default=_plain) + "\n")
                sink.flush()
            if progress:
                progress.update(result)
            if on_row:
                on_row(result)
            return result

        def kept_rows(results, before=()):
            results = (r for r in map(keep, results) if r is not None)
            return [*before, *results] if collect else len(before) + sum(1 for _ in results)

        known = [keep(row) for row in known]
        if chunked:  # any iterable: look at its first chunk
            items = iter(items)
            first = next(items, None)
            items = itertools.chain([first], items) if first is not None else []
        if not items:  # nothing to run: no cluster started
            return kept_rows((), known)
        if on == "dask":
            run = _chunks_on_dask if chunked else _on_dask
            return kept_rows(run(task, items, extra, workers, scheduler, kwargs), known)
        if on != "processes":
            raise ValueError(f"on must be processes or dask, got {on!r}")
        workers = workers or os.cpu_count() or 1
        if workers == 1:
            return kept_rows((r for item in items for r in (task(item, *extra, **kwargs) if chunked else
                                                            [task(item, *extra, **kwargs)])), known)
        if chunked:
            return kept_rows(chunks_in_pool(task, items, extra, workers, kwargs, worker_context(), start_worker, lost),
                             known)
        with worker_pool(workers) as pool:
            futures = [pool.submit(_listed, task, item, *extra, **kwargs) if chunked else
                       pool.submit(task, item, *extra, **kwargs) for item in items]
            try:
                return kept_rows((r for future in as_completed(futures) for r in
                                  (future.result() if chunked else [future.result()])), known)
            except BaseException:  # Ctrl-C (the workers ignore it) or a failed item: drop what has not begun
                pool.shutdown(wait=True, cancel_futures=True)
                raise


def _ends_a_line(path):
    """Whether the file at ``path`` is empty or ends with a newline."""
    with open(path, "rb") as f:
        if f.seek(0, os.SEEK_END) == 0:
            return True
        f.seek(-1, os.SEEK_END)
        return f.read(1) == b"\n"


def _listed(task, chunk, *extra, **kwargs):
    return list(task(chunk, *extra, **kwargs))


@contextmanager
def _dask_client(workers, scheduler):
    """A Dask client of the cluster at ``scheduler``, or of a local cluster of ``workers`` processes (closed after)."""
    from distributed import Client  # optional: the dask extra

    if scheduler:
        try:
            client, cluster = Client(scheduler, timeout=10), None
        except (OSError, TimeoutError) as exc:
            raise ValueError(f"scheduler {scheduler}: cannot connect ({str(exc).splitlines()[0]})") from None
    else:
        # The workers ignore Ctrl-C (the disposition is inherited by the processes they start): only this
        # process stops, closes the cluster and says so in one line, no traceback from every worker.
        handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            cluster = local_cluster(workers or os.cpu_count() or 1)
        finally:
            signal.signal(signal.SIGINT, handler)
        client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


# What a worker process runs (a sweep's, a board's case or picture), imported once by the fork server
WORKER_PRELOAD = ["distributed", "crane_fmu.compare"]


def worker_context(preload=(), dask=True):
    """The multiprocessing context of this package's worker processes: 'forkserver' where the platform has it, each
    worker forked from a server process that has no other thread and has imported :data:`WORKER_PRELOAD` once
    (a fork of this process can hang for ever: another of its threads may hold a lock at that moment, a logging
    handler's or a queue's, which stays held in the child), else 'spawn' (Windows). The first call starts the
    server: ``preload`` names more modules for it to import (one that cannot be imported is left out), ``dask``
    False leaves Dask's out (a batch in a local process pool does not use it)."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload([m for m in WORKER_PRELOAD if dask or m != "distributed"] + list(preload))
    multiprocessing.forkserver.ensure_running()  # with this package's preload, not the one Dask would set
    return context


def start_worker(environment):
    """A worker process's start: the environment of the process that asked for it (a fork server's children have
    the server's own, as it was when it started), Ctrl-C ignored."""
    os.environ.clear()
    os.environ.update(environment)
    tempfile.tempdir = None  # the temporary folder as TMPDIR now says
    ignore_interrupts()


def worker_pool(workers):
    """A pool of ``workers`` processes started as :func:`worker_context` starts them, each with this environment
    and ignoring Ctrl-C (:func:`start_worker`)."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=worker_context(), initializer=start_worker,
                               initargs=(dict(os.environ),))


def local_cluster(workers):
    """A local Dask cluster of ``workers`` single-threaded worker processes on the loopback, started as
    :func:`worker_context` starts them."""
    import dask
    from distributed import LocalCluster

    with dask.config.set({"distributed.worker.multiprocessing-method": worker_context().get_start_method(),
                          # not what a batch looks at: Dask's profiler (a look at every thread's stack each 10 ms)
                          # and its monitors of memory and system (each 0.1 and 0.5 s) less often
                          "distributed.worker.profile.enabled": False,
                          "distributed.worker.memory.monitor-interval": "1s",
                          "distributed.admin.system-monitor.interval": "2s"}):
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host=LOOPBACK,
                            dashboard_address=DASHBOARD or DEFAULT_DASHBOARD, silence_logs=50, env=dict(os.environ))


def _shared_column(client, items, extra):
    """The columns of ``client.map``'s arguments after the items: the shared data scattered to every worker once."""
    return [[client.scatter([extra[0]], broadcast=True)[0]] * len(items)] if extra else []


def _on_dask(task, items, extra, workers, scheduler, kwargs):
    """The results of ``task`` on Dask as they finish; ``extra`` (the shared data) scattered to every worker once."""
    from distributed import as_completed as finished

    with _dask_client(workers, scheduler) as client:
        for future in finished(client.map(task, items, *_shared_column(client, items, extra), pure=False,
                                          **kwargs)):
            yield future.result()


def _chunks_on_dask(task, chunks, extra, workers, scheduler, kwargs):
    """The rows of ``task``'s chunks on Dask: each as its worker reports it (an event of a topic of this batch),
    then each chunk's rows again when it finishes (those of a chunk whose worker died before it could report
    them). Chunks are taken from the iterable as they are sent: four per worker thread (16 at least) at a time."""
    with _dask_client(workers, scheduler) as client:
        topic = f"crane-fmu-batch-{uuid.uuid4().hex}"
        reported = queue.SimpleQueue()
        client.subscribe_topic(topic, lambda event: reported.put(event[1]["row"]))  # the scheduler adds "worker"
        try:
            shared = [client.scatter([extra[0]], broadcast=True)[0]] if extra else []
            chunks, remaining = iter(chunks), set()

            def send(count):
                for chunk in itertools.islice(chunks, count):
                    remaining.add(client.submit(_reporting, chunk, *shared, pure=False, task=task, topic=topic,
                                                **kwargs))

            send(max(16, 4 * sum(client.nthreads().values())))
            while remaining:
                try:
                    yield reported.get(timeout=0.05)
                    continue
                except queue.Empty:
                    pass
                for future in [f for f in remaining if f.done()]:
                    remaining.discard(future)
                    yield from future.result()
                    send(1)
        finally:
            client.unsubscribe_topic(topic)


def _reporting(chunk, *extra, task, topic, **kwargs):
    """Run ``task`` on a chunk on a Dask worker, reporting each row under ``topic`` as it is yielded; return them."""
    from distributed import get_worker

    worker, rows = get_worker(), []
    for row in task(chunk, *extra, **kwargs):
        worker.log_event(topic, {"row": row})
        rows.append(row)
    return rows


def ignore_interrupts():
    """Ignore Ctrl-C in a worker process: the parent handles it (one line, not a traceback per worker)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _plain(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__}")
