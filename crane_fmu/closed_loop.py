"""What a host sees of a closed loop packed as one FMU: chosen here for fmpy's container (``container.py``) and for
our native one-FMU (``build_scripts/one_fmu.py``) alike.

The plant's outputs and the controller's demands (``u``); as parameters the crane's ``m1``, ``m2``, ``l1``, ``l2``,
``g`` (``crane_parameters.packed``: each set on the instances that model the crane, by the rule of ``crane.l2``,
and agree on its value with the system's crane value or the first of them: hoist-transport's planner, designed for
l1 = 1.5 m, keeps its own l1, so that a host that sets every parameter to its start value gets the system's own run),
each axis's target ``x_d`` (to the axis's planner if there is one, :func:`axis_planners`, and to a controller
told the move's target by its ``x_d``; else to the controller) and the plant's start swing
``theta1_0``, whose start values are the system's; as inputs the plant's inputs that nothing inside feeds (``F1``,
``F2``, ``hoist``); a system without a controller (an open loop) shows each axis's planned demand as the
plant's demand (``ux``). The plant, controller, planner and estimator are the first instances of those roles (their
components' ``role``), never found by name, and what the plant's roles name (``Component.crane``: its axes,
demands and start swing) is read from them. Its model structure (which own inputs each own output reads at once)
follows the instances' along the connections.
"""

from collections import namedtuple

from crane_fmu import components, crane_parameters

Exposed = namedtuple("Exposed", "name causality targets start")
Exposed.__doc__ = """One variable of the packed FMU: ``targets`` is ``[(instance, variable)]``, the first of which
it takes its unit and description from; ``start`` is the system's value (None for an output)."""


def interface(system, kinds, variables, fed):
    """The packed FMU's variables, in order: a list of :class:`Exposed`.

    Parameters
    ----------
    system : System
        Its parameter values are the start values.
    kinds : dict
        ``{instance: model identifier}``.
    variables : dict
        ``{instance: {variable: (causality, start)}}``.
    fed : set
        ``{(instance, input)}`` of the inputs a connection inside feeds.

    Raises
    ------
    ValueError
        The system has no plant.
    """
    by_role = components.by_role(kinds)
    if "plant" not in by_role:
        raise ValueError(f"system {system.name} has no instance whose component is a plant to expose")
    plant, exposed = by_role["plant"], []
    crane = components.get(kinds[plant]).crane
    if "controller" not in by_role:  # a user's FMU in the controller's place: the one that gives the demands
        by_role["controller"] = next((i for i in kinds if components.find(kinds[i]) is None and all(
            variables[i].get(d, ("",))[0] == "output" for d in crane.demands)), None)

    def start(instance, name):
        return system.parameters.get(instance, {}).get(name, variables[instance][name][1])

    models = crane_parameters.modelled(kinds, lambda i: [n for n, (c, _) in variables[i].items() if c == "parameter"])
    for name, (value, holders) in crane_parameters.packed(system, models, start).items():
        exposed.append(Exposed(name, "parameter", [(i, name) for i in holders], value))
    planners, controller = axis_planners(crane, kinds, system.connections), by_role.get("controller")
    for axis in crane.axes:
        target = planners.get(axis.position, controller)
        held = planner_target(axis, variables[target]) if target in planners.values() else axis.target
        if target is not None and held in variables[target]:
            # a controller told the move's target (a user's, without the planner's inputs: systems.tell_controllers
            # gives it the planner's) gets it too; one with a value of its own keeps it (an SSP file holds every
            # value: the LQR's x_d = 0 beside its planner's references)
            told = [controller] if controller not in (None, target) and _same(
                system.parameters.get(controller, {}).get(axis.target), start(target, held)) else []
            exposed.append(Exposed(axis.target, "parameter", [(target, held)] + [(c, axis.target) for c in told],
                                   start(target, held)))
    if crane.start_swing:
        exposed.append(Exposed(crane.start_swing, "parameter", [(plant, crane.start_swing)],
                               start(plant, crane.start_swing)))
    for name, (causality, _) in variables[plant].items():
        if causality == "input" and (plant, name) not in fed:
            exposed.append(Exposed(name, "input", [(plant, name)], start(plant, name)))
    for name, (causality, _) in variables[plant].items():
        if causality == "output":
            exposed.append(Exposed(name, "output", [(plant, name)], None))
    controller = by_role.get("controller")
    feeds = {c.input: (c.source, c.output) for c in system.connections if c.target == plant}
    for axis in crane.axes:
        if controller and axis.demand in variables[controller]:
            exposed.append(Exposed(axis.demand, "output", [(controller, axis.demand)], None))
        elif axis.demand in feeds and feeds[axis.demand][0] == planners.get(axis.position):  # the planner's
            exposed.append(Exposed(axis.demand, "output", [feeds[axis.demand]], None))
    return exposed


