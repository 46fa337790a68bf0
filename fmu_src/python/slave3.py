"""The FMI 3.0 slave class of any component (pythonfmu3), with its units declared natively.

``crane-fmu build`` generates, per component, a script whose only class is
``class <ModelIdentifier>(Fmi3Slave)`` with ``Fmi3Slave = slave_base(COMPONENT)``.
"""

from pythonfmu3 import Float64, Fmi3Causality, Fmi3Initial, Fmi3Slave, Fmi3Status, Fmi3Variability, Int64, String
from pythonfmu3.default_experiment import DefaultExperiment
from pythonfmu3.unit import Unit

from crane_fmu.fmu_src.python.runtime import AUTHOR, Runtime, SlaveCalls, register
from crane_fmu.model.tables import BASE_UNITS


def register_with_time(slave, runtime):
    """The component's variables with their units, and the independent variable ``time``."""
    slave.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                    variability=Fmi3Variability.continuous, description="simulation time",
                                    getter=lambda: runtime.time))
    table = runtime.component.variables
    slave.register_units([Unit(name, **BASE_UNITS[name]) for name in sorted({v.unit for v in table if v.unit})])
    register(slave, runtime, Float64, String, Fmi3Causality, Fmi3Variability, Fmi3Initial, units=True, integer=Int64)


def slave_base(component):
    """An ``Fmi3Slave`` subclass that runs ``component``."""

    class Base(SlaveCalls, Fmi3Slave):
        WARNING, DISCARD = Fmi3Status.warning, Fmi3Status.discard

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.author, self.description = AUTHOR, component.description
            if component.default_experiment:
                self.default_experiment = DefaultExperiment(*component.default_experiment)
            self.runtime = Runtime(component)
            register_with_time(self, self.runtime)
            self._index_reals(Float64)

        get_float64, set_float64 = SlaveCalls.get_reals, SlaveCalls.set_reals

    return Base
