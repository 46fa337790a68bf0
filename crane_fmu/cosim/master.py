"""Fixed-step co-simulation master over FMU instances of any FMI version.

As in libcosim, the wiring (:class:`Wiring`: ports, buffers, connections), the
stepping algorithm (``crane_fmu.cosim.algorithms``), and the observers
(``crane_fmu.cosim.recorder``) are separate objects, put together by
:class:`Master`. An observer has ``start(names)``, called once with the
``instance.variable`` name of every output, and ``observe(time, values)``,
called at every communication point with the values in the same order
(``values[i]`` is the value of ``names[i]``; a read-only memoryview of doubles
that the next exchange overwrites: copy what you keep). An observer that also has
``observe_rows(rows)`` takes the points in blocks instead, as the master's compiled
loop gives them: ``rows`` holds rows of ``time`` and the values, one after another.
"""

import ctypes

from . import algorithms
from .compiled_loop import CompiledLoop
from .connections import connect
from .exchange import AlgebraicLoop, Calls, exchange_calls


def communication_points(start_time, stop_time, step):
    """Number of steps ``n`` with ``start_time + n*step == stop_time``.

    Raises
    ------
    ValueError
        If ``step`` is not positive or does not divide the interval.
    """
    if not step > 0:
        raise ValueError(f"step must be > 0, got {step!r}")
    if not stop_time > start_time:
        raise ValueError(f"stop time must be > start time {start_time!r}, got {stop_time!r}")
    n = round((stop_time - start_time) / step)
    if n < 1 or abs(start_time + n * step - stop_time) > 1e-9 * max(1.0, abs(stop_time)):
        raise ValueError(
            f"step {step!r} must divide the interval {stop_time - start_time!r} into whole steps")
    return n


class _Port:
    """The preallocated arrays of one instance, its outputs (a slice of the master's buffer) and connected
    inputs, and its prebuilt hot-path calls: :attr:`read`, :attr:`write` and :attr:`step`, each
    ``(call, function, instance)``."""

    def __init__(self, instance, buffer, offset):
        self.instance, self.buffer, self.offset = instance, buffer, offset
        size = len(instance.outputs)
        self.out = (ctypes.c_double * size).from_buffer(buffer, offset * ctypes.sizeof(ctypes.c_double))
        self.read = (*instance.reader(instance.vr_array(instance.outputs), self.out), instance)
        self.step = (*instance.stepper(), instance)
        self.write = None  # set by connect() when some input is connected

    def connect(self, inputs_and_sources):
        """Prepare the inputs: read in place from the source's outputs where they lie there in order, else copied."""
        if not inputs_and_sources:
            return
        inputs_and_sources = sorted(inputs_and_sources, key=lambda link: link[2])
        names = [name for name, _, _ in inputs_and_sources]
        sources = {id(src) for _, src, _ in inputs_and_sources}
        positions = [pos for _, _, pos in inputs_and_sources]
        if len(sources) == 1 and positions == list(range(positions[0], positions[0] + len(positions))):
            src = inputs_and_sources[0][1]  # a slice of the source's outputs: no copy at all
            inp = (ctypes.c_double * len(names)).from_buffer(
                src.buffer, (src.offset + positions[0]) * ctypes.sizeof(ctypes.c_double))
            self.write = (*self.instance.writer(self.instance.vr_array(names), inp), self.instance)
            return
        inp = (ctypes.c_double * len(names))()
        set_inputs, function = self.instance.writer(self.instance.vr_array(names), inp)
        links = [(i, src.out, pos) for i, (_, src, pos) in enumerate(inputs_and_sources)]

        def copy_and_set():
            for i, out, pos in links:
                inp[i] = out[pos]
            return set_inputs()

        size = ctypes.sizeof(ctypes.c_double)  # for the compiled loop: the copies by address, then the call
        copy_and_set.copies = [(ctypes.addressof(inp) + i * size, ctypes.addressof(out) + pos * size)
                               for i, out, pos in links]
        copy_and_set.fmi_call = set_inputs
        self.write = (copy_and_set, function, self.instance)


class Wiring:
    """The instances' ports, one buffer of every output and the connections, checked once.

    Offers the algorithms prebuilt calls, each ``(call, function, instance)``: :attr:`reads`,
    :attr:`writes` and :attr:`steps` of every instance (in dependency order where there is one),
    and :meth:`propagation`; :meth:`run` and :meth:`fail` for calls that go wrong.

    Raises
    ------
    ValueError
        For a connection naming an unknown instance or variable, or an input fed twice
        (the check of :func:`~crane_fmu.cosim.connections.connect`).
    """

    def __init__(self, instances, connections):
        connections = connect({name: (inst.inputs, inst.outputs) for name, inst in instances.items()},
                              connections, match_names=False)
        self.instances, self.connections = instances, connections
        self.output_names = [f"{name}.{v}" for name, inst in instances.items() for v in inst.outputs]
        self.buffer = buffer = (ctypes.c_double * len(self.output_names))()  # every output, in output_names order
        # what observers get: the outputs as floats (values[i] is output_names[i]), read-only
        self.values = memoryview(buffer).cast("B").cast("d").toreadonly()
        self.ports, offset = {}, 0
        for name, inst in instances.items():
            self.ports[name] = _Port(inst, buffer, offset)
            offset += len(inst.outputs)
        wiring = {name: [] for name in instances}
        for c in connections:
            src = self.ports[c.source]
            wiring[c.target].append((c.input, src, src.instance.outputs.index(c.output)))
        for name, links in wiring.items():
            self.ports[name].connect(links)
        try:
            self._calls, self.loop = exchange_calls(list(instances), {name: inst.dependencies for name, inst in
                                                                     instances.items()}, connections), None
        except AlgebraicLoop as loop:  # Jacobi's exchanges step it as it is; Gauss-Seidel refuses it
            self._calls, self.loop = Calls([], list(instances)), loop
        self.order = [self.ports[name] for name in self._calls.order]
        self.reads = [p.read for p in self.order]
        self.writes = [p.write for p in self.order if p.write]
        self.steps = [p.step for p in self.order]
        # who made a call, for the error of a call that fails
        self._callers = {id(call): (instance, function) for call, function, instance in
                         self.reads + self.writes + self.steps}

    def propagation(self):
        """The calls that propagate values along the connections in dependency order, judged per variable
        (:func:`~crane_fmu.cosim.exchange.exchange_calls`): an output that reads an input of the same instant is
        read after that input is set. :class:`~crane_fmu.cosim.exchange.AlgebraicLoop` (a ValueError) around an
        algebraic loop of direct feedthrough."""
        if self.loop:
            raise self.loop
        calls = [getattr(self.ports[name], op) for op, name in self._calls.exchange]
        return [c for c in calls if c]

    def fail(self, call, status, time):
        instance, function = self._callers[id(call)]
        instance.fail(function, status, time)

    def run(self, calls, time):
        """Make the prebuilt ``calls`` (bare calls of :attr:`reads`, :attr:`writes`, ...) at ``time``; the first
        whose status is worse than warning fails the run with its instance's error."""
        for call in calls:
            if (status := call()) > 1:
                self.fail(call, status, time)


