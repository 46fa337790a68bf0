"""Variable tables of the two FMUs: the single source of their interfaces.

The pythonfmu slaves register their variables from these tables, the build
post-processes units and descriptions from them, and the README's variable
lists are generated from them (``crane-fmu info --markdown``).
"""

import math
from collections import namedtuple

from .parameters import ControllerGains, PlantParameters

Variable = namedtuple("Variable", "name causality variability start unit description type")
Variable.__new__.__defaults__ = ("Real",)

# Display units for the SI units that users prefer to read in other units.
DISPLAY_UNITS = {"rad": "deg", "rad/s": "deg/s"}
DEG_PER_RAD = 180.0 / math.pi

# SI base-unit exponents of every unit the tables use.
BASE_UNITS = {
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "kg": {"kg": 1},
    "s": {"s": 1},
    "1/s": {"s": -1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "J": {"kg": 1, "m": 2, "s": -2},
    "1": {},
}

_P, _IN, _OUT = "parameter", "input", "output"
_FIXED, _CONT = "fixed", "continuous"
_PP, _KK = PlantParameters(), ControllerGains()  # defaults live in the dataclasses

_PLANT_MODEL = [
    Variable("m1", _P, _FIXED, _PP.m1, "kg", "hook mass"),
    Variable("m2", _P, _FIXED, _PP.m2, "kg", "payload mass"),
    Variable("l1", _P, _FIXED, _PP.l1, "m", "cable length trolley to hook"),
    Variable("l2", _P, _FIXED, _PP.l2, "m", "cable length hook to payload"),
    Variable("g", _P, _FIXED, _PP.g, "m/s2", "gravitational acceleration"),
]

PLANT = _PLANT_MODEL + [
    Variable("x0", _P, _FIXED, 0.0, "m", "initial trolley position"),
    Variable("dx0", _P, _FIXED, 0.0, "m/s", "initial trolley velocity"),
    Variable("theta1_0", _P, _FIXED, math.pi / 18, "rad", "initial hook swing angle"),
    Variable("dtheta1_0", _P, _FIXED, 0.0, "rad/s", "initial hook swing rate"),
    Variable("theta2_0", _P, _FIXED, 0.0, "rad", "initial payload swing angle"),
    Variable("dtheta2_0", _P, _FIXED, 0.0, "rad/s", "initial payload swing rate"),
    Variable("max_substep", _P, _FIXED, 1e-3, "s", "longest RK4 sub-step inside doStep"),
    Variable("u", _IN, _CONT, 0.0, "m/s2", "trolley acceleration (held over each step)"),
    Variable("x", _OUT, _CONT, None, "m", "trolley position"),
    Variable("dx", _OUT, _CONT, None, "m/s", "trolley velocity"),
    Variable("theta1", _OUT, _CONT, None, "rad", "hook swing angle from vertical"),
    Variable("dtheta1", _OUT, _CONT, None, "rad/s", "hook swing rate"),
    Variable("theta2", _OUT, _CONT, None, "rad", "payload swing angle from vertical"),
    Variable("dtheta2", _OUT, _CONT, None, "rad/s", "payload swing rate"),
    Variable("x1", _OUT, _CONT, None, "m", "hook horizontal position, eq (4)"),
    Variable("y1", _OUT, _CONT, None, "m", "hook vertical position (up positive), eq (4)"),
    Variable("x2", _OUT, _CONT, None, "m", "payload horizontal position, eq (5)"),
    Variable("y2", _OUT, _CONT, None, "m", "payload vertical position (up positive), eq (5)"),
    Variable("energy", _OUT, _CONT, None, "J", "kinetic + potential energy of hook and payload, eqs (6)-(7)"),
]

# The plant state in the order of crane_fmu.model.plant.
STATE = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")

CONTROLLER = [v._replace(description="controller's model: " + v.description) for v in _PLANT_MODEL] + [
    Variable("K1_x", _P, _FIXED, _KK.K1_x, "1/s", "K1 gain on trolley position error, eq (18)"),
    Variable("K1_theta1", _P, _FIXED, _KK.K1_theta1, "1/s", "K1 gain on hook angle error, eq (18)"),
    Variable("K1_theta2", _P, _FIXED, _KK.K1_theta2, "1/s", "K1 gain on payload angle error, eq (18)"),
    Variable("K2_x", _P, _FIXED, _KK.K2_x, "1/s", "K2 gain on trolley delta2, eq (19)"),
    Variable("K2_theta1", _P, _FIXED, _KK.K2_theta1, "1/s", "K2 gain on hook delta2, eq (19)"),
    Variable("K2_theta2", _P, _FIXED, _KK.K2_theta2, "1/s", "K2 gain on payload delta2, eq (19)"),
    Variable("x_d", _P, _FIXED, _KK.x_d, "m", "target trolley position"),
    Variable("theta1_d", _P, _FIXED, _KK.theta1_d, "rad", "target hook angle"),
    Variable("theta2_d", _P, _FIXED, _KK.theta2_d, "rad", "target payload angle"),
    Variable("w_x", _P, _FIXED, _KK.w_x, "1", "least-squares weight of the trolley row of eq (20)"),
    Variable("w_theta1", _P, _FIXED, _KK.w_theta1, "1", "least-squares weight of the hook row of eq (20)"),
    Variable("w_theta2", _P, _FIXED, _KK.w_theta2, "1", "least-squares weight of the payload row of eq (20)"),
    Variable("b3_form", _P, _FIXED, _KK.b3_form, None,
             "b3 of eq (14): 'derived' (corrected sign) or 'printed' (as in the paper)", "String"),
] + [
    Variable(name, _IN, _CONT, 0.0, unit, "measured " + desc)
    for name, unit, desc in (
        ("x", "m", "trolley position"),
        ("dx", "m/s", "trolley velocity"),
        ("theta1", "rad", "hook swing angle"),
        ("dtheta1", "rad/s", "hook swing rate"),
        ("theta2", "rad", "payload swing angle"),
        ("dtheta2", "rad/s", "payload swing rate"),
    )
] + [
    Variable("u", _OUT, _CONT, None, "m/s2", "demanded trolley acceleration, eq (21)"),
]

TABLES = {"CranePlant": PLANT, "BacksteppingController": CONTROLLER}


def defaults(table, causality=_P):
    """``{name: start}`` of the table's variables of one causality."""
    return {v.name: v.start for v in table if v.causality == causality}

# Two trivial FMUs with the crane pair's 6+1 connected signals, for the
# benchmark's framework floor (crane-fmu bench).
TRIVIAL_PLANT = [v for v in PLANT if v.name == "u" or v.name in STATE]
TRIVIAL_CONTROLLER = [v for v in CONTROLLER if v.causality != "parameter"]
