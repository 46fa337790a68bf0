"""Two trivial components with the crane pair's 6+1 connected signals: the benchmark's framework floor.

``crane-fmu bench`` runs them through the same master as the crane pair, so the
difference between the two is what the crane's physics and law cost.
"""

from .component import Component
from .tables import MEASURED_STATE, STATE, input_, output, state_variables

PLANT_VARIABLES = (input_("u", "m/s2", "trolley acceleration"),) + state_variables(output)
CONTROLLER_VARIABLES = MEASURED_STATE + (output("u", "m/s2", "demanded trolley acceleration"),)


def _plant_update(config, state, inputs, time, step):
    # Full-precision values, so that recording them costs what real outputs cost.
    return ((time + step) / 3.0 + 1e-3 * inputs[0],) * len(STATE)


TRIVIAL_PLANT = Component(
    "TrivialPlant", "benchmark",
    "Benchmark floor: CranePlant's input and state outputs, outputs = time / 3 + u / 1000",
    PLANT_VARIABLES, lambda values: None, lambda config, state, inputs: state,
    initial_state=lambda config: (0.0,) * len(STATE), update=_plant_update)

TRIVIAL_CONTROLLER = Component(
    "TrivialController", "benchmark",
    "Benchmark floor: BacksteppingController's inputs and output, u = -x (feedthrough)",
    CONTROLLER_VARIABLES, lambda values: None, lambda config, state, inputs: (-inputs[0],), feedthrough=True,
    depends_on={"u": ("x",)})
