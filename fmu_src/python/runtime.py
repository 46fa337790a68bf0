"""What every slave does, from its component descriptor alone: values, outputs, steps, saved states.

Shared by the FMI 2.0 (pythonfmu) and FMI 3.0 (pythonfmu3) slave factories,
which only register the variables and delegate here. Standard library only: it
is bundled into every FMU with the model core.
"""

import functools
import math
import numbers
import operator
from math import isfinite

from crane_fmu.model.component import Discard, Step
from crane_fmu.model.tables import enumeration_name, enumeration_value

AUTHOR = "crane anti-sway co-simulation toolkit"
# A communication step this short is a host's rounding, not a step: hosts that add up their steps (OMSimulator,
# a loop of t += h) end a run with the remainder stop - t, 1.03e-13 s after 10,000 steps of 1 ms. It is taken as
# no step (time moves on, the state does not), as the one-FMU systems take 1e-6 of their 1 ms system step
# (fmu_src/system/system.c STEP_ROUNDING); instance.c has the same rule for the native components.
ROUNDING_STEP = 1e-9  # s


class Runtime:
    """The values, configuration and state of one FMU instance of ``component``.

    Parameters live in :attr:`values`, inputs in the list :attr:`inputs` (table
    order). The configuration is set up (and the parameters validated) when
    initialisation ends; until then the outputs follow the parameters. Outputs
    are computed once per change and read from a cache.
    """

    def __init__(self, component):
        self.component = component
        self.values = {v.name: v.start for v in component.variables if v.causality == "parameter"}
        self.inputs = [v.start for v in component.variables if v.causality == "input"]
        self._input_names, self._output_names = component.names("input"), component.names("output")
        self._stateful, self._feedthrough = component.stateful, component.feedthrough
        self.initialised = False
        self.config = self.state = None  # set when initialisation ends
        self.time = 0.0
        self._outputs = None
        self.messages = self.notes = ()  # the last step's warnings and notes for the host's log

    def set_parameter(self, name, value):
        self.values[name] = value
        self._outputs = None

    def set_inputs(self, positions, values):
        """Set the inputs at ``positions`` (table order; None: all, in order) to the Real ``values``.

        A value that is not finite is refused (ValueError naming the input) and nothing is set.
        """
        for value in values:
            if not isfinite(value):
                i = next(i for i, v in enumerate(values) if not isfinite(v))
                name = self._input_names[i if positions is None else positions[i]]
                raise ValueError(f"input {name} must be finite, got {value!r}")
        if positions is None:
            self.inputs[:] = values
        else:
            inputs = self.inputs
            for position, value in zip(positions, values):
                inputs[position] = value
        if self._feedthrough:
            self._outputs = None

    def output(self, index):
        """The output at ``index`` (in table order of the outputs)."""
        return self.outputs()[index]

    def outputs(self):
        """Every output, in table order (computed once per change)."""
        if self._outputs is None:
            config, state = self.config, self.state
            if not self.initialised:  # outputs follow the parameters
                config = self.component.configure(dict(self.values))
                state = self.component.initial_state(config) if self._stateful else None
            outputs = self.component.output(config, state, tuple(self.inputs))
            if type(outputs) is not tuple or len(outputs) != len(self._output_names) or \
                    not all(type(v) is float for v in outputs):
                outputs = self._checked(outputs)
            self._outputs = outputs
        return self._outputs

    def _checked(self, outputs):
        """The component's ``output`` value as the tuple of its outputs' numbers (a list or array of them is taken);
        ValueError naming the function, what it must return and what it gave."""
        names = self._output_names
        if isinstance(outputs, (str, bytes)) or not hasattr(outputs, "__len__") or len(outputs) != len(names) or \
                not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in outputs):
            raise ValueError(f"{getattr(self.component.output, '__name__', 'output')} must return a tuple of "
                             f"{len(names)} number{'s' * (len(names) != 1)} ({', '.join(names)}), got {outputs!r}")
        return tuple(outputs)

    def initialise(self, state=None):
        """End of initialisation (or a restored state): validate the parameters, set the state."""
        self.config = self.component.configure(dict(self.values))
        self.initialised = True
        if self._stateful:
            self.state = self.component.initial_state(self.config) if state is None else tuple(state)
        self._outputs = None

    def step(self, time, step):
        """Advance one communication step; return None, or the reason the step is discarded.

        Warnings and notes the component gives with the new state are kept in :attr:`messages` and
        :attr:`notes` for the slave to log.
        """
        if not (step > 0 and step < math.inf):
            raise ValueError(f"communication step must be > 0 and finite, got {step!r}")
        if not self.initialised:
            raise RuntimeError("doStep before initialisation ended")
        self.messages = self.notes = ()
        if self._stateful and step > ROUNDING_STEP:
            try:
                state = self.component.update(self.config, self.state, tuple(self.inputs), time, step)
            except Discard as exc:
                return str(exc)
            if type(state) is Step:
                state, self.messages, self.notes = state
            self.state = state
        self.time = time + step
        self._outputs = None
        return None

    def saved(self):
        """The full state for get-FMU-state: JSON-able and exact (floats survive JSON bit for bit)."""
        return {"values": dict(self.values), "inputs": list(self.inputs), "initialised": self.initialised,
                "time": self.time, "state": None if self.state is None else list(self.state)}

    def restore(self, saved):
        self.values, self.inputs = dict(saved["values"]), list(saved["inputs"])
        self.time = saved["time"]
        self.initialised, self.config, self.state, self._outputs = False, None, None, None
        if saved["initialised"]:
            self.initialise(saved["state"])


