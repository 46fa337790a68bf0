"""BacksteppingController FMU: the anti-swing law of eqs (10)-(21)."""

import math

from pythonfmu import Fmi2Slave

from crane_fmu.model import controller, tables
from crane_fmu.model.parameters import controller_setup
from fmu_src.slave_support import register_table, restore_variables, saved_state, values


class BacksteppingController(Fmi2Slave):
    author = "crane anti-sway co-simulation toolkit"
    description = ("Backstepping anti-swing controller for a double-pendulum crane payload "
                   "(least-squares eq 21); output: trolley acceleration u, direct feedthrough")

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._law = None  # (PlantParameters, ControllerGains) once initialisation ends
        register_table(self, tables.CONTROLLER, self._current_outputs)

    def _parameters(self):
        return controller_setup(values(self, tables.CONTROLLER, "parameter"))

    def _current_outputs(self):
        p, k = self._law or self._parameters()
        # Direct feedthrough: u from the inputs as they are set now.
        state = (self.x, self.dx, self.theta1, self.dtheta1, self.theta2, self.dtheta2)
        return (controller.control(state, p, k),)

    def exit_initialization_mode(self):
        self._law = self._parameters()

    def do_step(self, current_time, step_size):
        if not (step_size > 0 and math.isfinite(step_size)):
            raise ValueError(f"communication step must be > 0 and finite, got {step_size!r}")
        return True

    # fmi2GetFMUstate / fmi2SetFMUstate: the law has no memory beyond its variables.
    def _get_fmu_state(self):
        return saved_state(self, tables.CONTROLLER, initialised=self._law is not None)

    def _set_fmu_state(self, saved):
        restore_variables(self, tables.CONTROLLER, saved)
        self._law = self._parameters() if saved["initialised"] else None
