"""One way to run many cases: a local process pool or a Dask cluster, with a journal, resume and progress.

Used by ``crane-fmu sweep``, ``compare``, ``reproduce`` and the controllers' target checks. A
task is a plain function of one item (and, on Dask, of data shared by every item, sent to each
worker once); its results come back in the order they finish. With a journal, each result (a
JSON-able row with a ``case_id``) is appended to it at once, so an interrupted batch resumes
from :func:`read_journal`; a worker that dies has its running items rescheduled by Dask.
"""

import json
import math
import os
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import nullcontext
from pathlib import Path

JOURNAL = "cases.jsonl"


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
    """A one-line progress bar on stderr (a line per 10 % when stderr is not a terminal).

    ``total`` items, ``done`` of them finished before, ``failed`` of those not ok (so that a resumed
    batch counts as its summary does); ``ok(result)`` tells a result that is not counted as "not ok"
    (default: its ``status`` is ``ok``).
    """

    def __init__(self, total, done=0, stream=None, ok=lambda result: result.get("status") == "ok", failed=0):
        stream = sys.stderr if stream is None else stream
        self.total, self.done, self.failed, self.stream, self.ok = total, done, failed, stream, ok
        self.start, self.tty = time.perf_counter(), stream.isatty()
        self._shown = -1

    def update(self, result):
        self.done += 1
        self.failed += not self.ok(result)
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


def run_batch(task, items, shared=None, *, on="processes", workers=None, scheduler=None, journal=None, known=(),
              progress=None, **kwargs):
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

    Returns
    -------
    list
        The results of ``items``, in the order they finished.
    """
    extra = () if shared is None else (shared,)
    with open(journal, "a") if journal else nullcontext() as sink:
        def keep(result):
            if sink:
                sink.write(json.dumps(result, default=_plain) + "\n")
                sink.flush()
            if progress:
                progress.update(result)
            return result

        for row in known:
            keep(row)
        if not items:
            return []
        if on == "dask":
            return [keep(r) for r in _on_dask(task, items, extra, workers, scheduler, kwargs)]
        if on != "processes":
            raise ValueError(f"on must be processes or dask, got {on!r}")
        workers = workers or os.cpu_count() or 1
        if workers == 1:
            return [keep(task(item, *extra, **kwargs)) for item in items]
        with ProcessPoolExecutor(max_workers=workers, initializer=ignore_interrupts) as pool:
            futures = [pool.submit(task, item, *extra, **kwargs) for item in items]
            try:
                return [keep(future.result()) for future in as_completed(futures)]
            except BaseException:  # Ctrl-C (the workers ignore it) or a failed item: drop what has not begun
                pool.shutdown(wait=True, cancel_futures=True)
                raise


def _on_dask(task, items, extra, workers, scheduler, kwargs):
    """The results of ``task`` on Dask as they finish; ``extra`` (the shared data) scattered to every worker once."""
    from distributed import Client, LocalCluster  # optional: the dask extra
    from distributed import as_completed as finished

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
            cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                                   dashboard_address=":0", silence_logs=50)  # a free port: no warning
        finally:
            signal.signal(signal.SIGINT, handler)
        client = Client(cluster)
    try:
        columns = [items] + ([[client.scatter([extra[0]], broadcast=True)[0]] * len(items)] if extra else [])
        for future in finished(client.map(task, *columns, pure=False, **kwargs)):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def ignore_interrupts():
    """Ignore Ctrl-C in a worker process: the parent handles it (one line, not a traceback per worker)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _plain(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__}")
