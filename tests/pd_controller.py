"""A controller kind that lives only in the tests: a PD law on the trolley position, one module plus one descriptor.

``test_registry.py`` registers it and then builds, simulates, writes, runs in
libcosim and sweeps it without any other file of the project knowing it.
"""

from crane_fmu.model.component import Component
from crane_fmu.model.parameters import positive
from crane_fmu.model.tables import MEASURED_STATE, output, parameter


def law(state, k_x, k_v, x_d):
    """u = -k_x (x - x_d) - k_v dx [m/s2]."""
    return -k_x * (state[0] - x_d) - k_v * state[1]


def configure(values):
    positive("k_x", values["k_x"])
    positive("k_v", values["k_v"])
    return values["k_x"], values["k_v"], values["x_d"]


COMPONENT = Component(
    "PdController", "controller", "PD law on the trolley position (test component)",
    (parameter("k_x", 4.0, "1/s2", "position gain"), parameter("k_v", 3.0, "1/s", "velocity gain"),
     parameter("x_d", 0.0, "m", "target trolley position")) + MEASURED_STATE
    + (output("u", "m/s2", "demanded trolley acceleration"),),
    configure, lambda config, state, inputs: (law(inputs, *config),), feedthrough=True)
