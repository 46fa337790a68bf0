"""An instance outside the master: some program provides its outputs and reads its inputs.

:class:`ExternalInstance` takes the place of an FMU in a system and has exactly that
FMU's interface (its modelDescription.xml: names, value references, feedthrough), so
the wiring, the connections and their check stay the system's own: every connection
from the instance's outputs has its source, which is whatever the program last set.
Stepping it does nothing; time is the master's. This is how a PLC takes an FMU's place
in ``serve --external NAME``.
"""

import math
import threading

from .instance import Instance


class ExternalInstance(Instance):
    """The stand-in of the FMU at ``path``: its outputs are set by :meth:`set_outputs` (from any thread), its
    inputs, as the master writes them, are read by :meth:`input_values`.

    Parameters
    ----------
    path : str or Path
        The FMU whose interface the instance has (it is read, not loaded).
    name : str
        Instance name.

    Attributes
    ----------
    parameters : dict
        The values the system sets on the instance (``{name: value}``): kept, not applied; the program
        outside applies its own.
    """

    def __init__(self, path, name):
        self._interface(path, name)
        self.time = None
        self.parameters = {}
        self._lock = threading.Lock()
        self._out = [_start(self.variables[n]) for n in self.outputs]
        self._in = [_start(self.variables[n]) for n in self.inputs]
        self._out_index = {self.variables[n].valueReference: i for i, n in enumerate(self.outputs)}
        self._in_index = {self.variables[n].valueReference: i for i, n in enumerate(self.inputs)}

    def set_outputs(self, values):
        """Set outputs ``{name: value}`` at once (atomically for the master's next exchange)."""
        index = {n: i for i, n in enumerate(self.outputs)}
        for name in values:
            if name not in index:
                raise KeyError(f"{self.name} has no output {name!r}; outputs: {', '.join(self.outputs)}")
        with self._lock:
            for name, value in values.items():
                self._out[index[name]] = float(value)

    def output_values(self):
        """``{name: value}`` of the outputs as last set."""
        with self._lock:
            return dict(zip(self.outputs, self._out))

    def input_values(self):
        """``{name: value}`` of the inputs as the master last wrote them."""
        with self._lock:
            return dict(zip(self.inputs, self._in))

    # --- what the master calls ---

    def set(self, name, value):
        self._variable(name)
        self.parameters[name] = value

    def get(self, name):
        v = self._variable(name)
        with self._lock:
            if v.causality == "output":
                return self._out[self.outputs.index(name)]
            if v.causality == "input":
                return self._in[self.inputs.index(name)]
        return self.parameters.get(name, _start(v))

    def setup(self, start_time, stop_time=None):
        self.time = start_time

    def enter_initialization(self):
        pass

    def exit_initialization(self):
        pass

    def terminate(self):
        pass

    def get_state(self):
        """Its inputs as the master last wrote them (its outputs are the program's, never rolled back)."""
        with self._lock:
            return list(self._in)

    def set_state(self, state):
        with self._lock:
            self._in[:] = state

    def free_state(self, state):
        pass

    def free(self):
        pass

    def reader(self, vrs, values):
        positions = [self._out_index[vr] for vr in vrs]
        out, lock = self._out, self._lock

        def read():
            with lock:
                for i, position in enumerate(positions):
                    values[i] = out[position]
            return 0

        return read, "external get"

    def writer(self, vrs, values):
        positions = [self._in_index[vr] for vr in vrs]
        inputs, lock = self._in, self._lock

        def write():
            with lock:
                for i, position in enumerate(positions):
                    inputs[position] = values[i]
            return 0

        return write, "external set"

    def stepper(self):
        return (lambda time, step: 0), "external step"


def _start(variable):
    """A Real variable's start value as a float (0 without one)."""
    try:
        value = float(variable.start)
    except (TypeError, ValueError):
        return 0.0
    return value if math.isfinite(value) else 0.0