def _same(value, start):
    """Whether a system's ``value`` (None: none given) is ``start`` (a number, or an FMU's start value as text)."""
    try:
        return value is not None and float(value) == float(start)
    except (TypeError, ValueError):
        return False


ONE_AXIS_TARGET = "x_d"  # a planner of one axis (TrajectoryPlanner) plans along its own x, whichever axis it drives


def planner_target(axis, names):
    """The parameter of a planner (its variables' ``names``) that holds the target along ``axis``: the axis's own
    (``y_d``) where the planner has it, else a one-axis planner's :data:`ONE_AXIS_TARGET`."""
    return axis.target if axis.target in names else ONE_AXIS_TARGET


def axis_planners(crane, kinds, connections):
    """``{axis position: planner instance}``: per axis of the plant's ``crane``, the planner whose output feeds
    that axis's demand (an open loop of a planner per axis: ``planner_y.ddx_ref`` to ``plant.uy``) or the
    controller's position reference of the axis (``planner_y.x_ref`` to ``controller.y_ref``); where none
    does, the system's first planner that does not plan the cable's length plans the first axis (it feeds a
    controller the references by name).

    ``kinds``: ``{instance: model identifier}`` in the system's order; ``connections``: the written-out ones.
    """
    by_role = components.by_role(kinds)
    planners = [name for name, kind in kinds.items() if getattr(components.find(kind), "role", None) == "planner"]
    plant, controller = by_role.get("plant"), by_role.get("controller")
    found = {}
    for axis in crane.axes:
        fed = {(plant, axis.demand), (controller, axis.references[0])}
        source = next((c.source for c in connections if (c.target, c.input) in fed), None)
        if source in planners:
            found[axis.position] = source
    hoisting = {c.source for c in connections if (c.target, c.input) == (plant, crane.hoist)}
    free = [name for name in planners if name not in hoisting]
    if not found and free:
        found[crane.axes[0].position] = free[0]
    return found


def system_dependencies(dependencies, connections, outputs, inputs):
    """``{own output: (own input, ...)}`` of a system packed as one FMU (a one-FMU, a container).

    An own output reads an own input at the same instant when a chain of direct feedthrough, along the
    connections, leads from an instance input that the own input sets to the instance output it shows.

    Parameters
    ----------
    dependencies : dict
        ``{instance: {output: (input, ...)}}``: the inputs each instance's outputs read at the same instant.
    connections : iterable of Connection
    outputs : dict
        ``{own output: (instance, output)}``: where each own output comes from.
    inputs : dict
        ``{own input: [(instance, input)]}``: what each own input sets, in the own inputs' order.
    """
    fed = {(c.target, c.input): (c.source, c.output) for c in connections}
    result = {}
    for name, source in outputs.items():
        read, todo, seen = set(), [source], set()
        while todo:
            instance, output = todo.pop()
            if (instance, output) in seen:
                continue
            seen.add((instance, output))
            for variable in dependencies[instance][output]:
                read.add((instance, variable))
                if (instance, variable) in fed:
                    todo.append(fed[(instance, variable)])
        result[name] = tuple(own for own, targets in inputs.items() if read.intersection(targets))
    return result
