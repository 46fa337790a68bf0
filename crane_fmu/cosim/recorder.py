"""Observers that record every output of every instance at each communication point.

numpy, pyarrow and scipy.io are imported where a recorder or reader needs them: importing them takes about
0.3, 0.4 and 0.9 s (crane_fmu/commands/__init__.py says how that was measured), which every command that
imports the master would pay otherwise.
"""

import contextlib
import os
import re
import threading
import time
from array import array


class WriteError(OSError):
    """The result file could not be written (a full disk, a file-size limit, ...): ``errno``, ``strerror`` and
    ``filename`` as the OSError's. The rows written before it are kept (:meth:`_StreamingRecorder.close`)."""


def _write_error(exc, path):
    return WriteError(exc.errno, exc.strerror or str(exc), path)


class ArrayRecorder:
    """Keeps the results in memory; :meth:`columns` returns them by column name.

    Column names are ``time`` then ``instance.variable``, values in SI units.
    """

    def __init__(self):
        self.names = None
        self._rows = array("d")

    def start(self, names):
        self.names = ["time"] + list(names)

    def observe(self, time, values):
        rows = self._rows
        rows.append(time)
        rows.frombytes(values.cast("B"))  # memcpy of the outputs just read

    def observe_rows(self, rows):
        """Record a block of rows (``time`` and the values, one row after another) at once."""
        self._rows.frombytes(rows.cast("B"))

    def columns(self):
        """``{name: numpy array}`` of everything recorded."""
        import numpy as np

        data = np.frombuffer(self._rows, dtype=float).reshape(-1, len(self.names))
        return {name: data[:, i].copy() for i, name in enumerate(self.names)}


class _StreamingRecorder(ArrayRecorder):
    """Streams the results to a file in chunks of rows, so memory stays flat on long runs.

    Each full chunk is written by a background thread while the run goes on
    (pyarrow formats and writes without holding the GIL); the next chunk waits
    for it, so chunks land in order and at most two are in memory. A write error
    is raised by the next :meth:`observe` that fills a chunk, or by :meth:`close`.
    The file is written under a temporary name and renamed by :meth:`close`, so
    an existing result is never replaced by a half-written one. :meth:`close`
    with a ``reason`` keeps every row recorded so far, says why the run was cut
    short and renames the file to :func:`cut_short_path` (``run.cut-short.csv``
    beside ``run.csv``): the file named ``path`` only ever holds a complete run,
    and an earlier good result there is left as it was. :attr:`written` is the
    file written. Subclasses write a chunk (a pyarrow table) and finish the file.
    """

    CHUNK_ROWS = 2048

    def __init__(self, path):
        super().__init__()
        self.path = os.fspath(path)
        self._partial = self.path + ".partial"
        self.written = None
        self._closed = False
        os.makedirs(os.path.dirname(os.path.abspath(self.path)), exist_ok=True)
        self._pending, self._write_error, self._done = None, None, threading.Event()

    def start(self, names):
        super().start(names)
        self._chunk = self.CHUNK_ROWS * len(self.names)

    def observe(self, time, values):
        rows = self._rows
        rows.append(time)
        rows.frombytes(values.cast("B"))
        if len(rows) >= self._chunk:
            self._flush(background=True)

    def observe_rows(self, rows):
        self._rows.frombytes(rows.cast("B"))
        if len(self._rows) >= self._chunk:
            self._flush(background=True)

    def _flush(self, background=False):
        self._wait()
        table = _table(self._rows, self.names)
        self._rows = array("d")
        if background:
            # The chunk is written once, by whoever claims it: the thread, or _wait when Ctrl-C stopped
            # Thread.start() before the thread began.
            claim = threading.Lock()
            self._pending = (table, claim)
            threading.Thread(target=self._write_keeping_error, args=(table, claim), daemon=True).start()
        else:
            self._write_checked(table)

    def _write_keeping_error(self, table, claim):
        if not claim.acquire(blocking=False):
            return
        try:
            self._write_checked(table)
        except BaseException as exc:  # raised in the recording thread by _wait
            self._write_error = exc
        finally:
            self._done.set()

    def _write_checked(self, table):
        try:
            self._write(table)
        except OSError as exc:
            raise _write_error(exc, self.path) from None

    def _wait(self):
        """Wait for the chunk being written (or write it here if its thread never began); raise its error."""
        if self._pending is not None:
            table, claim = self._pending
            if claim.acquire(blocking=False):
                self._pending = None
                self._write_checked(table)
            else:
                self._done.wait()
                self._done.clear()
                self._pending = None
        if self._write_error is not None:
            error, self._write_error = self._write_error, None
            raise error

    def columns(self):
        raise TypeError(f"{type(self).__name__} streams to disk; read the file with crane_fmu.cosim.read_result")

    def close(self, reason=None):
        """Finish the file; ``reason`` marks a run cut short. Where the file cannot be written (a full disk, a
        file-size limit), the rows written before are kept in :func:`cut_short_path` as far as the format allows
        (:meth:`_salvage`) and the :class:`WriteError` is raised."""
        if self._closed:
            return
        self._closed = True
        if self.names is None:  # nothing recorded: leave any existing result alone
            self._discard()
            return
        try:
            if self._write_error is None:
                self._flush()
                self._finish(reason)
            else:  # an earlier chunk could not be written: nothing more will be
                raise self._write_error
        except OSError as exc:
            error = exc if isinstance(exc, WriteError) else _write_error(exc, self.path)
            self._write_error = None
            self.written = cut_short_path(self.path)
            if self._salvage(f"{reason + '; ' if reason else ''}cannot write: {error.strerror}"):
                os.replace(self._partial, self.written)
            else:
                self.written = None
                with contextlib.suppress(OSError):
                    os.remove(self._partial)
            raise error from None
        self.written = cut_short_path(self.path) if reason else self.path
        os.replace(self._partial, self.written)

    def _salvage(self, reason):
        """After a write error: the file as far as it is whole, with ``reason`` where there is room; whether it
        holds anything worth keeping."""
        return False


