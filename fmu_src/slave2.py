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
            self._index_reals(Real)

        get_real, set_real = SlaveCalls.get_reals, SlaveCalls.set_reals

    return Base
