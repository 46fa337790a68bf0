"""The master's stepping loop compiled (``step_loop.c``): the same FMI calls without Python between them.

:class:`~crane_fmu.cosim.master.Master` steps through it when the algorithm has a fixed plan
(:meth:`~crane_fmu.cosim.algorithms.Algorithm.plan`: Gauss-Seidel, Jacobi), every observer takes
rows in blocks (``observe_rows``, as the recorders do) and a C compiler is found; otherwise (or
with ``loop="python"``) through its Python loop. Both make the same calls in the same order with
the same arguments, so they give the same numbers (a test holds them equal bit for bit); the
compiled loop only drops the cost of a ctypes call per FMI call, which is most of a step with
native FMUs.

The library is compiled once per machine into ``$XDG_CACHE_HOME/crane_fmu`` (``~/.cache``),
named by a checksum of its source (:func:`compiled`, which other C helpers of the toolkit use too);
``CRANE_FMU_LOOP=python`` turns it off.
"""

import ctypes
import functools
import os
import shutil
import subprocess
import tempfile
import zlib
from pathlib import Path

SOURCE = Path(__file__).with_name("step_loop.c")
KINDS = {"fmi2GetReal": 0, "fmi2SetReal": 0, "fmi3GetFloat64": 1, "fmi3SetFloat64": 1, "fmi2DoStep": 3,
         "fmi3DoStep": 4}
GET_SET_2, GET_SET_3, COPY = 0, 1, 2
CALL, SETUP_2, ENTER_3, SET_STRINGS_2, SET_STRINGS_3 = 5, 6, 7, 8, 9  # run_calls' kinds of operation (step_loop.c)
SET_INTEGERS_2, SET_INT64S_3 = 10, 11  # run_calls' sets of Enumerations (step_loop.c)
ROWS_PER_CALL = 4096


class Operation(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_int), ("function", ctypes.c_void_p), ("instance", ctypes.c_void_p),
                ("vr", ctypes.c_void_p), ("n", ctypes.c_size_t), ("values", ctypes.c_void_p),
                ("source", ctypes.c_void_p)]


def _cache_dir():
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "crane_fmu"


@functools.cache
def library(hold_gil=False):
    """The compiled loop (a ctypes library), or None: no C compiler, or ``CRANE_FMU_LOOP=python``.

    ``hold_gil``: loaded to be called holding the GIL (``ctypes.PyDLL``), for FMUs that run Python in
    this interpreter and are called so by the Python loop too.
    """
    if os.environ.get("CRANE_FMU_LOOP") == "python":
        return None
    lib = compiled(SOURCE, hold_gil)
    if lib is not None:
        lib.run_points.restype = ctypes.c_long
        lib.run_points.argtypes = [ctypes.POINTER(Operation), ctypes.c_size_t, ctypes.POINTER(Operation),
                                   ctypes.c_size_t, ctypes.c_double, ctypes.c_double, ctypes.c_long, ctypes.c_long,
                                   ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p,
                                   ctypes.POINTER(ctypes.c_long), ctypes.POINTER(ctypes.c_int),
                                   ctypes.POINTER(ctypes.c_double)]
        lib.run_calls.restype = ctypes.c_long
        lib.run_calls.argtypes = [ctypes.POINTER(Operation), ctypes.c_size_t, ctypes.c_double, ctypes.c_double,
                                  ctypes.POINTER(ctypes.c_int)]
    return lib


@functools.cache
def compiled(source, hold_gil=False):
    """The C file ``source`` compiled (``-O2 -ffp-contract=off``) into a shared library in the cache, once per
    machine and version of the file, and loaded (``ctypes.PyDLL`` with ``hold_gil``); None without a C compiler
    or a writable cache folder."""
    path = _cache_dir() / f"{Path(source).stem}-{zlib.crc32(Path(source).read_bytes()):08x}.so"
    if not path.exists() and not _compile(source, path):
        return None
    return (ctypes.PyDLL if hold_gil else ctypes.CDLL)(str(path))


