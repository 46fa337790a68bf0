"""The crane's parameters, set once: ``crane.m1``, ``crane.m2``, ``crane.l1``, ``crane.l2``, ``crane.g``.

A system's value of the reserved instance name ``crane`` (``{"crane": {"l2": 0.6}}``: ``--set crane.l2=0.6``, an
SSV's ``crane.l2``, a study's ``"crane.l2"``) sets that parameter on every instance that models the crane, as an
SSP system parameter bound to its components does, unless the instance has its own value: one set in the system,
a parameter file or ``--set controller.l2=...`` overrides it, on purpose (a controller told another crane).

Which instances model the crane, and in which parameters:

- an instance of a registered component: those its component declares (``Component.crane_model``: the plant,
  the model-based controllers, the planner, the estimator; the wind its ``l1``, ``l2``), never by instance name;
- any other FMU (a user's): its parameters of those names.

A crane value that nothing set leaves each instance its own (its FMU's start value). Standard library only: the
FMUs' own variables come in as arguments.
"""

from dataclasses import replace

from crane_fmu import components

CRANE = "crane"  # the reserved instance name


def model():
    """The crane's parameters as variable rows (name, unit, ...): the model parameters of the registered plants, by
    their roles (``Component.crane.model``), each name once in registration order."""
    from crane_fmu import components

    rows = {}
    for plant in components.registered("plant"):
        if plant.crane is not None:
            rows.update({v.name: v for v in plant.variables if v.name in plant.crane.model and v.name not in rows})
    return tuple(rows.values())


def names():
    """``("m1", "m2", "l1", "l2", "g")``."""
    return tuple(v.name for v in model())


def check_reserved(system):
    """Raise ValueError (one line) if ``system`` has an instance called ``crane``."""
    if CRANE in system.instances:
        raise ValueError(f"system {system.name}: an instance may not be called {CRANE!r}: {CRANE}.NAME sets the "
                         f"crane's parameters ({', '.join(names())}) on every instance that models it; rename it")


def modelled(kinds, parameters):
    """``{instance: (crane parameter, ...)}``: what each instance models of the crane (the rule above).

    Parameters
    ----------
    kinds : dict
        ``{instance: model identifier}``.
    parameters : callable
        ``parameters(instance) -> names``: the parameters of an instance's FMU; asked only of an instance whose
        component is not registered.
    """
    result = {}
    for name, kind in kinds.items():
        component = components.find(kind)
        own = component.crane_model if component is not None else set(parameters(name))
        result[name] = tuple(n for n in names() if n in own)
    return result


def values(system):
    """``{name: value}``: the crane's values the system sets."""
    return dict(system.parameters.get(CRANE, {}))


def bound(system, models):
    """``{name: [instance, ...]}``: for each crane parameter, the instances that model it and have no value of
    their own in ``system``, in the system's order; ``models`` as :func:`modelled` gives."""
    return {name: [i for i, modelled_ in models.items()
                   if name in modelled_ and name not in system.parameters.get(i, {})] for name in names()}


def with_values(system, overrides):
    """``system.with_parameters(overrides)``, where ``overrides`` may hold crane values (``{"crane": {...}}``)."""
    overrides = dict(overrides)
    crane = overrides.pop(CRANE, {})
    unknown = [n for n in crane if n not in names()]
    if unknown:
        raise ValueError(f"{CRANE}.{unknown[0]}: the crane's parameters are {', '.join(names())}")
    system = system.with_parameters(overrides)
    if crane:
        system = replace(system, parameters={**system.parameters, CRANE: {**values(system), **crane}})
    return system


def bind_values(parameters, crane, binding):
    """``parameters`` (``{instance: {variable: value}}``) with each crane value of ``crane`` set on the instances
    ``binding`` names for it (:func:`bound`) that have no value of their own in ``parameters``."""
    result = {name: dict(v) for name, v in parameters.items()}
    for name, value in crane.items():
        for instance in binding.get(name, ()):
            if name not in parameters.get(instance, {}):
                result.setdefault(instance, {})[name] = value
    return result


def bind(system, models):
    """The system as the master runs it: each crane value set on the instances it binds (:func:`bound`), the
    name ``crane`` gone from its values."""
    check_reserved(system)
    unknown = [name for name in system.parameters if name not in system.instances and name != CRANE]
    if unknown:
        raise ValueError(f"system {system.name}: values for {unknown[0]!r}, which is no instance; instances: "
                         f"{', '.join(system.instances)} (and {CRANE}: the crane's {', '.join(names())})")
    own = {name: v for name, v in system.parameters.items() if name != CRANE}
    return replace(system, parameters=bind_values(own, values(system), bound(system, models)))


def shared(system, models, start):
    """``{name: (value, [instance, ...])}``: each crane parameter as a value of the system's own (an SSP file's,
    ``crane-fmu info``'s) and exactly the instances it binds: the system's value, or where it sets none the start
    value of the first instance it binds, and the bound instances that have that value (reading the file back
    binds the same). ``start(instance, name)`` is an instance's start value."""
    crane, result = values(system), {}
    for name, instances in bound(system, models).items():
        if instances:
            value = crane.get(name, start(instances[0], name))
            result[name] = (value, [i for i in instances if name in crane or start(i, name) == value])
    return result


def packed(system, models, start):
    """``{name: (value, [instance, ...])}``: each crane parameter as one parameter of a closed loop packed as one
    FMU (the one-FMU, the container): the system's value, or where it sets none the value of the first instance
    that models it, set on every instance that models it and has that value now (the crane's it is bound to, its
    own, or its start value: ``start(instance, name)`` gives the last two), so that a host that sets every
    parameter to its start value changes nothing."""
    crane, binding, result = values(system), bound(system, models), {}

    def now(instance, name):
        return crane[name] if name in crane and instance in binding[name] else start(instance, name)

    for name in names():
        holders = [i for i, modelled_ in models.items() if name in modelled_]
        if holders:
            value = crane.get(name, now(holders[0], name))
            result[name] = (value, [i for i in holders if now(i, name) == value])
    return result


def settable(models):
    """``{"crane": {name: (FMI type, unit)}}`` of the crane parameters some instance models (``--set`` checks)."""
    modelled_ = {n for names_ in models.values() for n in names_}
    return {CRANE: {v.name: (v.type, v.unit) for v in model() if v.name in modelled_}}