class Master:
    """Steps FMU instances at a fixed communication step, exchanging values along connections.

    Parameters
    ----------
    instances : dict
        ``{name: Instance}`` (FMI 2.0 or 3.0), already instantiated.
    connections : list of Connection
    algorithm : str or Algorithm
        A registered algorithm's name (``gauss-seidel``, ``jacobi``, ``iterative-jacobi``, or one
        registered in ``crane_fmu.cosim.algorithms.ALGORITHMS``) or an algorithm object.
    initial_exchange : bool
        With an algorithm name: see :class:`~crane_fmu.cosim.algorithms.Algorithm`.
    loop : str
        ``"auto"``: step through the compiled loop (:mod:`~crane_fmu.cosim.compiled_loop`) where it can
        run the algorithm and the observers, else through Python; ``"python"``: always through Python.
        Both give the same numbers.
    """

    def __init__(self, instances, connections, algorithm="gauss-seidel", initial_exchange=True, loop="auto"):
        if loop not in ("auto", "python"):
            raise ValueError(f"loop must be auto or python, got {loop!r}")
        if isinstance(algorithm, str):
            algorithm = algorithms.create(algorithm, initial_exchange=initial_exchange)
        self.wiring = Wiring(instances, connections)
        self.algorithm = algorithm
        algorithm.bind(self.wiring)
        self.instances, self.output_names, self.values = instances, self.wiring.output_names, self.wiring.values
        self.compiled = CompiledLoop.create(self.wiring, algorithm.plan()) if loop == "auto" else None

    def initialize(self, start_time, stop_time, parameters=None):
        """Set parameters, run initialisation mode and settle the inputs at ``start_time``.

        Parameters
        ----------
        parameters : dict, optional
            ``{instance: {variable: value}}``, set before initialisation.
        """
        for name, inst in self.instances.items():
            inst.setup(start_time, stop_time)
            for var, value in (parameters or {}).get(name, {}).items():
                inst.set(var, value)
            inst.enter_initialization()
        self.algorithm.initialize(start_time)
        for inst in self.instances.values():
            inst.exit_initialization()

    def run(self, start_time, stop_time, step, observers=(), parameters=None):
        """Initialise and step from ``start_time`` to ``stop_time``.

        Time is ``start_time + k*step`` from the integer step count ``k``.
        Each observer is started with :attr:`output_names`, then its
        ``observe(time, values)`` is called at every communication point after
        the exchange, with the outputs read there.

        Returns
        -------
        int
            The number of steps taken.
        """
        n = communication_points(start_time, stop_time, step)
        self.initialize(start_time, stop_time, parameters)
        for o in observers:
            o.start(self.output_names)
        self.advance(start_time, step, 0, n, observers)
        self.finish(stop_time, observers)
        return n

    def advance(self, start_time, step, first, last, observers=()):
        """Take the steps ``first`` to ``last - 1`` of the grid ``start_time + k*step``.

        At each communication point: exchange, observe, then step every instance.
        Observers must have been started with :attr:`output_names`.
        """
        if self.compiled and all(hasattr(o, "observe_rows") for o in observers):
            self.compiled.advance(start_time, step, first, last, observers)
        else:
            self._advance_in_python(start_time, step, first, last, observers)
        for inst in self.instances.values():
            inst.time = start_time + last * step

    def _advance_in_python(self, start_time, step, first, last, observers):
        exchange, do_step = self.algorithm.exchange, self.algorithm.step
        observe = [o.observe for o in observers]
        values = self.values
        for k in range(first, last):
            t = start_time + k * step
            exchange(t)
            for f in observe:
                f(t, values)
            do_step(t, step)

    def finish(self, stop_time, observers=()):
        """The exchange and observation at the last communication point."""
        self.algorithm.exchange(stop_time)
        for o in observers:
            o.observe(stop_time, self.values)

    def save_state(self):
        """``{instance: FMU state}`` of every instance (get-FMU-state), for :meth:`restore_state`."""
        return {name: inst.get_state() for name, inst in self.instances.items()}

    def restore_state(self, saved):
        """Roll every instance back to a :meth:`save_state` (set-FMU-state), e.g. to retry steps."""
        for name, state in saved.items():
            self.instances[name].set_state(state)

    def terminate(self):
        for inst in self.instances.values():
            inst.terminate()
