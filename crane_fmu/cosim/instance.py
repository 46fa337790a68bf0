"""One protocol for FMU instances, whatever their FMI version; the FMI 2.0 and 3.0 adapters implement it.

Value references come from modelDescription.xml. Every FMI status above
warning becomes one :class:`FmiError` that names the instance, the FMI function
and the simulation time, with the FMU's own log messages attached.
"""

import atexit
import ctypes
import functools
import multiprocessing.util
import os
import shutil
from collections import deque
from pathlib import Path

STATUS = ("ok", "warning", "discard", "error", "fatal", "pending")


class FmiError(RuntimeError):
    """An FMI call failed.

    Attributes
    ----------
    instance, function : str
        The instance name and the FMI function, e.g. ``"pump"``, ``"fmi2DoStep"``.
    time : float or None
        Simulation time of the call (None before the experiment starts).
    status : str
        ``"error"``, ``"fatal"``, ...
    messages : list of str
        The FMU's latest log messages; the last one is normally the reason.
    """

    def __init__(self, instance, function, time, status, messages=()):
        self.instance, self.function, self.time = instance, function, time
        self.status, self.messages = status, list(messages)
        when = "" if time is None else f" at t={time:.9g} s"
        detail = self.messages[-1].removeprefix(function + ": ") if self.messages else ""
        detail = f": {detail}" if detail else ""
        super().__init__(f"{instance}: {function} returned {status}{when}{detail}")


