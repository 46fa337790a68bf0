"""The order of one exchange, and algebraic loops, judged per variable.

An output *depends* on an input of its instance when it reads that input at the same instant (the
ModelStructure's per-output dependencies). An algebraic loop exists only where a chain of
connections and such dependencies, output -> input -> output -> ..., closes on itself: an instance
with direct feedthrough in some outputs only (a model whose acceleration output reads its force input
and whose position outputs read no input) closes no loop with a feedthrough instance that reads only
its positions and sets its force.

The exchange is made of whole-instance calls: ``("read", instance)`` gets every output,
``("write", instance)`` sets every connected input. An instance with *late* outputs (depending on a
connected input) is written, then read, once every source of its inputs is read; the others are read
first and written at the end. An instance with late outputs whose other, *early*, outputs are connected
is read twice: once first (its early outputs for whoever reads them), once after its write.
"""

from collections import namedtuple

Calls = namedtuple("Calls", "exchange order")
Calls.__doc__ = """``exchange``: ``[("read" | "write", instance)]`` in Gauss-Seidel order; ``order``: the instances
in the order they are first read (the order they step in)."""


class AlgebraicLoop(ValueError):
    """No exchange order exists: a loop of direct feedthrough (``path``: ``instance.variable`` along it), or an
    instance whose inputs would have to be set in two calls."""

    def __init__(self, instances, path=None, detail=None):
        self.instances, self.path = sorted(instances), path
        text = "algebraic loop through direct-feedthrough instances: " + ", ".join(self.instances)
        if path:
            text += " (" + " -> ".join(path) + ")"
        super().__init__(text + (f"; {detail}" if detail else ""))


def find_loop(dependencies, connections):
    """The first loop of direct feedthrough, as ``["a.o", "b.i", "b.o", "a.i", "a.o"]``, or None.

    Parameters
    ----------
    dependencies : dict
        ``{instance: {output: (input, ...)}}``: the inputs each output reads at the same instant.
    connections : iterable of Connection
    """
    after = {}  # the variables each variable's value flows into at the same instant
    for c in connections:
        after.setdefault((c.source, c.output), []).append((c.target, c.input))
    for instance, outputs in dependencies.items():
        for output, inputs in outputs.items():
            for i in inputs:
                after.setdefault((instance, i), []).append((instance, output))
    done, path, on_path = set(), [], set()

    def visit(node):  # depth first; a node met again on the current path closes a loop
        if node in on_path:
            return path[path.index(node):] + [node]
        if node in done:
            return None
        path.append(node)
        on_path.add(node)
        for following in after.get(node, ()):
            if loop := visit(following):
                return loop
        path.pop()
        on_path.discard(node)
        done.add(node)
        return None

    for start in list(after):
        if loop := visit(start):
            return [f"{instance}.{variable}" for instance, variable in loop]
    return None


def exchange_calls(names, dependencies, connections):
    """The :class:`Calls` of one Gauss-Seidel exchange; :class:`AlgebraicLoop` where none exists.

    Parameters
    ----------
    names : list of str
        The instances, in the order ties keep.
    dependencies : dict
        ``{instance: {output: (input, ...)}}``.
    connections : list of Connection
    """
    loop = find_loop(dependencies, connections)
    if loop:
        raise AlgebraicLoop({v.rsplit(".", 1)[0] for v in loop}, loop)
    connected = {name: {c.input for c in connections if c.target == name} for name in names}
    late = {name: {o for o, read in dependencies[name].items() if connected[name] & set(read)} for name in names}
    read_first = {name for name in names if late[name] and any(
        c.source == name and c.output not in late[name] for c in connections)}
    # a node is an instance's read first (name, True), or its place in the order (name, False): its write and read
    # where it has late outputs, else its one read; a late instance's place waits for its inputs' sources

    def source(c):
        return (c.source, c.source in read_first and c.output not in late[c.source])

    waits = {(name, True): set() for name in read_first}
    for name in names:
        waits[(name, False)] = {source(c) for c in connections if c.target == name} if late[name] else set()
    waits = dict(sorted(waits.items(), key=lambda item: (names.index(item[0][0]), not item[0][1])))
    nodes = []
    while waits:
        ready = [node for node, sources in waits.items() if not sources - set(nodes)]
        if not ready:
            stuck = sorted({name for name, _ in waits})
            raise AlgebraicLoop(stuck, detail="no loop of variables, but an exchange of whole-instance calls "
                                "would set some inputs of one instance before others' sources are read")
        for node in ready:
            nodes.append(node)
            del waits[node]
    exchange = []
    for name, first in nodes:
        exchange += [("read", name)] if first or not late[name] else [("write", name), ("read", name)]
    order = list(dict.fromkeys(name for name, _ in nodes))  # as first read
    return Calls(exchange + [("write", name) for name in order if not late[name]], order)
