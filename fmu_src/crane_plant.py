"""CranePlant FMU: the double-pendulum payload under a trolley, eqs (4)-(9)."""

import math

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from crane_fmu.model import plant, tables
from crane_fmu.model.parameters import plant_setup
from fmu_src.slave_support import register_table, restore_variables, saved_state, values


class CranePlant(Fmi2Slave):
    author = "crane anti-sway co-simulation toolkit"
    description = ("Overhead crane with a double-pendulum payload (hook m1 on cable l1, payload m2 "
                   "on cable l2); input: trolley acceleration u; fixed-step RK4 inside doStep")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=20.0, step_size=0.01)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._state = None  # plant state once initialisation ends
        self._outputs = None  # plant.outputs(state) after every step
        register_table(self, tables.PLANT, self._current_outputs)

    def _initial_state(self):
        return (self.x0, self.dx0, self.theta1_0, self.dtheta1_0, self.theta2_0, self.dtheta2_0)

    def _current_outputs(self):
        if self._outputs is None:  # initialisation mode: outputs follow the parameters
            params, _ = plant_setup(values(self, tables.PLANT, "parameter"))
            return plant.outputs(self._initial_state(), params)
        return self._outputs

    def exit_initialization_mode(self):
        self._params, self._max_substep = plant_setup(values(self, tables.PLANT, "parameter"))
        self._state = self._initial_state()
        self._outputs = plant.outputs(self._state, self._params)

    def do_step(self, current_time, step_size):
        if self._state is None:
            raise RuntimeError("doStep before initialisation ended (fmi2ExitInitializationMode)")
        plant.substeps(step_size, self._max_substep)  # raises ValueError for an unusable step size
        try:
            state = plant.advance(self._state, self.u, step_size, self._max_substep, self._params)
            finite = all(map(math.isfinite, state))
        except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
            finite = False
        if not finite:
            self.log(f"plant state became non-finite in the step from t={current_time!r} s "
                     f"(u={self.u!r} m/s2); the step is discarded", Fmi2Status.error)
            return False
        self._state = state
        self._outputs = plant.outputs(state, self._params)
        return True

    # fmi2GetFMUstate / fmi2SetFMUstate: the variables and the integrator state.
    def _get_fmu_state(self):
        return saved_state(self, tables.PLANT, state=None if self._state is None else list(self._state))

    def _set_fmu_state(self, saved):
        restore_variables(self, tables.PLANT, saved)
        if saved["state"] is None:
            self._state = self._outputs = None
        else:
            self._params, self._max_substep = plant_setup(values(self, tables.PLANT, "parameter"))
            self._state = tuple(saved["state"])
            self._outputs = plant.outputs(self._state, self._params)
