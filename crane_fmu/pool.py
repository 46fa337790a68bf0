"""A local pool of processes for a batch's chunks that outlives a process that dies.

Each process has two pipes of its own: the chunk it is given, and each row it yields, one message each, back. So
this process always knows which chunk, and which of its cases, a process is running. When one dies (a crash in
an FMU's binary, the kernel's out-of-memory killer), the rows it sent are kept, a new process takes its place,
the case it was running is run again alone and the rest of its chunk after it. A case whose process dies
:data:`STRIKES` times is given to ``lost``, which makes its row (the board's: "failed", with why): one case cannot
end a batch of thousands. An exception a task raises ends the batch, as it always did.
"""

import collections
import os
import signal
from multiprocessing.connection import wait

STRIKES = 2  # a case whose process dies this many times is lost (the first death may be another's: a kill, OOM)


def chunks_in_pool(task, chunks, extra, workers, kwargs, context, start, lost=None):
    """The rows of ``task(chunk, *extra, **kwargs)`` for every chunk ``(kind, cases)`` of ``chunks`` (any iterable,
    taken as processes become free), each as its process yields it, in ``workers`` processes of ``context`` that
    run ``start(environment)`` first.

    Parameters
    ----------
    lost : callable, optional
        ``lost(case, why)``: the row of a case whose process died :data:`STRIKES` times running it (``why``: one
        line, the last death's signal or exit status); None: such a case ends the batch (RuntimeError, that line).
    """
    def fresh():
        return _Process(context, start, dict(os.environ), task, extra, kwargs)

    chunks, waiting = iter(chunks), collections.deque()  # waiting: (chunk, the deaths its first case has seen)
    pool = [fresh() for _ in range(workers)]
    try:
        while True:
            for i, process in enumerate(pool):
                if process.chunk is None and (waiting or (chunk := next(chunks, None)) is not None):
                    if process.ended():  # died idle, or in a chunk (below)
                        pool[i] = process = fresh()
                    process.give(*(waiting.popleft() if waiting else (chunk, 0)))
            busy = [p for p in pool if p.chunk is not None]
            if not busy:
                break
            ready = set(wait([p.rows for p in busy if not p.rows.closed] + [p.process.sentinel for p in busy]))
            for process in busy:
                if process.rows in ready or process.process.sentinel in ready:
                    yield from process.read()
                    if process.chunk is not None and process.ended():
                        yield from process.read()  # what it sent before it ended
                        yield from _died(process, waiting, lost)
        for process in pool:
            process.stop()
        for process in pool:
            process.process.join()
    finally:  # Ctrl-C or a failed task: no process is left running
        for process in pool:
            if process.process.is_alive():
                process.process.kill()
                process.process.join()


def _died(process, waiting, lost):
    """A process ended in its chunk: the case it was running waits to run again alone (or, at its last strike, its
    ``lost`` row is yielded), then the rest of the chunk."""
    (kind, cases), done, process.chunk = process.chunk, process.done, None
    if done == len(cases):  # it ended after its last row
        return
    strikes = process.strikes + 1 if done == 0 else 1
    if strikes < STRIKES:
        waiting.appendleft(((kind, [cases[done]]), strikes))
    elif lost is None:
        raise RuntimeError(f"a case killed its worker process {STRIKES} times ({process.why()}): {cases[done]}")
    else:
        yield lost(cases[done], f"its worker process died {STRIKES} times running it ({process.why()})")
    if cases[done + 1:]:
        waiting.append(((kind, cases[done + 1:]), 0))


class _Process:
    """One process of the pool, the chunk it runs (None: idle), how many of that chunk's rows it has sent."""

    def __init__(self, context, start, environment, task, extra, kwargs):
        tasks, self._tasks = context.Pipe(duplex=False)
        self.rows, rows = context.Pipe(duplex=False)
        self.process = context.Process(target=_serve, args=(tasks, rows, start, environment, task, extra, kwargs),
                                       daemon=True)
        self.process.start()
        tasks.close(), rows.close()  # the process's ends: its pipe of rows then ends when it does
        self.chunk, self.done, self.strikes = None, 0, 0

    def give(self, chunk, strikes):
        """Send a chunk to run (its first case has seen ``strikes`` deaths)."""
        self.chunk, self.done, self.strikes = chunk, 0, strikes
        try:
            self._tasks.send(chunk)
        except OSError:  # it has just died: the pool sees it end (with this chunk, whose first case then has a strike)
            pass

    def stop(self):
        try:
            self._tasks.send(None)
        except OSError:  # ended already
            pass

    def ended(self):
        return self.process.exitcode is not None

    def read(self):
        """The rows sent and not read yet; the chunk is cleared when it is done, a task's exception raised here."""
        while not self.rows.closed and self.rows.poll():
            try:
                kind, value = self.rows.recv()
            except (EOFError, OSError):  # the process ended (in the middle of a message, if it was killed then)
                self.rows.close()
                break
            if kind == "row":
                self.done += 1
                yield value
            elif kind == "done":
                self.chunk = None
            else:
                raise value

    def why(self):
        code = self.process.exitcode
        return f"killed by {signal.Signals(-code).name}" if code < 0 else f"exit status {code}"


def _serve(tasks, rows, start, environment, task, extra, kwargs):
    """A pool process: run each chunk it is sent, sending each row, then "done" (or the task's exception)."""
    start(environment)
    while (chunk := tasks.recv()) is not None:
        try:
            for row in task(chunk, *extra, **kwargs):
                rows.send(("row", row))
        except Exception as exc:  # the batch's own process raises it
            try:
                rows.send(("error", exc))
            except Exception:  # an exception that does not pickle: its line
                rows.send(("error", RuntimeError(f"{type(exc).__name__}: {exc}")))
            return
        rows.send(("done", None))
