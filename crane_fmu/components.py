"""The component registry: every FMU kind the toolkit can build, simulate, sweep and score.

A component is registered once (:func:`register`); from then on
``crane-fmu build`` builds it, systems name it by its model identifier, and its
parameter rules are applied before a run. Nothing else in the toolkit names a
component.
"""

from crane_fmu.model import (
    backstepping,
    benchmark,
    disturbances,
    energy,
    estimator,
    hard_hit,
    lqr,
    lqr3d,
    mpc,
    mpc3d,
    planner,
    plant,
    plant3d,
    wind,
)
from crane_fmu.registry import Registry

_COMPONENTS = Registry("component", lambda c: c.model_identifier)
register, unregister, get, find = _COMPONENTS.register, _COMPONENTS.unregister, _COMPONENTS.get, _COMPONENTS.find


def registered(role=None):
    """Every registered component (of one role), in registration order."""
    return [c for c in _COMPONENTS.registered() if role is None or c.role == role]


def by_role(kinds):
    """``{role: instance}``: the first instance of each role, from ``{instance: model identifier}`` in the
    system's order (an instance whose component is not registered has no role)."""
    found = {}
    for name, kind in kinds.items():
        component = find(kind)
        if component is not None:
            found.setdefault(component.role, name)
    return found


def check_parameters(model_identifier, values):
    """Apply a registered component's parameter rules to its defaults overridden by ``values``.

    Components that are not registered (a user's own FMU) are left to the FMU.

    Raises
    ------
    ValueError
        ``"l1 must be > 0 and finite, got -1.0"``.
    """
    component = find(model_identifier)
    if component is not None:
        component.check(values)


for _component in (plant.COMPONENT, backstepping.COMPONENT, lqr.COMPONENT, energy.COMPONENT, hard_hit.COMPONENT,
                   mpc.COMPONENT, planner.COMPONENT,
                   disturbances.GUST, disturbances.SENSOR, disturbances.CRANE_SENSOR, wind.COMPONENT,
                   estimator.COMPONENT, plant3d.COMPONENT, lqr3d.COMPONENT, mpc3d.COMPONENT, benchmark.TRIVIAL_PLANT,
                   benchmark.TRIVIAL_CONTROLLER):
    register(_component)