def _compile(source, path):
    """Compile ``source`` into ``path`` (aside, then renamed: never a half-written library); False without a
    C compiler or a writable cache folder."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if cc is None:
        return False
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=path.parent) as tmp:
            built = Path(tmp) / path.name
            done = subprocess.run([cc, "-O2", "-shared", "-fPIC", "-ffp-contract=off", str(source), "-o",
                                   str(built)], capture_output=True)
            if done.returncode == 0:
                os.replace(built, path)
            return done.returncode == 0
    except OSError:  # a cache folder that cannot be written: the Python loop
        return False


def _operations(calls):
    """``(Operations, the call each stands for)`` of prebuilt ``(call, function, instance)`` triples; None if one is
    not a call the loop knows."""
    ops, owners = [], []
    for call, function, _ in calls:
        for dst, src in getattr(call, "copies", ()):  # a writer that first copies its inputs together
            ops.append(Operation(COPY, None, None, None, 0, dst, src))
            owners.append(call)
        fmi = getattr(call, "fmi_call", call)
        if function not in KINDS or not isinstance(fmi, functools.partial):
            return None
        instance, *args = fmi.args
        address = ctypes.cast(fmi.func, ctypes.c_void_p).value
        if function.endswith("DoStep"):
            ops.append(Operation(KINDS[function], address, instance.value))
        else:
            ops.append(Operation(KINDS[function], address, instance.value, ctypes.addressof(args[0]), args[1].value,
                                 ctypes.addressof(args[2])))
        owners.append(call)
    return (Operation * len(ops))(*ops), owners


class CompiledLoop:
    """The loop over a wiring's buffer for an algorithm's plan (``(exchange calls, step calls)``)."""

    def __init__(self, lib, wiring, plan):
        self.lib, self.wiring = lib, wiring
        (self.exchange, exchange_owners), (self.steps, step_owners) = plan
        self.owners = exchange_owners + step_owners
        self.outputs = ctypes.addressof(wiring.buffer)
        self.width = len(wiring.output_names) + 1
        self.every_output = (ctypes.c_size_t * (self.width - 1))(*range(self.width - 1))

    @classmethod
    def create(cls, wiring, plan):
        """The compiled loop for ``plan``, or None where it cannot run it."""
        if plan is None:
            return None
        lib = library(any(isinstance(getattr(inst, "_library", None), ctypes.PyDLL) for calls in plan
                          for _, _, inst in calls))
        if lib is None:
            return None
        parts = [_operations(calls) for calls in plan]
        return None if None in parts else cls(lib, wiring, parts)

    def run(self, start_time, step, first, last, step_until, keep, n_keep, rows):
        """The points ``first`` to ``last - 1`` into ``rows`` (``run_points`` of step_loop.c: stepped before
        ``step_until``; a row is the time and the ``n_keep`` outputs of the indices ``keep``, a ctypes array).

        Returns ``(rows recorded, failure)``: ``failure`` is None, or ``(call, status, time)`` of the call that
        failed, for :meth:`~crane_fmu.cosim.master.Wiring.fail`.
        """
        failed, status, failed_at = ctypes.c_long(), ctypes.c_int(), ctypes.c_double()
        done = self.lib.run_points(self.exchange, len(self.exchange), self.steps, len(self.steps), start_time, step,
                                   first, last, step_until, self.outputs, keep, n_keep, rows, ctypes.byref(failed),
                                   ctypes.byref(status), ctypes.byref(failed_at))
        return done, (self.owners[failed.value], status.value, failed_at.value) if failed.value >= 0 else None

    def advance(self, start_time, step, first, last, observers):
        """As :meth:`Master.advance`, a block of rows per call into C; observers get them by ``observe_rows``."""
        rows = (ctypes.c_double * (min(ROWS_PER_CALL, max(last - first, 1)) * self.width))()
        view = memoryview(rows).cast("B").cast("d")
        for begin in range(first, last, ROWS_PER_CALL):
            end = min(begin + ROWS_PER_CALL, last)
            done, failure = self.run(start_time, step, begin, end, end, self.every_output, self.width - 1, rows)
            for o in observers:
                o.observe_rows(view[:done * self.width].toreadonly())
            if failure:
                self.wiring.fail(*failure)
