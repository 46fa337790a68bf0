"""Observers that record every output of every instance at each communication point."""

import os
import threading
from array import array


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
    an existing result is never replaced by a half-written one; :meth:`close`
    with a ``reason`` keeps every row recorded so far and says why the run was
    cut short. Subclasses write a chunk (a pyarrow table) and finish the file.
    """

    CHUNK_ROWS = 2048

    def __init__(self, path):
        super().__init__()
        self.path = os.fspath(path)
        self._partial = self.path + ".partial"
        self._closed = False
        self._writer_thread, self._write_error = None, None

    def start(self, names):
        super().start(names)
        self._chunk = self.CHUNK_ROWS * len(self.names)

    def observe(self, time, values):
        rows = self._rows
        rows.append(time)
        rows.frombytes(values.cast("B"))
        if len(rows) >= self._chunk:
            self._flush(background=True)

    def _flush(self, background=False):
        table = _table(self._rows, self.names)
        self._rows = array("d")
        self._wait()
        if background:
            self._writer_thread = threading.Thread(target=self._write_keeping_error, args=(table,), daemon=True)
            self._writer_thread.start()
        else:
            self._write(table)

    def _write_keeping_error(self, table):
        try:
            self._write(table)
        except BaseException as exc:  # raised in the recording thread by _wait
            self._write_error = exc

    def _wait(self):
        """Wait for the chunk being written; raise its error, if any."""
        if self._writer_thread is not None:
            self._writer_thread.join()
            self._writer_thread = None
        if self._write_error is not None:
            error, self._write_error = self._write_error, None
            raise error

    def columns(self):
        raise TypeError(f"{type(self).__name__} streams to disk; read the file with crane_fmu.cosim.read_result")

    def close(self, reason=None):
        """Finish the file; ``reason`` marks a run that was cut short."""
        if self._closed:
            return
        self._closed = True
        if self.names is None:  # nothing recorded: leave any existing result alone
            self._discard()
            return
        self._flush()
        self._finish(reason)
        os.replace(self._partial, self.path)


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


def _table(rows, names):
    """Recorded rows (a flat array of doubles) as a pyarrow table of float64 columns."""
    import numpy as np
    import pyarrow as pa

    columns = np.frombuffer(rows, dtype=float).reshape(-1, len(names)).T.copy()  # each column contiguous
    return pa.Table.from_arrays([pa.Array.from_buffers(pa.float64(), len(c), [None, pa.py_buffer(c)])
                                 for c in columns], names=names)


def recorder_for(path):
    """The streaming recorder for a result file: Parquet for ``.parquet``, else CSV."""
    return ParquetRecorder(path) if os.fspath(path).endswith(".parquet") else CsvRecorder(path)


def read_result(path):
    """Read a result file (CSV or Parquet) into ``{column: numpy array}``."""
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