def register(slave, runtime, real, string, causality, variability, initial, units=False, integer=None):
    """Register every variable of the runtime's component on a pythonfmu or pythonfmu3 ``slave``.

    ``real``, ``string`` and ``integer`` are the FMI version's variable classes (``integer``, Integer or Int64,
    for an Enumeration: the build's post-processing declares its type; the runtime keeps the item's name,
    the host gets and sets its value), ``causality``,
    ``variability`` and ``initial`` its enums; ``units`` declares each variable's
    unit (FMI 3.0). Values live in ``runtime``. Outputs are ``initial=calculated``
    (listed as InitialUnknowns by the build's post-processing); inputs are Real
    and refuse a value that is not finite.
    """
    outputs, inputs = runtime.component.names("output"), runtime.component.names("input")
    for v in runtime.component.variables:
        kind = string if v.type == "String" else real
        common = dict(causality=causality[v.causality], variability=variability[v.variability],
                      description=v.description)
        if units and v.unit:
            common["unit"] = v.unit
        if v.causality == "output":
            i = outputs.index(v.name)
            slave.register_variable(kind(v.name, initial=initial.calculated,
                                         getter=lambda i=i: runtime.output(i), **common))
        elif v.causality == "input":
            if kind is not real:
                raise TypeError(f"{runtime.component.model_identifier}.{v.name}: an input must be Real")
            i = inputs.index(v.name)
            slave.register_variable(kind(v.name, start=v.start, getter=lambda i=i: runtime.inputs[i],
                                         setter=lambda value, i=i: runtime.set_inputs((i,), (value,)), **common))
        elif v.type == "Enumeration":
            slave.register_variable(integer(
                v.name, start=enumeration_value(v, v.start),
                getter=lambda v=v: enumeration_value(v, runtime.values[v.name]),
                setter=lambda value, v=v: runtime.set_parameter(v.name, enumeration_name(v, int(value))), **common))
        else:
            slave.register_variable(kind(v.name, start=v.start, getter=lambda n=v.name: runtime.values[n],
                                         setter=lambda value, n=v.name: runtime.set_parameter(n, value), **common))


