"""What every controller takes and gives, and what it is told: the one rule of simulate and compare.

Every controller takes the measured crane state (:data:`MEASURED`) and gives the trolley
acceleration ``u`` [m/s2]. In a system that moves the load, a controller is told the move:

- one with the planner's inputs ``x_ref``, ``dx_ref``, ``ddx_ref`` (and optionally the swing
  references) gets the planner's references;
- else one with a parameter ``x_d`` [m] gets the move's target there;
- one with neither cannot be told the move and is refused, with that reason.
"""

import math
from collections import namedtuple

MEASURED = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
REFERENCE = ("x_ref", "dx_ref", "ddx_ref", "theta1_ref", "dtheta1_ref", "theta2_ref", "dtheta2_ref")
TRACKED = REFERENCE[:3]  # the references a controller needs to follow a planner's move

Told = namedtuple("Told", "references x_d")
Told.__doc__ = ("What a controller is told: the planner's reference inputs it gets (a tuple, empty when none) and "
                "the target position set as its parameter ``x_d`` [m] (None when not set).")

MOVE_NEEDS = f"a parameter x_d or the inputs {', '.join(TRACKED)}"


def misses(inputs, outputs, parameters):
    """``(always, to_move)``: what the controller misses of what every system needs, and of what a move needs."""
    always = [n for n in MEASURED if n not in inputs] + (["output u"] if "u" not in outputs else [])
    to_move = [] if all(n in inputs for n in TRACKED) or "x_d" in parameters else [MOVE_NEEDS]
    return always, to_move


def told(name, inputs, outputs, parameters, target=None):
    """What the controller ``name`` is told in a system; the one rule of simulate and compare.

    Parameters
    ----------
    name : str
        The controller, named in the message.
    inputs, outputs, parameters : iterable of str
        Its variables' names.
    target : float, optional
        Where the system moves the load [m] (infinite: somewhere a parameter cannot say); None in a system
        that does not move it (regulation).

    Returns
    -------
    Told
        The planner's references (when it has their inputs), else ``x_d = target`` (when it has the
        parameter); nothing in regulation.

    Raises
    ------
    ValueError
        One line: what the controller misses, and why it is needed.
    """
    inputs, parameters = list(inputs), list(parameters)
    always, to_move = misses(inputs, outputs, parameters)
    if always:
        raise ValueError(f"{name} is not a crane controller: it misses {', '.join(always)} (every controller takes "
                         f"the measured state {', '.join(MEASURED)} and gives u)")
    if target is None:
        return Told((), None)
    if all(n in inputs for n in TRACKED):
        return Told(tuple(n for n in REFERENCE if n in inputs), None)
    where = f" ({target:g} m)" if math.isfinite(target) else ""
    if "x_d" in parameters and where:
        return Told((), target)
    raise ValueError(f"{name} cannot be told where the load goes{where}: it misses "
                     + (to_move[0] if where else f"the inputs {', '.join(TRACKED)}"))
