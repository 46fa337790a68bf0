"""The slaves' behaviour, shared by the FMI 2.0 (pythonfmu) and FMI 3.0 (pythonfmu3) FMUs.

Functions of a slave object whose parameters and inputs are attributes named
as in crane_fmu.model.tables; the slave classes only register variables and
call these.
"""

import math

from crane_fmu.model import controller, plant, tables
from crane_fmu.model.parameters import controller_setup, plant_setup

PLANT_DESCRIPTION = ("Overhead crane with a double-pendulum payload (hook m1 on cable l1, payload m2 on cable l2); "
                     "input: trolley acceleration u; fixed-step RK4 inside doStep")
CONTROLLER_DESCRIPTION = ("Backstepping anti-swing controller for a double-pendulum crane payload "
                          "(least-squares eq 21); output: trolley acceleration u, direct feedthrough")


def values(slave, table, causality):
    """``{name: value}`` of the slave's variables of one causality."""
    return {v.name: getattr(slave, v.name) for v in table if v.causality == causality}


def checked_input(name, value):
    """A Real input's value, or ValueError naming the input when it is not finite."""
    if not math.isfinite(value):
        raise ValueError(f"input {name} must be finite, got {value!r}")
    return value


def saved_state(slave, table, **internal):
    """The slave's full state for get-FMU-state: every parameter and input, plus ``internal``.

    JSON-able (pythonfmu serialises it with json), and exact: floats survive
    the JSON round trip bit for bit.
    """
    return {"variables": {v.name: getattr(slave, v.name) for v in table if v.causality != "output"}, **internal}


def restore_variables(slave, table, saved):
    """Set every parameter and input back from :func:`saved_state`."""
    for v in table:
        if v.causality != "output":
            setattr(slave, v.name, saved["variables"][v.name])


def check_step(step_size):
    if not (step_size > 0 and math.isfinite(step_size)):
        raise ValueError(f"communication step must be > 0 and finite, got {step_size!r}")


# --- CranePlant ------------------------------------------------------------------

def plant_start(slave):
    slave._state = None  # plant state once initialisation ends
    slave._outputs = None  # plant.outputs(state) after every step


def _initial_state(slave):
    return (slave.x0, slave.dx0, slave.theta1_0, slave.dtheta1_0, slave.theta2_0, slave.dtheta2_0)


def plant_outputs(slave):
    if slave._outputs is None:  # initialisation mode: outputs follow the parameters
        params, _ = plant_setup(values(slave, tables.PLANT, "parameter"))
        return plant.outputs(_initial_state(slave), params)
    return slave._outputs


def plant_initialise(slave, state=None):
    """End of initialisation (or a restored state): validate the parameters, set the state."""
    slave._params, slave._max_substep = plant_setup(values(slave, tables.PLANT, "parameter"))
    slave._state = _initial_state(slave) if state is None else tuple(state)
    slave._outputs = plant.outputs(slave._state, slave._params)


def plant_step(slave, current_time, step_size):
    """Advance one communication step; return None, or the reason the step is discarded."""
    if slave._state is None:
        raise RuntimeError("doStep before initialisation ended")
    plant.substeps(step_size, slave._max_substep)  # raises ValueError for an unusable step size
    try:
        state = plant.advance(slave._state, slave.u, step_size, slave._max_substep, slave._params)
        finite = all(map(math.isfinite, state))
    except (ArithmeticError, ValueError):  # overflow, or sin/cos of inf
        finite = False
    if not finite:
        return (f"plant state became non-finite in the step from t={current_time!r} s "
                f"(u={slave.u!r} m/s2); the step is discarded")
    slave._state = state
    slave._outputs = plant.outputs(state, slave._params)
    return None


def plant_saved(slave):
    return saved_state(slave, tables.PLANT, state=None if slave._state is None else list(slave._state))


def plant_restore(slave, saved):
    restore_variables(slave, tables.PLANT, saved)
    if saved["state"] is None:
        plant_start(slave)
    else:
        plant_initialise(slave, saved["state"])


# --- BacksteppingController ------------------------------------------------------

def controller_start(slave):
    slave._law = None  # (PlantParameters, ControllerGains) once initialisation ends


def _law(slave):
    return controller_setup(values(slave, tables.CONTROLLER, "parameter"))


def controller_outputs(slave):
    p, k = slave._law or _law(slave)
    # Direct feedthrough: u from the inputs as they are set now.
    state = (slave.x, slave.dx, slave.theta1, slave.dtheta1, slave.theta2, slave.dtheta2)
    return (controller.control(state, p, k),)


def controller_initialise(slave):
    slave._law = _law(slave)


def controller_saved(slave):
    return saved_state(slave, tables.CONTROLLER, initialised=slave._law is not None)


def controller_restore(slave, saved):
    restore_variables(slave, tables.CONTROLLER, saved)
    slave._law = _law(slave) if saved["initialised"] else None