class Instance:
    """What every instance offers the master, whatever its FMI version.

    Attributes
    ----------
    name : str
        Instance name, used in errors and result columns.
    md : fmpy model description
    variables : dict
        ``{name: fmpy ScalarVariable}``.
    inputs, outputs : list of str
        Names of the inputs and outputs, in modelDescription order.
    dependencies : dict
        ``{output: (input, ...)}``: the inputs each output reads at the same instant (ModelStructure).
    feedthrough : bool
        Some output depends on an input of the same instant.

    Subclasses implement ``set``, ``get``, ``setup``, ``enter_initialization``,
    ``exit_initialization``, the saved-state calls, ``terminate``, and the hot
    path that the master prebuilds its steps from: ``reader(vrs, values)`` and
    ``writer(vrs, values)``, each ``(call, function)`` with ``call()`` getting or
    setting the Reals of the value references ``vrs`` from or into the ctypes
    array ``values`` and returning the FMI status, and ``stepper()``, the same
    with ``call(time, step)`` taking one step (:meth:`do_step` uses the one in
    ``self._step``).
    """

    def _describe(self, path, name):
        self._path = path
        self._interface(path, name)
        self.messages = deque(maxlen=20)  # the FMU's latest log messages
        self.time = None
        self._instantiated = False
        self._folder_key, self._unzip, self._spare = _take_folder(path)

    def _interface(self, path, name):
        """The name, model description, variables, inputs, outputs and feedthrough of the FMU at ``path``."""
        self.name = name
        self.md = read_fmu(path)
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.inputs = [v.name for v in self.md.modelVariables if v.causality == "input"]
        # FMI: an output without a dependencies attribute may depend on every input (a listed continuous state of
        # an FMU with Model Exchange is no input)
        self.dependencies = {name: () for name in self.outputs}
        self.dependencies.update({u.variable.name: tuple(self.inputs) if u.dependencies is None else
                                  tuple(v.name for v in u.dependencies if v.causality == "input")
                                  for u in self.md.outputs})
        self.feedthrough = any(self.dependencies.values())

    def _call(self, function, call, *args, **kwargs):
        """Run an fmpy call, turning its exceptions into FmiError (with the exception as cause)."""
        self.messages.clear()
        try:
            return call(*args, **kwargs)
        except Exception as exc:
            status = STATUS[exc.status] if hasattr(exc, "status") and exc.status < 6 else "error"
            raise FmiError(self.name, function, self.time, status, self.messages) from exc

    def fail(self, function, status, time):
        """Raise the FmiError of a hot-path call at ``time`` that returned ``status`` (worse than warning)."""
        self.time = time
        raise FmiError(self.name, function, time, STATUS[status] if 0 <= status < 6 else str(status), self.messages)

    def do_step(self, time, step):
        """One communication step from ``time``; FmiError if the FMU returns worse than warning."""
        call, function = self._step
        status = call(time, step)
        if status > 1:
            self.fail(function, status, time)
        self.time = time + step

    def _variable(self, name):
        v = self.variables.get(name)
        if v is None:
            raise KeyError(f"{self.name} has no variable {name!r}; valid names: " + ", ".join(self.variables))
        return v

    def enumeration_value(self, name, value):
        """The value of the item ``value`` (its name, or its value) of the Enumeration variable ``name``."""
        return enumeration_value(self._variable(name), value, f"{self.name}.")

    def _hot_library(self):
        """The FMU's library for the hot path. An FMU that says it runs Python in this process under its GIL
        (ours export ``crane_fmu_runs_in_host_python``) is called without releasing the GIL; others as fmpy
        loaded them."""
        dll = self._fmu.dll
        if hasattr(dll, "crane_fmu_runs_in_host_python"):
            return ctypes.PyDLL(dll._name, handle=dll._handle)
        return dll

    def _hot_call(self, function, *arguments):
        """``(call, function)``: ``call()`` runs the FMI ``function`` of this instance with ``arguments``.

        The arguments are ctypes objects made once, and ``library[function]`` is a
        fresh ctypes function without fmpy's argtypes: no conversion per call.
        """
        return functools.partial(self._library[function], ctypes.c_void_p(self._fmu.component), *arguments), function

    def _hot_stepper(self, function, *after):
        """``(call, function)``: ``call(time, step)`` runs ``function(instance, time, step, *after)``, the two
        doubles written into ctypes objects made once."""
        time_, step_ = ctypes.c_double(), ctypes.c_double()
        do_step, _ = self._hot_call(function, time_, step_, *after)

        def call(time, step):
            time_.value, step_.value = time, step
            return do_step()

        call.fmi_call = do_step  # for the compiled loop, which passes time and step itself
        return call, function

    def vr_array(self, names):
        """A ctypes array of the value references of ``names`` (checked)."""
        return (ctypes.c_uint * len(names))(*(self._variable(n).valueReference for n in names))

    def _library_of(self, kind):
        """fmpy's ``kind`` (FMU2Slave, FMU3Slave) over this instance's folder: the spare one that came with the
        folder, its library still loaded, else a new one (which loads it)."""
        if self._spare is None:
            self._check_binary()
            return kind(guid=self.md.guid, unzipDirectory=self._unzip,
                        modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=self.name)
        fmu, self._spare = self._spare, None
        fmu.instanceName = self.name
        return fmu

    def _check_binary(self):
        """ValueError (one line) when a library of the FMU for this platform is truncated: loading it would crash."""
        from fmpy import platform, platform_tuple, sharedLibraryExtension

        from .binary_check import check_library

        for folder in (platform, platform_tuple):  # FMI 2.0's name of this platform, FMI 3.0's
            for library in sorted(Path(self._unzip, "binaries", folder).glob(f"*{sharedLibraryExtension}")):
                check_library(library, self._path)  # the FMU's own and those it loads (pythonfmu's wrapper)

    def free(self):
        """Free the instance (fmi2FreeInstance, fmi3FreeInstance); safe to call twice. The extracted folder and
        its loaded library are kept for the next instance of this FMU file; the folder is removed when the
        process exits."""
        if self._instantiated:
            self._instantiated = False
            library = None
            try:
                getattr(self._fmu, f"fmi{self.md.fmiVersion[0]}FreeInstance")(self._fmu.component)
                library = self._fmu
            finally:
                _SPARE_FOLDERS.setdefault(self._folder_key, []).append((self._unzip, library))


# Extracted FMUs no instance uses now, by FMU file version, each with fmpy's object over its library, still
# loaded: the next instance of the same FMU takes one instead of unzipping it again and loading its library
# (fmpy binds each FMI function by inspecting its Python signature: about 8 ms an FMU, more than a whole case
# of the scoreboard simulates). A new instance is made by fmi2Instantiate / fmi3InstantiateCoSimulation, as the
# standard allows after the library's previous instance was freed. Instances alive at the same time each have
# their own folder and library, as if every one had unzipped it.
_SPARE_FOLDERS = {}
# Every folder extracted here, with the process that extracted it: that process removes it when it ends
# (remove_extracted), in use or spare; a forked child leaves its parent's to the parent.
_EXTRACTED = {}
_CLEANUP_FOR = [None]  # the process whose exit handler is registered (a forked child registers its own)


