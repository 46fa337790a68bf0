"""The component registry: every FMU kind the toolkit can build, simulate, sweep and score.

A component is registered once (:func:`register`); from then on
``crane-fmu build`` builds it, systems name it by its model identifier, and its
parameter rules are applied before a run. Nothing else in the toolkit names a
component.
"""

from crane_fmu.model import backstepping, benchmark, disturbances, energy, lqr, planner, plant

_REGISTRY = {}


def register(component):
    """Add ``component`` (a ``crane_fmu.model.component.Component``); return it."""
    known = _REGISTRY.get(component.model_identifier)
    if known is not None and known is not component:
        raise ValueError(f"a component {component.model_identifier!r} is already registered")
    _REGISTRY[component.model_identifier] = component
    return component


def get(model_identifier):
    """The registered component, or ValueError listing the known ones."""
    try:
        return _REGISTRY[model_identifier]
    except KeyError:
        raise ValueError(f"no component {model_identifier!r}; components: {', '.join(_REGISTRY)}") from None


def find(model_identifier):
    """The registered component, or None."""
    return _REGISTRY.get(model_identifier)


def all(role=None):
    """Every registered component (of one role), in registration order."""
    return [c for c in _REGISTRY.values() if role is None or c.role == role]


def check_parameters(model_identifier, values):
    """Apply a registered component's parameter rules to its defaults overridden by ``values``.

    Components that are not registered (a user's own FMU) are left to the FMU.

    Raises
    ------
    ValueError
        ``"l1 must be > 0 and finite, got -1.0"``.
    """
    component = _REGISTRY.get(model_identifier)
    if component is not None:
        component.check(values)


for _component in (plant.COMPONENT, backstepping.COMPONENT, lqr.COMPONENT, energy.COMPONENT, planner.COMPONENT,
                   disturbances.GUST, disturbances.SENSOR, benchmark.TRIVIAL_PLANT, benchmark.TRIVIAL_CONTROLLER):
    register(_component)
