# pd_sway.py: a controller of your own, one module (standard library and crane_fmu.model only: both are
# bundled into the FMU). Build it with: crane-fmu build --component pd_sway.py --out build/mine
from crane_fmu.model.component import Component
from crane_fmu.model.rules import check, positive
from crane_fmu.model.tables import MEASURED_STATE, output, parameter

RULES = positive("k_x", "k_v", "u_max")  # each > 0 and finite: one line per rule, each with its message


def configure(values):
    """The parameter values (defaults, then the system's and --set's) -> what `law` needs; a value that
    breaks a rule is refused with a ValueError naming the parameter, the rule and the value."""
    check(RULES, values)
    return values["k_x"], values["k_v"], values["k_s"], values["x_d"], values["u_max"]


def law(config, state, inputs):
    """u = -k_x (x - x_d) - k_v dx + k_s dtheta1, limited to |u| <= u_max.

    `state` is None (this controller has no state of its own); `inputs` holds the inputs' values in the
    order of the table below: x, dx, theta1, dtheta1, theta2, dtheta2 (SI units)."""
    k_x, k_v, k_s, x_d, u_max = config
    x, dx, theta1, dtheta1, theta2, dtheta2 = inputs
    u = -k_x * (x - x_d) - k_v * dx + k_s * dtheta1
    return (max(-u_max, min(u_max, u)),)  # the outputs, in the table's order


COMPONENT = Component(
    "PdSway", "controller", "PD law on the trolley position that damps the hook's swing",
    (parameter("k_x", 1.0, "1/s2", "position gain"),
     parameter("k_v", 1.5, "1/s", "velocity gain"),
     parameter("k_s", 2.0, "m/s", "gain on the hook's swing rate"),
     parameter("x_d", 0.0, "m", "target trolley position"),
     parameter("u_max", 2.0, "m/s2", "largest |u|"))
    + MEASURED_STATE  # the inputs: x, dx, theta1, dtheta1, theta2, dtheta2
    + (output("u", "m/s2", "demanded trolley acceleration"),),
    configure, law, feedthrough=True, rules=RULES)  # feedthrough: u depends on the inputs of the same instant