def cut_short_path(path):
    """Where a run cut short is written instead of ``path``: ``results/run.csv`` -> ``results/run.cut-short.csv``."""
    root, suffix = os.path.splitext(os.fspath(path))
    return f"{root}.cut-short{suffix}"


class CsvRecorder(_StreamingRecorder):
    """Streams the results to a CSV file; a run cut short ends with a ``# run cut short: ...`` line.

    Values are written as the shortest text that reads back as the same double
    (pyarrow's CSV writer: about 1.5 us a row of 16 values, against 5.6 us for
    Python's ``%.17g`` and about 8 us for ``repr``), in a background thread.
    """

    def __init__(self, path):
        super().__init__(path)
        self._file = open(self._partial, "wb")

    def start(self, names):
        super().start(names)
        self._file.write((",".join(self.names) + "\n").encode())

    def _write(self, table):
        import pyarrow.csv

        pyarrow.csv.write_csv(table, self._file, pyarrow.csv.WriteOptions(include_header=False))

    def _finish(self, reason):
        if reason:
            self._file.write(f"# run cut short: {reason}\n".encode())
        self._file.close()

    def _discard(self):
        self._file.close()
        os.remove(self._partial)

    def _salvage(self, reason):
        """The rows written before the error, to the last whole line, and the trailer if there is room for it."""
        try:
            self._file.close()  # its buffer may not fit either
        except OSError:
            pass
        whole = _last_line_end(self._partial)
        os.truncate(self._partial, whole)
        try:
            with open(self._partial, "ab") as f:
                f.write(f"# run cut short: {reason}\n".encode())
        except OSError:
            os.truncate(self._partial, whole)  # no room for the trailer: the rows alone
        return whole > 0


def _last_line_end(path, block=65536):
    """The size of the file at ``path`` up to and with its last newline (0: none)."""
    with open(path, "rb") as f:
        end = f.seek(0, os.SEEK_END)
        while end > 0:
            start = max(0, end - block)
            f.seek(start)
            found = f.read(end - start).rfind(b"\n")
            if found >= 0:
                return start + found + 1
            end = start
    return 0


class ParquetRecorder(_StreamingRecorder):
    """Streams the results to a Parquet file, one row group per chunk; for long runs.

    Columns as in the CSV (``time``, then ``instance.variable``, float64); a run
    cut short says why in the file's metadata (``run cut short``).
    """

    CHUNK_ROWS = 65536

    def __init__(self, path):
        import pyarrow.parquet  # noqa: F401  (fail here, before the run, if it is missing)

        super().__init__(path)
        self._writer = None

    def _write(self, table):
        import pyarrow.parquet as pq

        if self._writer is None:
            self._writer = pq.ParquetWriter(self._partial, table.schema)
        self._writer.write_table(table)

    def _finish(self, reason):
        if reason:
            self._writer.add_key_value_metadata({"run cut short": reason})
        self._writer.close()

    def _discard(self):
        pass  # nothing written yet


