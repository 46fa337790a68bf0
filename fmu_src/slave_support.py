"""Registers a variable table (crane_fmu.model.tables) on a pythonfmu (FMI 2.0) slave."""

from pythonfmu import Fmi2Causality, Fmi2Initial, Fmi2Variability, Real, String

from fmu_src.crane_logic import checked_input


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
                common["setter"] = lambda value, name=v.name: setattr(slave, name, checked_input(name, value))
            slave.register_variable(kind(v.name, start=v.start, **common))
