"""The FMI 3.0 co-simulation adapter of :class:`~crane_fmu.cosim.instance.Instance`, on fmpy."""

import ctypes
import shutil

from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64

from .instance import Instance


class Fmi3Instance(Instance):
    """One instance of an FMI 3.0 co-simulation FMU, driven like an FMI 2.0 one by the master."""

    def __init__(self, path, name):
        self._describe(path, name)
        self._start = self._stop = None
        try:
            self._fmu = self._library_of(FMU3Slave)
            self._call("fmi3InstantiateCoSimulation", self._fmu.instantiate, loggingOn=True,
                       logMessage=self._log)
        except BaseException:
            shutil.rmtree(self._unzip, ignore_errors=True)
            raise
        self._instantiated = True
        self._library = self._hot_library()
        self._step = self.stepper()

    def _log(self, environment, status, category, message):
        self.messages.append(message.decode("utf-8", "replace") if message else "")

    def set(self, name, value):
        v = self._variable(name)
        if v.type == "Enumeration":  # by name or value; FMI 3.0 sets it as an Int64
            value = self.enumeration_value(name, value)
        kind = {"Float64": "Float64", "Float32": "Float32", "String": "String", "Boolean": "Boolean",
                "Enumeration": "Int64"}.get(v.type, "Int32")
        convert = {"String": str, "Boolean": bool}.get(kind, float if kind.startswith("Float") else int)
        self._call(f"fmi3Set{kind}", getattr(self._fmu, f"set{kind}"), [v.valueReference], [convert(value)])

    def get(self, name):
        v = self._variable(name)
        kind = v.type if v.type in ("Float64", "Float32", "String", "Boolean") else (
            "Int64" if v.type == "Enumeration" else "Int32")
        return self._call(f"fmi3Get{kind}", getattr(self._fmu, f"get{kind}"), [v.valueReference])[0]

    def setup(self, start_time, stop_time=None):
        self.time, self._start, self._stop = start_time, start_time, stop_time

    def enter_initialization(self):
        self._call("fmi3EnterInitializationMode", self._fmu.enterInitializationMode, startTime=self._start,
                   stopTime=self._stop)

    def exit_initialization(self):
        self._call("fmi3ExitInitializationMode", self._fmu.exitInitializationMode)

    def get_state(self):
        return self._call("fmi3GetFMUState", self._fmu.getFMUState)

    def set_state(self, state):
        self._call("fmi3SetFMUState", self._fmu.setFMUState, state)

    def free_state(self, state):
        self._call("fmi3FreeFMUState", self._fmu.freeFMUState, state)

    def serialize_state(self, state):
        return bytes(self._call("fmi3SerializeFMUState", self._fmu.serializeFMUState, state))

    def deserialize_state(self, data):
        return self._call("fmi3DeserializeFMUState", self._fmu.deserializeFMUState, data)

    # --- hot path (see Instance._hot_call) ---

    def reader(self, vrs, values):
        size = ctypes.c_size_t(len(vrs))
        return self._hot_call("fmi3GetFloat64", vrs, size, values, size)

    def writer(self, vrs, values):
        size = ctypes.c_size_t(len(vrs))
        return self._hot_call("fmi3SetFloat64", vrs, size, values, size)

    def stepper(self):
        # noSetFMUStatePriorToCurrentPoint; then eventHandlingNeeded, terminateSimulation, earlyReturn and
        # lastSuccessfulTime, which this master does not use (byref keeps each alive)
        outputs = (fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64())
        return self._hot_stepper("fmi3DoStep", fmi3Boolean(True), *map(ctypes.byref, outputs))

    def terminate(self):
        self._call("fmi3Terminate", self._fmu.terminate)

    def reset(self):
        """Back to the state right after instantiation (fmi3Reset), to run again."""
        self._call("fmi3Reset", self._fmu.reset)
        self.time = self._start = self._stop = None