class SlaveCalls:
    """The FMI calls that every slave delegates to its :class:`Runtime` (``self.runtime``).

    A slave class sets ``WARNING`` and ``DISCARD`` to its FMI version's log statuses.
    """

    WARNING = DISCARD = None

    def _index_reals(self, real):
        """Prepare the readers and writers of the variables of class ``real`` (Real or Float64)."""
        component = self.runtime.component
        outputs, inputs = component.names("output"), component.names("input")
        # value reference -> output or input position, or the variable's getter and setter
        self._output_index = {vr: outputs.index(v.name) for vr, v in self.vars.items() if v.name in outputs}
        self._input_index = {vr: inputs.index(v.name) for vr, v in self.vars.items() if v.name in inputs}
        self._getters = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, real)}
        self._setters = {vr: v.setter for vr, v in self.vars.items() if isinstance(v, real) and v.setter}

    def real_reader(self, vrs):
        """A function of no arguments that returns the Real values of ``vrs``.

        The wrapper asks once per value-reference array and keeps it: a get of
        outputs is then one call that picks them from the runtime's cached tuple.
        ValueError naming a value reference that is not a Real.
        """
        runtime = self.runtime
        if not all(vr in self._output_index for vr in vrs):
            getters = self._lookup(self._getters, vrs)
            return lambda: [float(get()) for get in getters]
        indices = [self._output_index[vr] for vr in vrs]
        if indices == list(range(len(self._output_index))):
            return runtime.outputs  # every output, in order
        if len(indices) == 1:
            return lambda i=indices[0]: (runtime.outputs()[i],)
        pick = operator.itemgetter(*indices)
        return lambda: pick(runtime.outputs())

    def real_writer(self, vrs):
        """A function that sets the Real variables of ``vrs`` to its argument, a sequence of values.

        Asked for once per value-reference array, like :meth:`real_reader`: inputs
        are set together, checked first. ValueError naming a variable that is not a
        settable Real.
        """
        if not all(vr in self._input_index for vr in vrs):
            setters = self._lookup(self._setters, vrs)

            def write(values):
                for set_, value in zip(setters, values):
                    set_(value)
            parameter = next(self.vars[vr].name for vr in vrs if vr not in self._input_index)
            # the binary refuses the write once initialisation has ended with this line (component.c's store_reals)
            write.fixed = (f"{parameter} is a fixed parameter of {self.runtime.component.model_identifier}: it can be "
                           "set only before initialisation ends")
            return write
        positions = [self._input_index[vr] for vr in vrs]
        return functools.partial(self.runtime.set_inputs,
                                 None if positions == list(range(len(self._input_index))) else positions)

    def _lookup(self, table, vrs):
        """``[table[vr] for vr in vrs]``, or a ValueError that names the first variable missing and why."""
        missing = next((vr for vr in vrs if vr not in table), None)
        if missing is None:
            return [table[vr] for vr in vrs]
        component = self.runtime.component
        variable = self.vars.get(missing)
        if variable is None:
            raise ValueError(f"{component.model_identifier} has no variable with value reference {missing}")
        row = next((v for v in component.variables if v.name == variable.name), None)
        if row is None:  # FMI 3.0's time, read with any others
            raise ValueError(f"{variable.name} (value reference {missing}) is the independent variable: it is never "
                             "set")
        if row.type == "String":
            raise ValueError(f"{row.name} of {component.model_identifier} is a String, not a Real")
        raise ValueError(f"{row.name} is an {row.causality} of {component.model_identifier}; only parameters and "
                         "inputs can be set")

    def get_enumerations(self, vrs):
        """The values of the Enumeration variables ``vrs`` (our binaries' fmi2GetInteger, fmi3GetInt64)."""
        return [int(get()) for get in self._lookup_typed(vrs, "Enumeration", "getter")]

    def set_enumerations(self, vrs, values):
        """Set the Enumeration variables ``vrs`` to the item values ``values``, all checked first."""
        setters = self._lookup_typed(vrs, "Enumeration", "setter")
        rows = {v.name: v for v in self.runtime.component.variables}
        for vr, value in zip(vrs, values):
            enumeration_name(rows[self.vars[vr].name], value)
        for set_, value in zip(setters, values):
            set_(value)

    def _lookup_typed(self, vrs, kind, role):
        """The getters or setters (``role``) of ``vrs``, each a variable of type ``kind``; ValueError naming the first
        that is not."""
        component = self.runtime.component
        rows = {v.name: v for v in component.variables}
        found = []
        for vr in vrs:
            variable = self.vars.get(vr)
            if variable is None:
                raise ValueError(f"{component.model_identifier} has no variable with value reference {vr}")
            row = rows.get(variable.name)
            if row is None or row.type != kind:
                have = "the independent variable time" if row is None else f"a {row.type}"
                raise ValueError(f"{variable.name} of {component.model_identifier} is {have}, not an {kind}")
            found.append(getattr(variable, role))
        return found

    def get_reals(self, vrs):
        """pythonfmu's batched get, for its own binaries (ours use :meth:`real_reader`)."""
        return self.real_reader(tuple(vrs))()

    def set_reals(self, vrs, values):
        """pythonfmu's batched set, for its own binaries (ours use :meth:`real_writer`)."""
        self.real_writer(tuple(vrs))(values)

    def setup_experiment(self, start_time, *rest):
        """pythonfmu's (start, stop, tolerance) and pythonfmu3's (start): time starts at ``start_time``."""
        super().setup_experiment(start_time, *rest)
        self.runtime.time = start_time

    def exit_initialization_mode(self):
        self.runtime.initialise()

    def do_step(self, current_time, step_size):
        runtime = self.runtime
        reason = runtime.step(current_time, step_size)
        for message in runtime.messages:
            self.log(message, self.WARNING)
        for note in runtime.notes:
            self.log(note)  # status OK: the host sees it when it asks for every message
        if reason:
            self.log(reason, self.DISCARD)
        return reason is None

    def _get_fmu_state(self):
        return self.runtime.saved()

    def _set_fmu_state(self, saved):
        self.runtime.restore(saved)

