"""Fixed-step co-simulation master over FMU instances of any FMI version.

As in libcosim, the stepping algorithm (:class:`Master`), the connections
(:class:`Connection`) and the observers (``crane_fmu.cosim.recorder``) are
separate objects. An observer has ``start(names)``, called once with the
``instance.variable`` name of every output, and ``observe(time, values)``,
called at every communication point with the values in the same order
(``values[i]`` is the value of ``names[i]``; a read-only memoryview of doubles
that the next exchange overwrites: copy what you keep).
"""

import ctypes
from collections import namedtuple

MODES = ("gauss-seidel", "jacobi")

Connection = namedtuple("Connection", "source output target input")
Connection.__doc__ = "``source.output`` feeds ``target.input`` (instance and variable names)."


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

        self.write = (copy_and_set, function, self.instance)


class Master:
    """Steps FMU instances at a fixed communication step, exchanging values along connections.

    Parameters
    ----------
    instances : dict
        ``{name: Instance}`` (FMI 2.0 or 3.0), already instantiated.
    connections : list of Connection
    mode : {"gauss-seidel", "jacobi"}
        ``gauss-seidel``: before every step, values propagate along the
        connections in dependency order, so a direct-feedthrough output sees
        the inputs of the same instant. ``jacobi``: all outputs are read, then
        all inputs set, then every instance steps; a feedthrough path lags one
        step.
    initial_exchange : bool
        Settle the inputs at the start time by propagating the initial outputs
        along the connections (default). Without it the first step runs with
        the inputs' start values, as fmpy's container FMU does.
    """

    def __init__(self, instances, connections, mode="gauss-seidel", initial_exchange=True):
        if mode not in MODES:
            raise ValueError(f"master mode must be one of {', '.join(MODES)}, got {mode!r}")
        self.instances, self.mode, self.initial_exchange = instances, mode, initial_exchange
        self.output_names = [f"{name}.{v}" for name, inst in instances.items() for v in inst.outputs]
        buffer = (ctypes.c_double * len(self.output_names))()  # every output, in output_names order
        # what observers get: the outputs as floats (values[i] is output_names[i]), read-only
        self.values = memoryview(buffer).cast("B").cast("d").toreadonly()
        self.ports, offset = {}, 0
        for name, inst in instances.items():
            self.ports[name] = _Port(inst, buffer, offset)
            offset += len(inst.outputs)
        wiring = {name: [] for name in instances}
        for c in connections:
            for inst in (c.source, c.target):
                if inst not in instances:
                    raise KeyError(f"connection {c.source}.{c.output} -> {c.target}.{c.input}: "
                                   f"unknown instance {inst!r}; instances: {', '.join(instances)}")
            src = self.ports[c.source]
            if c.output not in src.instance.outputs:
                raise KeyError(f"{c.source}.{c.output} is not an output; outputs: "
                               + ", ".join(src.instance.outputs))
            if c.input not in instances[c.target].inputs:
                raise KeyError(f"{c.target}.{c.input} is not an input; inputs: "
                               + ", ".join(instances[c.target].inputs))
            wiring[c.target].append((c.input, src, src.instance.outputs.index(c.output)))
        for name, links in wiring.items():
            self.ports[name].connect(links)
        self.order = self._dependency_order(connections)
        # The exchange before each step as a flat list of calls. Gauss-Seidel: a
        # feedthrough instance gets its inputs before its outputs are read; the
        # others' inputs are set once every output is known.
        gauss_seidel = []
        for p in self.order:
            gauss_seidel += [p.write, p.read] if p.instance.feedthrough else [p.read]
        gauss_seidel += [p.write for p in self.order if not p.instance.feedthrough]
        self._plans = {
            "gauss-seidel": [c for c in gauss_seidel if c],
            "jacobi": [p.read for p in self.order] + [p.write for p in self.order if p.write],
        }
        self._steps = [p.step for p in self.order]
        # who made a call, for the error of a call that fails
        self._callers = {id(call): (instance, function)
                         for call, function, instance in self._plans["jacobi"] + self._steps}

    def _dependency_order(self, connections):
        """Instances ordered so that every feedthrough instance follows its sources."""
        after = {name: set() for name in self.instances}
        for c in connections:
            if self.instances[c.target].feedthrough and c.source != c.target:
                after[c.target].add(c.source)
        order = []
        while after:
            ready = [n for n, deps in after.items() if not deps - set(order)]
            if not ready:
                raise ValueError("algebraic loop through direct-feedthrough instances: "
                                 + ", ".join(sorted(after)))
            for n in ready:
                order.append(n)
                del after[n]
        return [self.ports[n] for n in order]

    def _fail(self, call, status, time):
        instance, function = self._callers[id(call)]
        instance.fail(function, status, time)

    def _exchange(self, mode, time):
        for call, _, _ in self._plans[mode]:
            if (status := call()) > 1:  # worse than warning
                self._fail(call, status, time)

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
        if self.initial_exchange:
            self._exchange("gauss-seidel", start_time)  # consistent inputs at t0 in both modes
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
        exchange = [call for call, _, _ in self._plans[self.mode]]
        steps = [call for call, _, _ in self._steps]
        observe = [o.observe for o in observers]
        values, fail = self.values, self._fail
        for k in range(first, last):
            t = start_time + k * step
            for call in exchange:
                if (status := call()) > 1:  # worse than warning
                    fail(call, status, t)
            for f in observe:
                f(t, values)
            for do_step in steps:
                if (status := do_step(t, step)) > 1:
                    fail(do_step, status, t)
        for inst in self.instances.values():
            inst.time = start_time + last * step

    def finish(self, stop_time, observers=()):
        """The exchange and observation at the last communication point."""
        self._exchange(self.mode, stop_time)
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
