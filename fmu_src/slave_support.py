"""Registers a variable table (crane_fmu.model.tables) on a pythonfmu slave."""

import math

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Variability, Real, String


def register_table(slave, table, outputs):
    """Register every variable of ``table`` on ``slave``.

    Parameters and inputs become attributes of the slave holding their start
    value; a Real input refuses a value that is not finite (the FMI call
    returns an error naming the input and the value). ``outputs()`` returns
    the values of all outputs in table order, so a slave computes them from its
    own state; they are ``initial=calculated`` (listed as InitialUnknowns by
    the build's post-processing).
    """
    position = 0
    for v in table:
        kind = String if v.type == "String" else Real
        common = dict(causality=Fmi2Causality[v.causality],
                      variability=Fmi2Variability[v.variability],
                      description=v.description)
        if v.causality == "output":
            slave.register_variable(kind(v.name, initial=Fmi2Initial.calculated,
                                         getter=lambda i=position: outputs()[i], **common))
            position += 1
        else:
            setattr(slave, v.name, v.start)
            if v.causality == "input" and kind is Real:
                common["setter"] = lambda value, name=v.name: _set_finite(slave, name, value)
            slave.register_variable(kind(v.name, start=v.start, **common))


def _set_finite(slave, name, value):
    if not math.isfinite(value):
        raise ValueError(f"input {name} must be finite, got {value!r}")
    setattr(slave, name, value)


def saved_state(slave, table, **internal):
    """The slave's full state for fmi2GetFMUstate: every parameter and input, plus ``internal``.

    JSON-able (pythonfmu serialises it with json), and exact: floats survive
    the JSON round trip bit for bit.
    """
    return {"variables": {v.name: getattr(slave, v.name) for v in table if v.causality != "output"}, **internal}


def restore_variables(slave, table, saved):
    """Set every parameter and input back from :func:`saved_state`."""
    for v in table:
        if v.causality != "output":
            setattr(slave, v.name, saved["variables"][v.name])


def values(slave, table, causality):
    """``{name: value}`` of the slave's variables of one causality."""
    return {v.name: getattr(slave, v.name) for v in table if v.causality == causality}
