"""Thin layer over one FMI 2.0 co-simulation instance, loaded with fmpy.

Value references come from modelDescription.xml. Every FMI status above
warning becomes one :class:`FmiError` that names the instance, the FMI function
and the simulation time, with the FMU's own log messages attached.
"""

import ctypes
import itertools
import shutil
import weakref
from collections import deque

from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

STATUS = ("ok", "warning", "discard", "error", "fatal", "pending")
_libc = ctypes.CDLL(None)
_libc.calloc.restype = ctypes.c_void_p
_libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]

# fmpy's logger proxy (which formats the FMU's printf-style messages) keeps ONE
# Python logger for the whole process, so every instance shares this one and
# its messages are told apart by the componentEnvironment each instance passes.
_instances = weakref.WeakValueDictionary()
_keys = itertools.count(1)


def _dispatch(environment, instance_name, status, category, message):
    instance = _instances.get(environment or 0)
    if instance is not None:
        instance.messages.append(message.decode("utf-8", "replace"))


_LOGGER = fmi2CallbackLoggerTYPE(_dispatch)


class FmiError(RuntimeError):
    """An FMI call failed.

    Attributes
    ----------
    instance, function : str
        The instance name and the FMI function, e.g. ``"plant"``, ``"fmi2DoStep"``.
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


class FmuInstance:
    """One instance of an FMI 2.0 co-simulation FMU.

    Parameters
    ----------
    path : str or Path
        The .fmu file.
    name : str
        Instance name, used in errors and result columns.
    """

    def __init__(self, path, name):
        self._describe(path, name)
        try:
            self._fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self._unzip,
                                  modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
            key = next(_keys)
            _instances[key] = self
            self._callbacks = fmi2CallbackFunctions()
            self._callbacks.logger = _LOGGER
            self._callbacks.componentEnvironment = key
            self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
            self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
            addLoggerProxy(ctypes.byref(self._callbacks))
            self._call("fmi2Instantiate", self._fmu.instantiate, callbacks=self._callbacks, loggingOn=True)
        except BaseException:
            shutil.rmtree(self._unzip, ignore_errors=True)
            raise
        self._instantiated = True
        dll = self._fmu.dll
        self._get_real, self._set_real, self._do_step = dll.fmi2GetReal, dll.fmi2SetReal, dll.fmi2DoStep
        # Ask for every log message. (pythonfmu 0.7 FMUs ignore this and loggingOn
        # alike and never call the logger, so their errors arrive without a reason.)
        self._call("fmi2SetDebugLogging", self._fmu.setDebugLogging, True, [])

    def _describe(self, path, name):
        """What both FMI versions share: the model description and the variable lists."""
        self.name = name
        self.md = read_model_description(str(path))
        if self.md.coSimulation is None:
            raise ValueError(f"{path} is not a co-simulation FMU")
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.inputs = [v.name for v in self.md.modelVariables if v.causality == "input"]
        # Direct feedthrough: some output depends on an input (ModelStructure).
        self.feedthrough = any(u.dependencies for u in self.md.outputs)
        self.messages = deque(maxlen=20)  # the FMU's latest log messages
        self.time = None
        self._instantiated = False
        self._unzip = extract(str(path))

    def _call(self, function, call, *args, **kwargs):
        """Run an fmpy call, turning its exceptions into FmiError."""
        self.messages.clear()
        try:
            return call(*args, **kwargs)
        except Exception as exc:
            status = STATUS[exc.status] if hasattr(exc, "status") and exc.status < 6 else "error"
            raise FmiError(self.name, function, self.time, status, self.messages) from None

    def _raise(self, function, status):
        """Raise the FmiError of a hot-path call that returned worse than warning."""
        raise FmiError(self.name, function, self.time, STATUS[status] if 0 <= status < 6 else str(status),
                       self.messages)

    # --- setup -----------------------------------------------------------------

    def vr_array(self, names):
        """A ctypes array of the value references of ``names`` (checked)."""
        for n in names:
            if n not in self.variables:
                raise KeyError(f"{self.name} has no variable {n!r}; valid names: "
                               + ", ".join(self.variables))
        return (ctypes.c_uint * len(names))(*(self.variables[n].valueReference for n in names))

    def set(self, name, value):
        """Set one variable by name, converting ``value`` to the variable's type."""
        v = self.variables.get(name)
        if v is None:
            raise KeyError(f"{self.name} has no variable {name!r}; valid names: " + ", ".join(self.variables))
        setter = {"Real": self._fmu.setReal, "Integer": self._fmu.setInteger,
                  "Boolean": self._fmu.setBoolean, "String": self._fmu.setString}[v.type]
        value = {"Real": float, "Integer": int, "Boolean": bool, "String": str}[v.type](value)
        self._call(f"fmi2Set{v.type}", setter, [v.valueReference], [value])

    def get(self, name):
        """Get one variable by name."""
        v = self.variables[name]
        getter = {"Real": self._fmu.getReal, "Integer": self._fmu.getInteger,
                  "Boolean": self._fmu.getBoolean, "String": self._fmu.getString}[v.type]
        value = self._call(f"fmi2Get{v.type}", getter, [v.valueReference])[0]
        return value.decode("utf-8") if isinstance(value, bytes) else value

    def setup(self, start_time, stop_time=None):
        self.time = start_time
        self._call("fmi2SetupExperiment", self._fmu.setupExperiment, startTime=start_time, stopTime=stop_time)

    def enter_initialization(self):
        self._call("fmi2EnterInitializationMode", self._fmu.enterInitializationMode)

    def exit_initialization(self):
        self._call("fmi2ExitInitializationMode", self._fmu.exitInitializationMode)

    # --- saved state (FMUs with canGetAndSetFMUstate / canSerializeFMUstate) ---

    def get_state(self):
        """An FMU state (fmi2GetFMUstate); free it with :meth:`free_state`."""
        return self._call("fmi2GetFMUstate", self._fmu.getFMUstate)

    def set_state(self, state):
        self._call("fmi2SetFMUstate", self._fmu.setFMUstate, state)

    def free_state(self, state):
        self._call("fmi2FreeFMUstate", self._fmu.freeFMUstate, state)

    def serialize_state(self, state):
        """The state as bytes (fmi2SerializeFMUstate), to restore in this or another instance."""
        return bytes(self._call("fmi2SerializeFMUstate", self._fmu.serializeFMUstate, state))

    def deserialize_state(self, data):
        return self._call("fmi2DeSerializeFMUstate", self._fmu.deSerializeFMUstate, data)

    # --- hot path: preallocated arrays, raw ctypes calls ----------------------

    def get_reals(self, vrs, values):
        """fmi2GetReal into the preallocated ctypes array ``values``."""
        status = self._get_real(self._fmu.component, vrs, len(vrs), values)
        if status > 1:  # worse than warning
            self._raise("fmi2GetReal", status)

    def set_reals(self, vrs, values):
        """fmi2SetReal from the preallocated ctypes array ``values``."""
        status = self._set_real(self._fmu.component, vrs, len(vrs), values)
        if status > 1:  # worse than warning
            self._raise("fmi2SetReal", status)

    def do_step(self, time, step):
        self.time = time
        status = self._do_step(self._fmu.component, time, step, 1)
        if status > 1:  # worse than warning
            self._raise("fmi2DoStep", status)
        self.time = time + step

    # --- teardown -------------------------------------------------------------

    def terminate(self):
        self._call("fmi2Terminate", self._fmu.terminate)

    def free(self):
        """Free the instance and unload the library; safe to call twice."""
        if self._instantiated:
            self._instantiated = False
            try:
                self._fmu.freeInstance()
            finally:
                shutil.rmtree(self._unzip, ignore_errors=True)
