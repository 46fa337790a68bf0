"""The FMI 2.0 slave class of any component (pythonfmu).

``crane-fmu build`` generates, per component, a script whose only class is
``class <ModelIdentifier>(Fmi2Slave)`` with ``Fmi2Slave = slave_base(COMPONENT)``.
"""

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from crane_fmu.fmu_src.python.runtime import AUTHOR, Runtime, SlaveCalls, register


def slave_base(component):
    """An ``Fmi2Slave`` subclass that runs ``component``."""

    class Base(SlaveCalls, Fmi2Slave):
        WARNING, DISCARD = Fmi2Status.warning, Fmi2Status.discard
        author = AUTHOR
        description = component.description
        default_experiment = (DefaultExperiment(*component.default_experiment)
                              if component.default_experiment else None)

        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.runtime = Runtime(component)
            register(self, self.runtime, Real, String, Fmi2Causality, Fmi2Variability, Fmi2Initial,
                     integer=Integer)
            self._index_reals(Real)

        get_real, set_real = SlaveCalls.get_reals, SlaveCalls.set_reals

    return Base
