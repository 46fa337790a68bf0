"""TrivialPlant FMU: the plant's interface with next to no computation (benchmark floor)."""

from pythonfmu import Fmi2Slave

from crane_fmu.model import tables
from fmu_src.slave_support import register_table


class TrivialPlant(Fmi2Slave):
    description = "Benchmark floor: CranePlant's input and state outputs, outputs = time / 3 + u / 1000"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._values = (0.0,) * 6
        register_table(self, tables.TRIVIAL_PLANT, lambda: self._values)

    def do_step(self, current_time, step_size):
        # Full-precision values, so that recording them costs what real outputs cost.
        self._values = ((current_time + step_size) / 3.0 + 1e-3 * self.u,) * 6
        return True
