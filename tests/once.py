"""Things made once per test run for every pytest-xdist worker: ``made_once`` (used by conftest.py's fixtures).

A session fixture runs once per worker process; what it makes through :func:`made_once` is made by the first
worker that asks, under a file lock, in a folder every worker of the run sees, and reused by the others.
"""

import contextlib
import fcntl
import os
import shutil


def _shared_root(tmp_path_factory):
    """The run's temporary folder that every xdist worker sees (a worker's own is a folder in it)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@contextlib.contextmanager
def _locked(path):
    with open(path, "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def made_once(tmp_path_factory, name, make):
    """The folder ``name`` in the run's shared temporary folder, filled by ``make(folder)`` once per run.

    The first worker to ask makes it under a file lock; the others wait and get the same folder. A folder
    left half-made (its maker failed) is made again by the next one to ask, which then fails the same way.
    """
    return made_in(_shared_root(tmp_path_factory), name, make)


def made_in(root, name, make):
    """:func:`made_once` in the folder ``root``."""
    folder, done = root / name, root / f"{name}.done"
    with _locked(root / f"{name}.lock"):
        if not done.exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            done.touch()
    return folder
