"""Controllers a user might write, with the mistakes the command line must catch (test components).

``PdTypo`` names its output ``acc`` instead of ``u``; ``PdRegulator`` has neither a parameter ``x_d``
nor the planner's inputs, so it can regulate but cannot be told where to move the load.
"""

from crane_fmu.model.component import Component
from crane_fmu.model.tables import MEASURED_STATE, output, parameter


def law(config, state, inputs):
    """u = -k_x x - k_v dx [m/s2]: a PD law towards x = 0."""
    k_x, k_v = config
    return (-k_x * inputs[0] - k_v * inputs[1],)


def configure(values):
    return values["k_x"], values["k_v"]


GAINS = (parameter("k_x", 4.0, "1/s2", "position gain"), parameter("k_v", 3.0, "1/s", "velocity gain"))
PD_TYPO = Component("PdTypo", "controller", "PD law whose output is misnamed (test component)",
                    GAINS + MEASURED_STATE + (output("acc", "m/s2", "demanded trolley acceleration"),),
                    configure, law, feedthrough=True)
PD_REGULATOR = Component("PdRegulator", "controller", "PD law towards x = 0, no target (test component)",
                         GAINS + MEASURED_STATE + (output("u", "m/s2", "demanded trolley acceleration"),),
                         configure, law, feedthrough=True)
