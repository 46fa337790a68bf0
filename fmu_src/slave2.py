"""The FMI 2.0 slave class of any component (pythonfmu).

``crane-fmu build`` generates, per component, a script whose only class is
``class <ModelIdentifier>(Fmi2Slave)`` with ``Fmi2Slave = slave_base(COMPONENT)``.
"""

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from crane_fmu.fmu_src.runtime import AUTHOR, Runtime, SlaveCalls


def register(slave, runtime):
    """Register every variable of the runtime's component on ``slave``, backed by ``runtime``.

    Outputs are ``initial=calculated`` (listed as InitialUnknowns by the build's
    post-processing); a Real input refuses a value that is not finite.
    """
    position = 0
    for v in runtime.component.variables:
        kind = String if v.type == "String" else Real
        common = dict(causality=Fmi2Causality[v.causality], variability=Fmi2Variability[v.variability],
                      description=v.description)
        if v.causality == "output":
            slave.register_variable(kind(v.name, initial=Fmi2Initial.calculated,
                                         getter=lambda i=position: runtime.output(i), **common))
            position += 1
            continue
        setter = runtime.set_input if v.causality == "input" and kind is Real else runtime.set_parameter
        slave.register_variable(kind(v.name, start=v.start, getter=lambda n=v.name: runtime.values[n],
                                     setter=lambda value, n=v.name, f=setter: f(n, value), **common))


def slave_base(component):
    """An ``Fmi2Slave`` subclass that runs ``component``."""

    class Base(SlaveCalls, Fmi2Slave):
        WARNING, ERROR = Fmi2Status.warning, Fmi2Status.error
        author = AUTHOR
        description = component.description
        default_experiment = (DefaultExperiment(*component.default_experiment)
                              if component.default_experiment else None)

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.runtime = Runtime(component)
            register(self, self.runtime)
            outputs = component.names("output")
            # value reference -> output position, or the variable's getter and setter
            self._output_index = {vr: outputs.index(v.name) for vr, v in self.vars.items() if v.name in outputs}
            self._getters = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, Real)}
            self._setters = {vr: v.setter for vr, v in self.vars.items() if isinstance(v, Real) and v.setter}
            self._reads = {}

        def get_real(self, vrs):
            """One Python call per fmi2GetReal: outputs come from one cached tuple."""
            key = tuple(vrs)
            indices = self._reads.get(key)
            if indices is None:
                if not all(vr in self._output_index for vr in key):
                    return [float(self._getters[vr]()) for vr in key]  # KeyError: not a Real
                indices = self._reads[key] = [self._output_index[vr] for vr in key]
            values = self.runtime.outputs()
            return [values[i] for i in indices]

        def set_real(self, vrs, values):
            setters = self._setters
            for vr, value in zip(vrs, values):
                setters[vr](value)

    return Base
