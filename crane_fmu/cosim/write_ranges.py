"""The range in which a program outside may write each writable served variable (``serve``).

A value is only as good as what it drives. An external instance's output connected to an input that the
receiving FMU limits with a parameter ``<input>_max`` (a drive: ``u`` by ``u_max``, ``ux`` by
``ux_max``) may be written within ``+-<input>_max``, the value in effect after initialisation; where that
parameter says no limit (1e60 or more), or where there is none, within the stated default of its unit
(:data:`DEFAULT_LIMITS`, else :data:`DEFAULT_LIMIT`). The ``min``/``max`` that either variable declares in its
modelDescription.xml narrow the range further. A tunable parameter keeps the range its FMU declares (none:
any finite value).
"""

import math

UNLIMITED = 1e60  # the FMUs' "no limit" (crane_fmu.model.limits)
# The stated default limit of an unlimited drive: 50 m/s2 (about 5 g), ten times and more what an industrial
# travelling or hoisting drive gives, and small enough that a step with it held stays within finite numbers.
DEFAULT_LIMITS = {"m/s2": 50.0}
DEFAULT_LIMIT = 1e6  # any other unit (SI): a force of 1 MN, a position of 1000 km


def write_ranges(master, variables, external):
    """``{instance.variable: (low, high)}`` of the writable ``variables`` (:class:`~.realtime.Served`) of
    ``master``, initialised; ``external`` is its external instance or None."""
    ranges = {}
    for v in variables:
        if not v.writable:
            continue
        instance, _, name = v.name.partition(".")
        inst = master.instances[instance]
        low, high = _declared(inst.variables[name])
        if inst is external:
            bounds = []
            for c in master.wiring.connections:
                if c.source != instance or c.output != name:
                    continue
                receiver = master.instances[c.target]
                limit = receiver.variables.get(f"{c.input}_max")
                if limit is not None and limit.causality == "parameter":
                    value = abs(float(receiver.get(limit.name)))
                    bounds.append(value if value < UNLIMITED else DEFAULT_LIMITS.get(v.unit, DEFAULT_LIMIT))
                t_low, t_high = _declared(receiver.variables[c.input])
                low, high = max(low, t_low), min(high, t_high)
            bound = min(bounds) if bounds else DEFAULT_LIMITS.get(v.unit, DEFAULT_LIMIT)
            low, high = max(low, -bound), min(high, bound)
        ranges[v.name] = (low, high)
    return ranges


def _declared(variable):
    """``(min, max)`` a modelDescription.xml declares for ``variable`` (-inf, inf where it declares none)."""
    def number(text, default):
        try:
            value = float(text)
        except (TypeError, ValueError):
            return default
        return value if math.isfinite(value) else default

    return number(getattr(variable, "min", None), -math.inf), number(getattr(variable, "max", None), math.inf)
