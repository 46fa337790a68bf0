"""BacksteppingController FMU (FMI 3.0): the anti-swing law of eqs (10)-(21)."""

from pythonfmu3 import Fmi3Slave

from crane_fmu.model import tables
from fmu_src import crane_logic as logic
from fmu_src.slave_support3 import register_table3


class BacksteppingController(Fmi3Slave):
    author = "crane anti-sway co-simulation toolkit"
    description = logic.CONTROLLER_DESCRIPTION

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        logic.controller_start(self)
        register_table3(self, tables.CONTROLLER, lambda: logic.controller_outputs(self))

    def exit_initialization_mode(self):
        logic.controller_initialise(self)

    def do_step(self, current_time, step_size):
        logic.check_step(step_size)
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return logic.controller_saved(self)

    def _set_fmu_state(self, saved):
        logic.controller_restore(self, saved)
