"""TrivialPlant FMU: the plant's interface with next to no computation (benchmark floor)."""

from pythonfmu import Fmi2Slave

from crane_fmu.model import tables
from fmu_src.slave_support import register_table


class TrivialPlant(Fmi2Slave):
    description = "Benchmark floor: CranePlant's input and state outputs, outputs = u * time"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._value = 0.0
        register_table(self, tables.TRIVIAL_PLANT, lambda name: self._value)

    def do_step(self, current_time, step_size):
        self._value = self.u * (current_time + step_size)
        return True
