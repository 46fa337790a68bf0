"""Connections between instances, and the one check of them (for systems and the master alike)."""

from collections import namedtuple

from .suggest import did_you_mean, nearest

Connection = namedtuple("Connection", "source output target input")
Connection.__doc__ = "``source.output`` feeds ``target.input`` (instance and variable names)."


def connect(interfaces, connections=(), match_names=True):
    """Every connection of a system: the written-out ones, then inputs matched to outputs by name.

    Parameters
    ----------
    interfaces : dict
        ``{instance: (input names, output names)}``.
    connections : iterable of Connection
    match_names : bool
        Connect each input that no written-out connection feeds to the one
        other instance's output of the same name.

    Raises
    ------
    ValueError
        For a connection naming an unknown instance or variable, an input fed
        twice, or an input that matches outputs of several instances.
    """
    result, fed = [], set()
    for c in connections:
        for instance in (c.source, c.target):
            if instance not in interfaces:
                raise ValueError(f"connection {c.source}.{c.output} -> {c.target}.{c.input}: unknown instance "
                                 f"{instance!r}; instances: {', '.join(interfaces)}"
                                 + did_you_mean(instance, interfaces))
        if c.output not in interfaces[c.source][1]:
            raise ValueError(f"connection: {c.source}.{c.output} is not an output; outputs: "
                             + ", ".join(interfaces[c.source][1]) + did_you_mean(c.output, interfaces[c.source][1]))
        if c.input not in interfaces[c.target][0]:
            raise ValueError(f"connection: {c.target}.{c.input} is not an input; inputs: "
                             + ", ".join(interfaces[c.target][0]) + did_you_mean(c.input, interfaces[c.target][0]))
        if (c.target, c.input) in fed:
            raise ValueError(f"connection: {c.target}.{c.input} is fed twice")
        fed.add((c.target, c.input))
        result.append(Connection(*c))
    if match_names:
        for target, (inputs, _) in interfaces.items():
            for name in inputs:
                if (target, name) in fed:
                    continue
                sources = [s for s, (_, outputs) in interfaces.items() if s != target and name in outputs]
                if len(sources) > 1:
                    raise ValueError(f"input {target}.{name} matches the outputs of {', '.join(sources)}: "
                                     "connect it explicitly")
                if sources:
                    result.append(Connection(sources[0], name, target, name))
    return result


def check_both_ends(designed, interfaces, fmus, optional=None):
    """Every connection of a system's design keeps both ends in the FMUs used; else one line.

    Parameters
    ----------
    designed : iterable of Connection
        The connections of the system as designed (with its own FMUs).
    interfaces : dict
        ``{instance: (input names, output names)}`` of the FMUs used.
    fmus : dict
        ``{instance: path}`` of the FMUs used, named in the message.
    optional : dict, optional
        ``{instance: input names}`` that the FMU used may lack: a connection into one is left out.

    Raises
    ------
    ValueError
        ``"ctl: mine/Typo.fmu has no output y, which the system connects to sys.y"``.
    """
    for c in designed:
        if c.input not in interfaces[c.target][0]:
            if c.input in (optional or {}).get(c.target, ()):
                continue
            raise ValueError(f"{c.target}: {fmus[c.target]} has no input {c.input}, which the system feeds from "
                             f"{c.source}.{c.output}")
        if c.output not in interfaces[c.source][1]:
            raise ValueError(f"{c.source}: {fmus[c.source]} has no output {c.output}, which the system connects to "
                             f"{c.target}.{c.input}")


# An input meant to be left unconnected says so in its description, with what its start value then means
# (``"an external force; unconnected: 0, none"``): :func:`unfed` does not report it.
UNCONNECTED = "unconnected: "


def unfed(inputs, outputs, connections, given=()):
    """The inputs nothing feeds and no value is given for, each read as its start value through the run.

    Parameters
    ----------
    inputs : dict
        ``{instance: {input name: description}}``; an input whose description holds :data:`UNCONNECTED` is meant
        to be left unconnected and is not reported.
    outputs : dict
        ``{instance: output names}``.
    connections : iterable of Connection
        Every connection of the run (matched ones included).
    given : iterable of (instance, name)
        The inputs given a value (``--set``, a parameter set, the system's own values).

    Returns
    -------
    list of (str, str, str or None)
        ``(instance, input, nearest)``: ``nearest`` is the other instances' output most like the input's name
        (difflib), as ``instance.output``, or None where none is near.
    """
    fed = {(c.target, c.input) for c in connections} | set(given)
    found = []
    for target, names in inputs.items():
        for name, description in names.items():
            if (target, name) in fed or UNCONNECTED in (description or ""):
                continue
            others = {output: source for source, names in outputs.items() if source != target for output in names}
            near = nearest(name, others, cutoff=0.5)
            found.append((target, name, None if near is None else f"{others[near]}.{near}"))
    return found
