"""A study's results in bounded memory: what its journal holds, and the results table streamed from it.

The journal (``cases.jsonl``) is a study's record: a row per finished case, appended as it finishes.
:class:`JournalIndex` knows which cases it holds (and whether each was ok) without holding their
rows: 17 bytes a case, in sorted arrays. :func:`write_results` writes the rows of a study's cases, in
the study's order, from the journal to Parquet (or CSV) a block at a time. So a study of any size
runs, resumes and is written in memory that does not grow with its rows.
"""

import json
import os
from pathlib import Path

import numpy as np

BLOCK = 4096  # rows a block of the table


class JournalIndex:
    """The rows of the journal at ``path``, by case id (the last of a case's rows counts; a torn line is ignored)."""

    def __init__(self, path):
        self.path = Path(path)
        ids, offsets, ok = [], [], []
        if self.path.exists():
            with open(self.path, "rb") as f:
                offset = 0
                for line in f:
                    try:
                        row = json.loads(line)
                        ids.append(int(row["case_id"], 16))
                        offsets.append(offset)
                        ok.append(row["status"] == "ok")
                    except (ValueError, KeyError, TypeError):
                        pass  # torn (the run was killed while writing it) or not a row
                    offset += len(line)
        ids = np.array(ids, dtype=np.uint64)
        order = np.lexsort((np.arange(len(ids)), ids))  # by id, then by place: the last of each id wins
        last = np.ones(len(order), bool)
        last[:-1] = ids[order][1:] != ids[order][:-1]
        keep = order[last]
        self._ids, self._offsets, self._ok = ids[keep], np.array(offsets, np.int64)[keep], np.array(ok, bool)[keep]

    def _find(self, case_id):
        key = np.uint64(int(case_id, 16))
        i = int(np.searchsorted(self._ids, key))
        return i if i < len(self._ids) and self._ids[i] == key else None

    def __contains__(self, case_id):
        return self._find(case_id) is not None

    def __len__(self):
        return len(self._ids)

    def ok(self, case_id):
        """Whether the case's row says ``ok``."""
        return bool(self._ok[self._find(case_id)])

    def rows(self, case_ids):
        """The rows of ``case_ids`` (each in the journal), in that order, read from the file one at a time."""
        with open(self.path, "rb") as f:
            for case_id in case_ids:
                f.seek(int(self._offsets[self._find(case_id)]))
                yield json.loads(f.readline())


def write_results(index, case_ids, path, columns=None):
    """Write the rows of the cases ``case_ids()`` gives (each in ``index``'s journal) to ``path`` (``.parquet`` or
    CSV) a block at a time, under a temporary name then renamed; returns the number of rows not ``ok``.

    The columns are the first row's keys, then any others in the order met (``columns``: given instead); their
    types are found in a first pass over the rows, as pyarrow would find them in one table of every row.
    """
    import pyarrow as pa

    types, names = {}, list(columns or [])
    for row in index.rows(case_ids()):
        for key, value in row.items():
            if key not in types:
                types[key] = set()
                if columns is None:
                    names.append(key)
            if value is not None:
                types[key].add(type(value))
    schema = pa.schema([(name, _arrow_type(types.get(name, set()))) for name in names])
    path = Path(path)
    partial = path.with_name(f".{path.name}.partial")
    not_ok = 0
    with _writer(partial, schema) as write:
        block = []
        for row in index.rows(case_ids()):
            not_ok += row.get("status") != "ok"
            block.append(row)
            if len(block) == BLOCK:
                write(pa.Table.from_pylist(block, schema=schema))
                block = []
        if block:
            write(pa.Table.from_pylist(block, schema=schema))
    os.replace(partial, path)
    return not_ok


def _arrow_type(kinds):
    import pyarrow as pa

    if kinds <= {bool} and kinds:
        return pa.bool_()
    if kinds <= {int}:
        return pa.int64() if kinds else pa.null()
    if kinds <= {int, float}:
        return pa.float64()
    if kinds <= {str}:
        return pa.string()
    raise ValueError(f"a column holds values of {', '.join(sorted(k.__name__ for k in kinds))}: no one type")


class _writer:
    """``with _writer(path, schema) as write``: ``write(table)`` appends a block to a Parquet or CSV file."""

    def __init__(self, path, schema):
        self.path, self.schema = Path(path), schema

    def __enter__(self):
        if self.path.name.endswith(".parquet.partial"):
            import pyarrow.parquet as pq

            self.sink = pq.ParquetWriter(self.path, self.schema)
        else:
            import pyarrow.csv as pcsv

            self.sink = pcsv.CSVWriter(self.path, self.schema)
        return self.sink.write_table

    def __exit__(self, *exc):
        self.sink.close()