def _take_folder(path):
    """``(key, folder, fmu)``: a spare extracted folder of the FMU at ``path`` with fmpy's object over its loaded
    library (None when not loaded), else a new folder and None."""
    key = _file_version(path)
    spare = _SPARE_FOLDERS.get(key)
    while spare:
        folder, fmu = spare.pop()
        if os.path.isdir(folder):
            return key, folder, fmu
    from fmpy import extract  # start-up: fmpy takes about 0.4 s to import

    folder = extract(str(path), include=_run_needs)
    _EXTRACTED[folder] = os.getpid()
    if _CLEANUP_FOR[0] != os.getpid():
        _CLEANUP_FOR[0] = os.getpid()
        # Run at this process's end however it ends normally: at exit, and at the end of a process forked by
        # multiprocessing (a forked Dask worker), which leaves by os._exit without atexit's handlers.
        multiprocessing.util.Finalize(None, remove_extracted, exitpriority=10)
    return key, folder, None


def _run_needs(member):
    """Whether an instance needs the FMU's file ``member``: all but its sources, documentation and the binaries of
    other platforms (a native FMU's are most of its bytes: its sources and a Windows library)."""
    from fmpy import platform, platform_tuple

    top, _, rest = member.partition("/")
    if top in ("sources", "documentation"):
        return False
    return top != "binaries" or rest.partition("/")[0] in (platform, platform_tuple) or "/" not in rest


@atexit.register
def remove_extracted():
    """Remove every folder this process extracted, spare or still in use (its instances must not be used after):
    called when the process ends (a Dask worker's too)."""
    for folder, pid in list(_EXTRACTED.items()):
        if pid == os.getpid():
            shutil.rmtree(folder, ignore_errors=True)
            del _EXTRACTED[folder]
    for key, folders in list(_SPARE_FOLDERS.items()):
        _SPARE_FOLDERS[key] = [(folder, fmu) for folder, fmu in folders if os.path.isdir(folder)]


def enumeration_value(v, value, prefix=""):
    """The value of the item ``value`` (its name, or its value as a number or text) of fmpy's Enumeration variable
    ``v``; ValueError naming the value and the items."""
    items = {item.name: int(item.value) for item in v.declaredType.items}
    if isinstance(value, str):
        if value in items:
            return items[value]
        if value.strip().lstrip("-").isdigit() and int(value) in items.values():
            return int(value)
    elif isinstance(value, (int, float)) and not isinstance(value, bool) and value in items.values():
        return int(value)
    raise ValueError(f"{prefix}{v.name} must be one of {', '.join(f'{k} ({n})' for k, n in items.items())}, "
                     f"got {value!r}")


def read_fmu(path):
    """The model description of a readable FMI 2.0 or 3.0 co-simulation FMU, else ValueError (one line).

    Read once per file version (path, size, modification time): treat it as read-only. A law file
    (``mylaw.py``) has the description its FMU will have (a source run in process:
    :mod:`~crane_fmu.cosim.in_process`).
    """
    from .in_process import kind_of

    if kind_of(path) is not None:
        return kind_of(path).model_description(path)
    if not Path(path).is_file():
        raise ValueError(f"{path} not found")
    return _read_fmu(_file_version(path), str(path))


def _file_version(path):
    """``(resolved path, size, modification time)``: what tells one version of a file from another."""
    stat = Path(path).stat()
    return str(Path(path).resolve()), stat.st_size, stat.st_mtime_ns


@functools.lru_cache(maxsize=64)
def _read_fmu(version, path):
    from fmpy import read_model_description  # start-up: fmpy takes about 0.4 s to import

    try:
        md = read_model_description(str(path))
    except Exception as exc:  # zip, XML and schema errors alike
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"{path} is not a readable FMU ({reason})") from None
    if md.fmiVersion not in ("2.0", "3.0") or md.coSimulation is None:
        raise ValueError(f"{path} is not an FMI 2.0 or 3.0 co-simulation FMU")
    return md
