"""What every slave does, from its component descriptor alone: values, outputs, steps, saved states.

Shared by the FMI 2.0 (pythonfmu) and FMI 3.0 (pythonfmu3) slave factories,
which only register the variables and delegate here. Standard library only: it
is bundled into every FMU with the model core.
"""

import math
import operator

from crane_fmu.model.component import Discard, Step

AUTHOR = "crane anti-sway co-simulation toolkit"


def check_step(step):
    if not (step > 0 and math.isfinite(step)):
        raise ValueError(f"communication step must be > 0 and finite, got {step!r}")


class Runtime:
    """The values, configuration and state of one FMU instance of ``component``.

    Parameters and inputs live in :attr:`values`. The configuration is set up
    (and the parameters validated) when initialisation ends; until then the
    outputs follow the parameters. Outputs are computed once per change and
    read from a cache.
    """

    def __init__(self, component):
        self.component = component
        self.values = {v.name: v.start for v in component.variables if v.causality != "output"}
        self._parameters = component.names("parameter")
        self._inputs = component.names("input")
        self.initialised = False
        self.config = self.state = None  # set when initialisation ends
        self.time = 0.0
        self._outputs = None
        self.messages = []  # the last step's messages for the host's log

    def inputs(self):
        return tuple(self.values[name] for name in self._inputs)

    def set_parameter(self, name, value):
        self.values[name] = value
        self._outputs = None

    def set_input(self, name, value):
        """Set a Real input; a value that is not finite is refused (ValueError naming the input)."""
        if not math.isfinite(value):
            raise ValueError(f"input {name} must be finite, got {value!r}")
        self.values[name] = value
        if self.component.feedthrough:
            self._outputs = None

    def output(self, index):
        """The output at ``index`` (in table order of the outputs)."""
        return self.outputs()[index]

    def outputs(self):
        """Every output, in table order (computed once per change)."""
        if self._outputs is None:
            config, state = self.config, self.state
            if not self.initialised:  # outputs follow the parameters
                config = self.component.setup({name: self.values[name] for name in self._parameters})
                state = self.component.initial_state(config) if self.component.stateful else None
            self._outputs = self.component.output(config, state, self.inputs())
        return self._outputs

    def initialise(self, state=None):
        """End of initialisation (or a restored state): validate the parameters, set the state."""
        self.config = self.component.setup({name: self.values[name] for name in self._parameters})
        self.initialised = True
        if self.component.stateful:
            self.state = self.component.initial_state(self.config) if state is None else tuple(state)
        self._outputs = None

    def step(self, time, step):
        """Advance one communication step; return None, or the reason the step is discarded.

        Messages the component gives with the new state are kept in :attr:`messages` for the slave to log.
        """
        check_step(step)
        self.messages = []
        if not self.initialised:
            raise RuntimeError("doStep before initialisation ended")
        if self.component.stateful:
            try:
                state = self.component.update(self.config, self.state, self.inputs(), time, step)
            except Discard as exc:
                return str(exc)
            if isinstance(state, Step):
                state, self.messages = state
            self.state = state
        self.time = time + step
        self._outputs = None
        return None

    def saved(self):
        """The full state for get-FMU-state: JSON-able and exact (floats survive JSON bit for bit)."""
        return {"values": dict(self.values), "initialised": self.initialised, "time": self.time,
                "state": None if self.state is None else list(self.state)}

    def restore(self, saved):
        self.values = dict(saved["values"])
        self.time = saved["time"]
        self.initialised, self.config, self.state, self._outputs = False, None, None, None
        if saved["initialised"]:
            self.initialise(saved["state"])


def register(slave, runtime, real, string, causality, variability, initial, units=False):
    """Register every variable of the runtime's component on a pythonfmu or pythonfmu3 ``slave``.

    ``real`` and ``string`` are the FMI version's variable classes, ``causality``,
    ``variability`` and ``initial`` its enums; ``units`` declares each variable's
    unit (FMI 3.0). Values live in ``runtime``. Outputs are ``initial=calculated``
    (listed as InitialUnknowns by the build's post-processing); a Real input
    refuses a value that is not finite.
    """
    position = 0
    for v in runtime.component.variables:
        kind = string if v.type == "String" else real
        common = dict(causality=causality[v.causality], variability=variability[v.variability],
                      description=v.description)
        if units and v.unit:
            common["unit"] = v.unit
        if v.causality == "output":
            slave.register_variable(kind(v.name, initial=initial.calculated,
                                         getter=lambda i=position: runtime.output(i), **common))
            position += 1
            continue
        setter = runtime.set_input if v.causality == "input" and kind is real else runtime.set_parameter
        slave.register_variable(kind(v.name, start=v.start, getter=lambda n=v.name: runtime.values[n],
                                     setter=lambda value, n=v.name, f=setter: f(n, value), **common))


class SlaveCalls:
    """The FMI calls that every slave delegates to its :class:`Runtime` (``self.runtime``).

    A slave class sets ``WARNING`` and ``ERROR`` to its FMI version's log statuses.
    """

    WARNING = ERROR = None

    def _index_reals(self, real):
        """Prepare the batched get and set of the variables of class ``real`` (Real or Float64)."""
        outputs = self.runtime.component.names("output")
        # value reference -> output position, or the variable's getter and setter
        self._output_index = {vr: outputs.index(v.name) for vr, v in self.vars.items() if v.name in outputs}
        self._getters = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, real)}
        self._setters = {vr: v.setter for vr, v in self.vars.items() if isinstance(v, real) and v.setter}
        self._reads = {}

    def get_reals(self, vrs):
        """One Python call per FMI get: outputs are picked from one cached tuple, in C."""
        key = tuple(vrs)
        pick = self._reads.get(key)
        if pick is None:
            if not all(vr in self._output_index for vr in key):
                return [float(self._getters[vr]()) for vr in key]  # KeyError: not a Real
            indices = [self._output_index[vr] for vr in key]
            n_outputs = len(self.runtime.component.names("output"))
            pick = self._reads[key] = (tuple if indices == list(range(n_outputs))  # every output, in order
                                       else operator.itemgetter(*indices) if len(indices) > 1
                                       else lambda values, i=indices[0]: (values[i],))
        return pick(self.runtime.outputs())

    def set_reals(self, vrs, values):
        setters = self._setters
        for vr, value in zip(vrs, values):
            setters[vr](value)

    def exit_initialization_mode(self):
        self.runtime.initialise()

    def do_step(self, current_time, step_size):
        reason = self.runtime.step(current_time, step_size)
        for message in self.runtime.messages:
            self.log(message, self.WARNING)
        if reason:
            self.log(reason, self.ERROR)
        return reason is None

    def _get_fmu_state(self):
        return self.runtime.saved()

    def _set_fmu_state(self, saved):
        self.runtime.restore(saved)
