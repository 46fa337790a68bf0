"""A controller kind for two axes that lives only in the tests: a PD law on the trolley's x and y, each axis alone.

``test_serve.py`` registers it, builds it with the spatial crane into a system file and drives that system over
``crane-fmu serve`` with this law applied by the client.
"""

from crane_fmu.model.component import Component
from crane_fmu.model.parameters import positive
from crane_fmu.model.tables import input_, output, parameter


def law(state, k_x, k_v, x_d, y_d):
    """``(ux, uy) = (-k_x (x - x_d) - k_v dx, -k_x (y - y_d) - k_v dy)`` [m/s2]; ``state``: x, dx, y, dy."""
    x, dx, y, dy = state
    return -k_x * (x - x_d) - k_v * dx, -k_x * (y - y_d) - k_v * dy


def configure(values):
    positive("k_x", values["k_x"])
    positive("k_v", values["k_v"])
    return values["k_x"], values["k_v"], values["x_d"], values["y_d"]


COMPONENT = Component(
    "PdXyController", "controller", "PD law on the trolley's x and y (test component)",
    (parameter("k_x", 4.0, "1/s2", "position gain"), parameter("k_v", 3.0, "1/s", "velocity gain"),
     parameter("x_d", 0.0, "m", "target trolley position along x"),
     parameter("y_d", 0.0, "m", "target trolley position along y"),
     input_("x", "m", "measured trolley position along x"), input_("dx", "m/s", "measured trolley velocity along x"),
     input_("y", "m", "measured trolley position along y"), input_("dy", "m/s", "measured trolley velocity along y"),
     output("ux", "m/s2", "demanded trolley acceleration along x"),
     output("uy", "m/s2", "demanded trolley acceleration along y")),
    configure, lambda config, state, inputs: law(inputs, *config), feedthrough=True)