class MatRecorder(ArrayRecorder):
    """Writes the results as a MATLAB file (``scipy.io.savemat``, format 5) when the run ends.

    The file holds ``columns`` (the CSV's column names, a cell array of strings) and ``data`` (a matrix,
    a row per communication point, a column per name, in the CSV's order), and ``time`` and a struct per
    instance whose name is a MATLAB name (``tank.level`` in MATLAB is the CSV's ``tank.level``). A
    run cut short holds ``run_cut_short``, the reason, and goes to :func:`cut_short_path`. The rows stay in
    memory until the end (128 bytes a row of 16 values): for runs of millions of steps, write Parquet.
    """

    def __init__(self, path):
        import scipy.io  # noqa: F401  (fail here, before the run, if it is missing)

        super().__init__()
        self.path = os.fspath(path)
        self.written = None
        self._closed = False
        os.makedirs(os.path.dirname(os.path.abspath(self.path)), exist_ok=True)

    def close(self, reason=None):
        """Write the file (under a temporary name, then renamed); ``reason`` marks a run cut short."""
        import numpy as np
        import scipy.io

        if self._closed:
            return
        self._closed = True
        if self.names is None:
            return
        data = np.frombuffer(self._rows, dtype=float).reshape(-1, len(self.names))
        content = {"columns": np.array(self.names, dtype=object), "data": data, "time": data[:, 0]}
        for i, name in enumerate(self.names[1:], start=1):
            instance, _, variable = name.rpartition(".")
            if re.fullmatch(r"[A-Za-z]\w{0,62}", instance) and re.fullmatch(r"[A-Za-z]\w{0,62}", variable) \
                    and instance not in ("columns", "data", "time", "run_cut_short"):
                content.setdefault(instance, {})[variable] = data[:, i]
        if reason:
            content["run_cut_short"] = reason
        self.written = cut_short_path(self.path) if reason else self.path
        partial = self.path + ".partial"
        with open(partial, "wb") as f:
            scipy.io.savemat(f, content, do_compression=True, oned_as="column")
        os.replace(partial, self.written)


class ProgressLine:
    """An observer that shows ``t = 12.0 of 3600 s (0 %)`` on one line of a terminal while a run goes on.

    It looks at the clock once every ``check_every`` communication points (or block of them) and redraws the
    line at most every ``interval`` seconds, starting after ``interval`` seconds (a short run shows nothing);
    :meth:`close` ends the line. Give it a stream that is a terminal: it does not check (the simulate command
    adds it only when stderr is one).
    """

    def __init__(self, start_time, stop_time, stream, interval=1.0, check_every=1000):
        self.start_time, self.stop_time, self.stream = start_time, stop_time, stream
        self.interval, self.check_every = interval, check_every
        self._clock = time.monotonic
        self._next = self._clock() + interval
        self._count, self._shown = 0, False

    def start(self, names):
        self._width = len(names) + 1

    def observe(self, time, values):
        self._count += 1
        if self._count % self.check_every == 0:
            self._show(time)

    def observe_rows(self, rows):
        """A block of rows: the clock looked at once, at its last point."""
        if rows:
            self._show(rows[-self._width])

    def _show(self, time):
        now = self._clock()
        if now < self._next:
            return
        self._next = now + self.interval
        share = (time - self.start_time) / (self.stop_time - self.start_time)
        self.stream.write(f"\rt = {time:.6g} of {self.stop_time:g} s ({100 * share:.0f} %)")
        self.stream.flush()
        self._shown = True

    def close(self, reason=None):
        """End the line (when one was shown)."""
        if self._shown:
            self.stream.write("\n")
            self.stream.flush()
            self._shown = False


def _table(rows, names):
    """Recorded rows (a flat array of doubles) as a pyarrow table of float64 columns."""
    import numpy as np
    import pyarrow as pa

    columns = np.frombuffer(rows, dtype=float).reshape(-1, len(names)).T.copy()  # each column contiguous
    return pa.Table.from_arrays([pa.Array.from_buffers(pa.float64(), len(c), [None, pa.py_buffer(c)])
                                 for c in columns], names=names)


RESULT_SUFFIXES = (".csv", ".parquet", ".mat")


def recorder_for(path):
    """The recorder for a result file by its suffix: Parquet (``.parquet``), MATLAB (``.mat``), else CSV."""
    suffix = os.path.splitext(os.fspath(path))[1]
    return {".parquet": ParquetRecorder, ".mat": MatRecorder}.get(suffix, CsvRecorder)(path)


def read_result(path):
    """Read a result file (CSV, Parquet or MATLAB ``.mat``) into ``{column: numpy array}``."""
    if os.fspath(path).endswith(".mat"):
        import scipy.io

        content = scipy.io.loadmat(path)
        names = [str(cell.ravel()[0]) for cell in content["columns"].ravel()]  # a cell array of strings
        return {name: content["data"][:, i].copy() for i, name in enumerate(names)}
    if os.fspath(path).endswith(".parquet"):
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        return {name: table.column(name).to_numpy() for name in table.column_names}
    return read_csv(path)


def read_csv(path):
    """Read a result CSV into ``{column: numpy array}``; comment lines are skipped."""
    import numpy as np

    with open(path) as f:
        names = [name.strip('"') for name in f.readline().strip().split(",")]  # fmpy quotes its names
        data = np.loadtxt(f, delimiter=",", comments="#", ndmin=2)
    return {name: data[:, i] for i, name in enumerate(names)}


def write_csv(path, columns, every=1):
    """Write ``{name: array}`` as a result CSV (every ``every``-th row), atomically."""
    names = list(columns)
    rows = zip(*(columns[n][::every] for n in names))
    partial = os.fspath(path) + ".partial"
    row_format = ",".join(["%.17g"] * len(names))
    with open(partial, "w") as f:
        f.write(",".join(names) + "\n")
        f.writelines(row_format % row + "\n" for row in rows)
    os.replace(partial, path)
