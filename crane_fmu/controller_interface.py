"""What every controller takes and gives, and what it is told: the one rule of simulate and compare.

A controller is checked against the plant it is connected to, by the plant's roles
(:class:`crane_fmu.model.component.Crane`): it takes the plant's measured state
(``crane.state``) and gives every axis's demand (the planar crane: ``u`` [m/s2]). In a
system that moves the load, a controller is told the move, axis by axis:

- one with a planner's references (``x_ref``, ``dx_ref``, ``ddx_ref`` for the axis ``x``, and
  optionally references of the other states, ``theta1_ref``, ...) gets the planner's references;
- else one with the axis's target parameter (``x_d``) gets the move's target there;
- one with neither cannot be told the move and is refused, with that reason.
"""

import math
from collections import namedtuple

Told = namedtuple("Told", "references targets")
Told.__doc__ = ("What a controller is told: the planner's reference inputs it gets (a tuple, empty when none) and "
                "the target of each axis set as its parameter, ``{x_d: 2.0}`` (empty when none).")


def tracked(crane):
    """The references a controller needs to follow a planner's move: each axis's position, velocity, acceleration."""
    return tuple(name for axis in crane.axes for name in axis.references)


def references(crane):
    """Every reference a planner gives, in order: :func:`tracked`, then one per other state (``theta1_ref``, ...)."""
    along = {name for axis in crane.axes for name in (axis.position, axis.velocity)}
    return tracked(crane) + tuple(f"{name}_ref" for name in crane.state if name not in along)


def move_needs(crane):
    """What a controller needs to be told a move: ``a parameter x_d or the inputs x_ref, dx_ref, ddx_ref``."""
    targets = ", ".join(axis.target for axis in crane.axes)
    return f"a parameter{'s' if len(crane.axes) > 1 else ''} {targets} or the inputs {', '.join(tracked(crane))}"


def misses(crane, inputs, outputs, parameters):
    """``(always, to_move)``: what the controller misses of what every system of this plant needs, and of what a
    move needs."""
    always = [n for n in crane.state if n not in inputs] + [f"output {n}" for n in crane.demands if n not in outputs]
    follows = all(n in inputs for n in tracked(crane))
    to_move = [] if follows or all(a.target in parameters for a in crane.axes) else [move_needs(crane)]
    return always, to_move


def told(name, inputs, outputs, parameters, plant, target=None):
    """What the controller ``name`` is told in a system of ``plant``; the one rule of simulate and compare.

    Parameters
    ----------
    name : str
        The controller, named in the message.
    inputs, outputs, parameters : iterable of str
        Its variables' names.
    plant : Component
        The plant it is connected to (its :attr:`~crane_fmu.model.component.Component.crane` roles).
    target : dict, optional
        Where the system moves the load, ``{axis position: value}`` [m] (infinite: somewhere a parameter cannot
        say); None in a system that does not move it (regulation).

    Returns
    -------
    Told
        The planner's references (when it has their inputs), else each axis's target as its parameter
        (when it has them); nothing in regulation.

    Raises
    ------
    ValueError
        One line: what the controller misses, and why it is needed.
    """
    crane, inputs, parameters = plant.crane, list(inputs), list(parameters)
    always, to_move = misses(crane, inputs, outputs, parameters)
    if always:
        raise ValueError(f"{name} is not a controller of {plant.model_identifier}: it misses {', '.join(always)} "
                         f"(every controller of it takes the measured state {', '.join(crane.state)} and gives "
                         f"{', '.join(crane.demands)})")
    if target is None:
        return Told((), {})
    if all(n in inputs for n in tracked(crane)):
        return Told(tuple(n for n in references(crane) if n in inputs), {})
    values = {axis.target: target[axis.position] for axis in crane.axes}
    where = ", ".join(f"{v:g} m" for v in values.values())
    if all(map(math.isfinite, values.values())):
        if not to_move:
            return Told((), values)
        raise ValueError(f"{name} cannot be told where the load goes ({where}): it misses {to_move[0]}")
    raise ValueError(f"{name} cannot be told where the load goes: it misses the inputs {', '.join(tracked(crane))}")
