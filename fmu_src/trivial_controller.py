"""TrivialController FMU: the controller's interface with next to no computation (benchmark floor)."""

from pythonfmu import Fmi2Slave

from crane_fmu.model import tables
from fmu_src.slave_support import register_table


class TrivialController(Fmi2Slave):
    description = "Benchmark floor: BacksteppingController's inputs and output, u = -x (feedthrough)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        register_table(self, tables.TRIVIAL_CONTROLLER, lambda: (-self.x,))

    def do_step(self, current_time, step_size):
        return True
