"""CranePlant FMU (FMI 3.0): the double-pendulum payload under a trolley, eqs (4)-(9)."""

from pythonfmu3 import Fmi3Slave, Fmi3Status
from pythonfmu3.default_experiment import DefaultExperiment

from crane_fmu.model import tables
from fmu_src import crane_logic as logic
from fmu_src.slave_support3 import register_table3


class CranePlant(Fmi3Slave):
    author = "crane anti-sway co-simulation toolkit"
    description = logic.PLANT_DESCRIPTION
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=20.0, step_size=0.01)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        logic.plant_start(self)
        register_table3(self, tables.PLANT, lambda: logic.plant_outputs(self))

    def exit_initialization_mode(self):
        logic.plant_initialise(self)

    def do_step(self, current_time, step_size):
        reason = logic.plant_step(self, current_time, step_size)
        if reason:
            self.log(reason, Fmi3Status.error)
            return False
        self.time = current_time + step_size
        return True

    def _get_fmu_state(self):
        return logic.plant_saved(self)

    def _set_fmu_state(self, saved):
        logic.plant_restore(self, saved)
