"""Master algorithms: how the instances of a :class:`~crane_fmu.cosim.master.Wiring` exchange and step.

libcosim's idiom: the wiring (ports, buffers, connections) is one thing, the stepping
algorithm another. An algorithm is bound once to a wiring, then called at every
communication point ``t``: :meth:`Algorithm.exchange` brings every connected input up to
date, the observers see the outputs, and :meth:`Algorithm.step` steps every instance and
returns the step it took. Algorithms are registered by name (:data:`ALGORITHMS`, the
command line's ``--algorithm`` choices); a new one is a subclass and :func:`register`.
"""

from .instance import FmiError


class Algorithm:
    """The interface of a master algorithm; subclasses set :attr:`name` and the exchange.

    Parameters
    ----------
    initial_exchange : bool
        Settle the inputs at the start time by propagating the initial outputs
        along the connections in dependency order (default). Without it the first
        step runs with the inputs' start values, as fmpy's container FMU does.
    """

    name = None

    def __init__(self, initial_exchange=True):
        self.initial_exchange = initial_exchange
        self.wiring = None

    def bind(self, wiring):
        """Prepare the calls of the exchange on ``wiring``; ValueError if this algorithm cannot step it."""
        self.wiring = wiring
        self._steps = [call for call, _, _ in wiring.steps]

    def initialize(self, time):
        """In initialisation mode at the start ``time``: the initial exchange, if any."""
        if self.initial_exchange:
            self.wiring.run([call for call, _, _ in self.wiring.propagation()], time)  # consistent inputs at t0

    def exchange(self, time):
        raise NotImplementedError

    def plan(self):
        """``(exchange, steps)``: the prebuilt ``(call, function, instance)`` triples one communication point
        makes, always the same, for the compiled loop (:mod:`crane_fmu.cosim.compiled_loop`); None when the
        exchange is not a fixed list of calls (the Python loop then steps this algorithm)."""
        return None

    def step(self, time, step):
        """Step every instance from ``time`` by ``step``; returns the step taken."""
        fail = self.wiring.fail
        for do_step in self._steps:
            if (status := do_step(time, step)) > 1:  # worse than warning
                fail(do_step, status, time)
        return step


class GaussSeidel(Algorithm):
    """Values propagate along the connections in dependency order before every step: a direct-feedthrough
    output sees the inputs of the same instant. Refuses an algebraic loop of feedthrough instances."""

    name = "gauss-seidel"

    def bind(self, wiring):
        super().bind(wiring)
        self._plan = wiring.propagation()
        self._exchange = [call for call, _, _ in self._plan]

    def exchange(self, time):
        self.wiring.run(self._exchange, time)

    def plan(self):
        return self._plan, self.wiring.steps


class Jacobi(GaussSeidel):
    """Every output is read, then every input set, then every instance steps: a feedthrough path lags
    one communication step. Loops of feedthrough instances are stepped as they are."""

    name = "jacobi"

    def bind(self, wiring):
        Algorithm.bind(self, wiring)
        self._plan = wiring.reads + wiring.writes
        self._exchange = [call for call, _, _ in self._plan]


class IterativeJacobi(Algorithm):
    """The Jacobi exchange repeated at each communication point until the outputs stop changing: the
    inputs then satisfy every connection at the same instant (a fixed point), also around an algebraic
    loop of feedthrough instances, which Gauss-Seidel refuses. Where there is no loop the fixed point
    is Gauss-Seidel's exchange, reached after one more exchange than the longest feedthrough chain.

    Parameters
    ----------
    tolerance : float
        Converged when no output changed by more than ``tolerance * (1 + |value|)``
        between two exchanges (default 0: exactly).
    max_exchanges : int
        More exchanges without converging fail the run with an :class:`FmiError`
        of the instance ``master``.
    """

    name = "iterative-jacobi"

    def __init__(self, initial_exchange=True, tolerance=0.0, max_exchanges=100):
        super().__init__(initial_exchange)
        self.tolerance, self.max_exchanges = tolerance, max_exchanges

    def bind(self, wiring):
        super().bind(wiring)
        self._reads = [call for call, _, _ in wiring.reads]
        self._writes = [call for call, _, _ in wiring.writes]

    def initialize(self, time):
        if self.initial_exchange:  # its own exchange: propagation cannot settle a loop
            self.exchange(time)

    def exchange(self, time):
        wiring, tolerance = self.wiring, self.tolerance
        previous = None
        for _ in range(self.max_exchanges):
            wiring.run(self._reads, time)
            now = wiring.values.tolist()
            if previous is not None and all(abs(a - b) <= tolerance * (1.0 + abs(a)) for a, b in zip(now, previous)):
                return
            wiring.run(self._writes, time)
            previous = now
        changes = [abs(a - b) for a, b in zip(now, previous)]
        worst = max(range(len(changes)), key=changes.__getitem__)
        raise FmiError("master", f"{self.name} exchange", time, "error", [
            f"no fixed point within {self.max_exchanges} exchanges: {wiring.output_names[worst]} still changed "
            f"by {changes[worst]!r}"])


ALGORITHMS = {}


def register(algorithm):
    """Make an :class:`Algorithm` subclass selectable by its name; returns it (a class decorator)."""
    ALGORITHMS[algorithm.name] = algorithm
    return algorithm


for _algorithm in (GaussSeidel, Jacobi, IterativeJacobi):
    register(_algorithm)


def create(name, **options):
    """A new algorithm object of the registered ``name``; ValueError naming the choices."""
    if name not in ALGORITHMS:
        raise ValueError(f"master algorithm must be one of {', '.join(ALGORITHMS)}, got {name!r}")
    return ALGORITHMS[name](**options)
