"""Registers a variable table (crane_fmu.model.tables) on a pythonfmu3 (FMI 3.0) slave, with its units."""

from pythonfmu3 import Float64, Fmi3Causality, Fmi3Initial, Fmi3Variability, String
from pythonfmu3.unit import Unit

from crane_fmu.model.tables import BASE_UNITS
from fmu_src.crane_logic import checked_input


def register_table3(slave, table, outputs):
    """Like the FMI 2.0 ``register_table``, plus the independent variable ``time``
    and every unit declared natively (UnitDefinitions, ``unit`` on each Float64)."""
    slave.time = 0.0
    slave.register_variable(Float64("time", causality=Fmi3Causality.independent,
                                    variability=Fmi3Variability.continuous, description="simulation time"))
    units = sorted({v.unit for v in table if v.type == "Real"})
    slave.register_units([Unit(name, **BASE_UNITS[name]) for name in units])
    position = 0
    for v in table:
        common = dict(causality=Fmi3Causality[v.causality], variability=Fmi3Variability[v.variability],
                      description=v.description)
        if v.type == "Real":
            common["unit"] = v.unit
        kind = String if v.type == "String" else Float64
        if v.causality == "output":
            slave.register_variable(kind(v.name, initial=Fmi3Initial.calculated,
                                         getter=lambda i=position: outputs()[i], **common))
            position += 1
        else:
            setattr(slave, v.name, v.start)
            if v.causality == "input" and kind is Float64:
                common["setter"] = lambda value, name=v.name: setattr(slave, name, checked_input(name, value))
            slave.register_variable(kind(v.name, start=v.start, **common))
