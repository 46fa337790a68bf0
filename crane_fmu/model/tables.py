"""The building blocks of the components' variable tables.

Each component lists its variables in one table (a tuple of :class:`Variable`);
the slaves register them, the build post-processes units and descriptions from
them, and the documentation's variable lists (docs/reference/variables.md) are generated from them
(``crane-fmu info --markdown``). The rows that several components share live here.
"""

import math
from collections import namedtuple

from .parameters import PlantParameters

Variable = namedtuple("Variable", "name causality variability start unit description type items")
Variable.__new__.__defaults__ = ("Real", ())

# Display units for the SI units that users prefer to read in other units.
DISPLAY_UNITS = {"rad": "deg", "rad/s": "deg/s"}
DEG_PER_RAD = 180.0 / math.pi

# SI base-unit exponents of every unit the tables use.
BASE_UNITS = {
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "m/s3": {"m": 1, "s": -3},
    "m2": {"m": 2},
    "kg": {"kg": 1},
    "kg/m3": {"kg": 1, "m": -3},
    "s": {"s": 1},
    "1/s": {"s": -1},
    "1/s2": {"s": -2},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "J": {"kg": 1, "m": 2, "s": -2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/s": {"kg": 1, "m": 1, "s": -3},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "1": {},
}


def xml_double(value):
    """``value`` as an xs:double: the shortest text that reads back exactly, ``INF`` for infinity."""
    value = float(value)
    if value != value:
        return "NaN"
    return repr(value) if abs(value) != float("inf") else ("INF" if value > 0 else "-INF")


def positions(variables, causality):
    """The positions of one causality's variables in table order, by name.

    The slaves pass a component its inputs, and take its outputs, as tuples in table
    order; code reads them by name (python-control's ``input_index`` habit), e.g.
    ``IN = positions(VARIABLES, "input")`` and ``inputs[IN.l1_now]``.
    """
    names = [v.name for v in variables if v.causality == causality]
    return namedtuple(f"{causality.capitalize()}Positions", names)(*range(len(names)))


def parameter(name, start, unit, description, type="Real"):
    return Variable(name, "parameter", "fixed", start, unit, description, type)


def enumeration(name, start, items, description):
    """A parameter of FMI type Enumeration: one of ``items`` (names), kept by name in the models, exchanged with a host
    as the item's value, its position in ``items`` plus one (``enumeration_value``); its declared type is the name
    with a capital (``shaper``: ``Shaper``). Hosts apply an Enumeration from a system file where they apply no String
    (OMSimulator 3.0)."""
    if start not in items:
        raise ValueError(f"{name}: the start value {start!r} must be one of {', '.join(items)}")
    return Variable(name, "parameter", "fixed", start, None, description, "Enumeration", tuple(items))


def declared_type(v):
    """The name of an Enumeration variable's type in modelDescription.xml: ``Shaper`` for ``shaper``."""
    return v.name[:1].upper() + v.name[1:]


def enumeration_value(v, name):
    """The value a host exchanges for the item ``name`` of the Enumeration variable ``v`` (1 for the first item);
    ValueError naming the value and the items."""
    if name not in v.items:
        raise ValueError(f"{v.name} must be one of {', '.join(v.items)}, got {name!r}")
    return v.items.index(name) + 1


def enumeration_name(v, value):
    """The item of the Enumeration variable ``v`` whose value is ``value``; ValueError naming the value and the
    values allowed."""
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= len(v.items):
        allowed = ", ".join(f"{i + 1} ({n})" for i, n in enumerate(v.items))
        raise ValueError(f"{v.name} must be one of {allowed}, got {value!r}")
    return v.items[value - 1]


def input_(name, unit, description, start=0.0):
    return Variable(name, "input", "continuous", start, unit, description)


def output(name, unit, description):
    return Variable(name, "output", "continuous", None, unit, description)


def local(name, unit, description):
    """A variable of Model Exchange only (a state that is no output, a derivative): see ``Continuous``."""
    return Variable(name, "local", "continuous", None, unit, description)


_PP = PlantParameters()  # defaults live in the dataclass

# The physical parameters of eqs (4)-(9): the plant's, and every model-based controller's model of it.
PLANT_MODEL = (
    parameter("m1", _PP.m1, "kg", "hook mass"),
    parameter("m2", _PP.m2, "kg", "payload mass"),
    parameter("l1", _PP.l1, "m", "cable length trolley to hook"),
    parameter("l2", _PP.l2, "m", "cable length hook to payload"),
    parameter("g", _PP.g, "m/s2", "gravitational acceleration"),
)
# What a component that models the whole crane declares as its model of it (Component.crane_model).
CRANE_MODEL = tuple(v.name for v in PLANT_MODEL)

# The plant state in the order of crane_fmu.model.plant, with units and descriptions.
_STATE_ROWS = {
    "x": ("m", "trolley position"),
    "dx": ("m/s", "trolley velocity"),
    "theta1": ("rad", "hook swing angle"),
    "dtheta1": ("rad/s", "hook swing rate"),
    "theta2": ("rad", "payload swing angle"),
    "dtheta2": ("rad/s", "payload swing rate"),
}
STATE = tuple(_STATE_ROWS)


def state_variables(make, prefix="", names=STATE, suffix=""):
    """Rows for the plant state's ``names``, made by ``make`` (:func:`input_` or :func:`output`).

    Each is named ``name + suffix`` and has the state's unit and ``prefix`` + its description:
    ``state_variables(output, "estimated ")`` gives ``output("x", "m", "estimated trolley position")``, ...
    """
    return tuple(make(name + suffix, _STATE_ROWS[name][0], prefix + _STATE_ROWS[name][1]) for name in names)


# What every controller takes: the measured plant state.
MEASURED_STATE = state_variables(input_, "measured ")


def controller_model(whose="controller"):
    """The :data:`PLANT_MODEL` rows as a controller's (or ``whose``) model of the plant."""
    return tuple(v._replace(description=f"{whose}'s model: " + v.description) for v in PLANT_MODEL)


def variable_table(component, markdown=False):
    """A component's variables as text (``crane-fmu info``) or as the docs' Markdown table."""
    lines = ([f"#### {component.model_identifier}", "", "| name | causality | start | unit | description |",
              "|---|---|---|---|---|"] if markdown else
             [f"{component.model_identifier}.fmu ({component.role}): {component.description}"])
    for v in component.variables:
        start = "" if v.start is None else f"{v.start:.6g}" if v.type == "Real" else v.start
        unit = v.unit or ""
        if unit in DISPLAY_UNITS:
            unit += f" (display {DISPLAY_UNITS[unit]})"
        lines.append(f"| `{v.name}` | {v.causality} | {start} | {unit} | {v.description} |" if markdown else
                     f"  {v.name:<12} {v.causality:<10} {start:>10} {unit:<22} {v.description}")
    return "\n".join(lines) + "\n"
