"""The FMI 2.0 co-simulation adapter of :class:`~crane_fmu.cosim.instance.Instance`, on fmpy."""

import ctypes
import functools
import itertools
import shutil
import weakref
from pathlib import Path

from fmpy import calloc, free
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

from .compiled_loop import compiled
from .instance import Instance

# Every instance logs through one C function that formats the FMU's printf-style messages (fmi2_log.c) for
# _dispatch, which tells them apart by the componentEnvironment each instance passes. Not through fmpy's proxy
# (fmpy.logging): its one target per process is replaced by any other host in the process that uses it, and the
# instances made before then lose their messages; it serves only where no C compiler made ours.
LOG_SOURCE = Path(__file__).with_name("fmi2_log.c")
_instances = weakref.WeakValueDictionary()
_keys = itertools.count(1)


def _dispatch(environment, instance_name, status, category, message):
    instance = _instances.get(environment or 0)
    if instance is not None:
        instance.messages.append(message.decode("utf-8", "replace"))


_LOGGER = fmi2CallbackLoggerTYPE(_dispatch)
_CONVERT = {"Real": float, "Integer": int, "Boolean": bool, "String": str}


@functools.cache
def _formatter():
    """The logger of fmi2_log.c, whose target is _dispatch; None without a C compiler."""
    lib = compiled(LOG_SOURCE)
    if lib is None:
        return None
    lib.set_sink.argtypes, lib.set_sink.restype = [fmi2CallbackLoggerTYPE], None
    lib.set_sink(_LOGGER)
    return fmi2CallbackLoggerTYPE(ctypes.cast(lib.log_message, ctypes.c_void_p).value)


class Fmi2Instance(Instance):
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
            self._fmu = self._library_of(FMU2Slave)
            key = next(_keys)
            _instances[key] = self
            self._callbacks = fmi2CallbackFunctions()
            formatter = _formatter()
            self._callbacks.logger = formatter or _LOGGER
            self._callbacks.componentEnvironment = key
            self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            if formatter is None:
                addLoggerProxy(ctypes.byref(self._callbacks))
            self._call("fmi2Instantiate", self._fmu.instantiate, callbacks=self._callbacks, loggingOn=True)
        except BaseException:
            shutil.rmtree(self._unzip, ignore_errors=True)
            raise
        self._instantiated = True
        self._library = self._hot_library()
        self._step = self.stepper()
        # Ask for every log message. (pythonfmu 0.7's own binary ignores this and loggingOn
        # alike and never calls the logger, so its errors arrive without a reason.)
        self._call("fmi2SetDebugLogging", self._fmu.setDebugLogging, True, [])

    # --- setup -----------------------------------------------------------------

    def set(self, name, value):
        """Set one variable by name, converting ``value`` to the variable's type."""
        v = self._variable(name)
        if v.type == "Enumeration":  # by name or value; FMI 2.0 sets it as an Integer
            value = self.enumeration_value(name, value)
        kind = "Integer" if v.type == "Enumeration" else v.type
        setter = getattr(self._fmu, f"set{kind}")
        self._call(f"fmi2Set{kind}", setter, [v.valueReference], [_CONVERT[kind](value)])

    def get(self, name):
        """Get one variable by name."""
        v = self._variable(name)
        kind = "Integer" if v.type == "Enumeration" else v.type
        value = self._call(f"fmi2Get{kind}", getattr(self._fmu, f"get{kind}"), [v.valueReference])[0]
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

    # --- hot path (see Instance._hot_call) ---

    def reader(self, vrs, values):
        return self._hot_call("fmi2GetReal", vrs, ctypes.c_size_t(len(vrs)), values)

    def writer(self, vrs, values):
        return self._hot_call("fmi2SetReal", vrs, ctypes.c_size_t(len(vrs)), values)

    def stepper(self):
        return self._hot_stepper("fmi2DoStep", ctypes.c_int(1))  # noSetFMUStatePriorToCurrentPoint

    def terminate(self):
        self._call("fmi2Terminate", self._fmu.terminate)

    def reset(self):
        """Back to the state right after instantiation (fmi2Reset), to run again."""
        self._call("fmi2Reset", self._fmu.reset)
        self.time = None
