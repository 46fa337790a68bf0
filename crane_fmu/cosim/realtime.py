"""A master stepped in real time or in lock-step, between programs that read and write its values.

:class:`Runner` drives an ordinary :class:`~crane_fmu.cosim.master.Master` (the same exchange, the same
observers and recorders) in one of two modes:

- **real time**: every ``period`` (a whole number of communication steps) at absolute deadlines
  (:class:`~crane_fmu.cosim.pacing.Pacer`), the latest values written are taken, the master advances one
  period, and what it computed is served until the next deadline;
- **lock-step**: the master advances only when asked (:meth:`Runner.request_steps`), in virtual time.

What is served is a list of :class:`Served` variables: every output of every instance, every Real
parameter, and of an :class:`~crane_fmu.cosim.external.ExternalInstance` its inputs (which the program
outside reads) and its outputs (which it writes). A program writes with :meth:`Runner.write` and reads
:meth:`Runner.snapshot`; adapters for network protocols (``crane_fmu.serve``) do both, and are told of every
new snapshot by the ``listeners``. Nothing here knows a protocol. In real time the :meth:`Runner.run` loop makes
every FMI call on its thread; in lock-step the thread that asks for steps takes them (one request at a time),
so that a request costs no hand-over between threads.

After every advance the master exchanges once more at the new time, so the external instance's inputs
(what the program reads) are those of the new time; the next advance exchanges at that time again and then
takes what the program has written since. In lock-step with a program that reads, computes and writes
before every step, this is the offline run's Gauss-Seidel exchange exactly.
"""

import math
import threading
import time
from collections import namedtuple
from concurrent.futures import Future

from .external import ExternalInstance
from .instance import FmiError
from .pacing import Pacer

Served = namedtuple("Served", "name role unit description writable")
Served.__doc__ = ("A served variable: ``name`` is ``instance.variable``; ``role`` is ``output``, ``input`` (of the "
                  "external instance) or ``parameter``; ``writable`` by the program outside.")

Snapshot = namedtuple("Snapshot", "time steps values status code")
Snapshot.__doc__ = ("What is served at one moment: the simulated ``time``, the ``steps`` taken, ``values`` (in the "
                    "order of :attr:`Runner.variables`), the ``status`` line and its ``code`` (:data:`STATUS_CODES`).")

# status codes, as the Modbus register map gives them
STATUS_CODES = {"waiting": 1, "running": 2, "holding": 3, "finished": 4, "failed": 5, "stopped": 6}


class Runner:
    """Steps ``master`` in real time or lock-step; see the module's description.

    Parameters
    ----------
    master : Master
        Not yet initialised; at most one of its instances an :class:`ExternalInstance`.
    start_time, step : float
        The grid ``start_time + k*step`` [s].
    stop_time : float or None
        Where the run ends (None: when stopped).
    parameters : dict
        ``{instance: {variable: value}}`` set before initialisation.
    observers : sequence
        Observers of every communication point (recorders), as the master's.
    lock_step : bool
    period_steps : int
        Real time: communication steps per cycle (the period is ``period_steps * step``).
    watchdog : Watchdog or None
        Real time with an external instance: holds its outputs when no write came for its timeout.
    writable : bool
        Let the program outside write the parameters that the FMUs declare tunable (FMI allows setting
        only those during a run); never the others.
    clock, sleep : callable
        For the pacing; the default sleep waits on the runner's stop event.
    log : callable
        Gets the lines that say what changed (the watchdog), e.g. ``print`` to stderr.
    """

    def __init__(self, master, start_time, step, stop_time=None, parameters=None, observers=(), lock_step=False,
                 period_steps=1, watchdog=None, writable=False, clock=time.monotonic, sleep=None, log=None):
        if not isinstance(period_steps, int) or period_steps < 1:
            raise ValueError(f"steps per period must be a whole number >= 1, got {period_steps!r}")
        self.master, self.start_time, self.step, self.stop_time = master, start_time, step, stop_time
        self.parameters, self.observers = parameters or {}, list(observers)
        self.lock_step, self.period_steps, self.watchdog = lock_step, period_steps, watchdog
        self.clock, self.log = clock, log or (lambda line: None)
        self._stopping = threading.Event()
        self.sleep = sleep or self._stopping.wait
        self.last_steps = None if stop_time is None else round((stop_time - start_time) / step)
        externals = [inst for inst in master.instances.values() if isinstance(inst, ExternalInstance)]
        if len(externals) > 1:
            raise ValueError("at most one external instance: " + ", ".join(e.name for e in externals))
        self.external = externals[0] if externals else None
        self.variables = self._served(writable)
        self.listeners = []  # callables getting every new Snapshot, on the runner's thread
        self.steps, self.pacer, self.error = 0, None, None
        self._lock = threading.Lock()  # one advance at a time
        self._pending = {}  # parameter writes, applied by the runner's thread before its next advance
        self._pending_lock = threading.Lock()
        self._last_write = None
        self._status = ("waiting", "starting")  # (code, line)
        self._snapshot = None

    def _served(self, writable):
        served = []
        for name, inst in self.master.instances.items():
            variables = [inst.variables[n] for n in inst.outputs]
            if inst is self.external:
                variables = [inst.variables[n] for n in inst.inputs] + variables
            else:
                variables += [v for v in inst.md.modelVariables if v.causality == "parameter"
                              and v.type in ("Real", "Float64")]
            for v in variables:
                served.append(Served(
                    f"{name}.{v.name}", v.causality, v.unit or "1", v.description or "",
                    (inst is self.external and v.causality == "output")
                    or (writable and v.causality == "parameter" and v.variability == "tunable")))
        return served

    # --- what programs outside call, from any thread ---

    def snapshot(self):
        """The latest :class:`Snapshot` (None before :meth:`start`)."""
        return self._snapshot

    def write(self, values):
        """Write ``{instance.variable: value}`` of writable variables, all or none.

        The external instance's outputs take effect at the next exchange; parameters before the next
        advance. ValueError (one line) for a name that is not writable or a value that is not finite.
        """
        writable = {v.name: v for v in self.variables if v.writable}
        checked = {}
        for name, value in values.items():
            if name not in writable:
                known = any(v.name == name for v in self.variables)
                raise ValueError(f"{name} is {'read-only' if known else 'not served'}; writable: "
                                 + (", ".join(writable) or "none"))
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number, got {value!r}")
            checked[name] = float(value)
        outputs = {n.partition(".")[2]: v for n, v in checked.items() if writable[n].role == "output"}
        if outputs:
            self.external.set_outputs(outputs)
            self._last_write = self.clock()
        with self._pending_lock:
            self._pending.update({n: v for n, v in checked.items() if writable[n].role == "parameter"})

    def request_steps(self, n):
        """Lock-step: take ``n`` communication steps now, on the calling thread; a done Future of the simulated
        time after them.

        The Future holds a ValueError instead when ``n`` is not a whole number >= 1, when the runner is not in
        lock-step, when the steps would pass the stop time, when the run has ended, or when an FMU failed (the
        run then ends; :attr:`error` holds the FmiError). Requests from several threads are taken one after
        another.
        """
        future = Future()
        if not self.lock_step:
            future.set_exception(ValueError("the run is in real time: steps are taken by the clock, not asked for"))
            return future
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            future.set_exception(ValueError(f"the number of steps must be a whole number >= 1, got {n!r}"))
            return future
        with self._lock:
            if self._stopping.is_set() or self._snapshot is None:
                future.set_exception(ValueError(f"the run is not going ({self._status[1]})"))
            elif self.last_steps is not None and self.steps + n > self.last_steps:
                future.set_exception(ValueError(
                    f"{n} steps from t = {self.time():.9g} s would pass the stop time {self.stop_time:g} s "
                    f"({self.last_steps - self.steps} steps left)"))
            else:
                try:
                    self.advance(n)
                    future.set_result(self.time())
                except FmiError as exc:
                    self._failed(exc)
                    future.set_exception(ValueError(str(exc)))
        return future

    def stop(self):
        """End :meth:`run` at its next safe point (from any thread or a signal handler)."""
        self._stopping.set()

    # --- the runner's own thread ---

    def start(self):
        """Initialise the master, start the observers and serve the first snapshot."""
        self.master.initialize(self.start_time, self.stop_time, self.parameters)
        self._parameter_values = {}
        for v in self.variables:
            if v.role == "parameter":
                instance, _, variable = v.name.partition(".")
                self._parameter_values[v.name] = self.master.instances[instance].get(variable)
        for o in self.observers:
            o.start(self.master.output_names)
        self._sources = self._value_sources()
        self._last_write = self.clock()
        self._set_status("waiting for Step (lock-step)" if self.lock_step else "running in real time",
                         "waiting" if self.lock_step else "running")
        return self._snapshot

    def _value_sources(self):
        """For each served variable: ``("out", index in the master's values)``, ``("in", instance variable)`` or
        ``("par", name)``."""
        position = {name: i for i, name in enumerate(self.master.output_names)}
        sources = []
        for v in self.variables:
            if v.role == "output":
                sources.append(("out", position[v.name]))
            elif v.role == "input":
                sources.append(("in", v.name.partition(".")[2]))
            else:
                sources.append(("par", v.name))
        return sources

    def run(self):
        """Start (unless :meth:`start` was called), then in real time step until the stop time or until stopped,
        in lock-step wait until stopped (the steps are taken by :meth:`request_steps`). Call :meth:`finish` then.

        An FMU failure ends the run: the status says so, :attr:`error` holds the
        :class:`~crane_fmu.cosim.instance.FmiError`, and it is raised here.
        """
        if self._snapshot is None:
            self.start()
        if self.lock_step:
            while not self._stopping.wait(0.1):
                pass
        else:
            try:
                self._run_in_real_time()
            except FmiError as exc:
                self._failed(exc)
        if self.error is not None:
            raise self.error

    def _failed(self, error):
        self.error = error
        self._stopping.set()
        self._set_status(f"failed: {error}", "failed")

    def _run_in_real_time(self):
        self.pacer = Pacer(self.period_steps * self.step, self.clock, self.sleep)
        self._last_write = self.clock()  # the watchdog counts from the first deadline
        m = self.period_steps
        while not self._stopping.is_set():
            n = m if self.last_steps is None else min(m, self.last_steps - self.steps)
            if n <= 0:
                self._stopping.set()
                break
            if not self.pacer.cycle(lambda n=n: self._cycle(n)):
                break

    def _cycle(self, n):
        if self.watchdog and self.external:
            self._watch()
        self.advance(n)

    def _watch(self):
        now = self.clock()
        change = self.watchdog.check(now, self._last_write)
        what = f"{self.external.name}'s outputs"
        if change == "hold":
            if self.watchdog.hold == "zero":
                self.external.set_outputs(dict.fromkeys(self.external.outputs, 0.0))
            line = self.watchdog.describe(now - self._last_write, what)
            self.log(f"t = {self.time():.6g} s: {line}")
            self._set_status(f"holding: {line}", "holding", publish=False)
        elif change == "resume":
            self.log(f"t = {self.time():.6g} s: the client writes again: {what} follow it")
            self._set_status("running in real time", "running", publish=False)

    def advance(self, n):
        """Take ``n`` communication steps (parameters written since are set first), exchange at the new time and
        serve the new snapshot."""
        self._apply_parameters()
        k = self.steps
        self.master.advance(self.start_time, self.step, k, k + n, self.observers)
        self.steps = k + n
        self.master.algorithm.exchange(self.time())
        self._publish()

    def _apply_parameters(self):
        with self._pending_lock:
            pending, self._pending = self._pending, {}
        for name, value in pending.items():
            instance, _, variable = name.partition(".")
            self.master.instances[instance].set(variable, value)
            self._parameter_values[name] = self.master.instances[instance].get(variable)

    def time(self):
        """The simulated time now: ``start_time + steps*step``."""
        return self.start_time + self.steps * self.step

    def finish(self):
        """End the run: the last communication point's exchange and observation, the master terminated.
        Returns the simulated time."""
        with self._lock:
            self._stopping.set()
            t = self.time()
            self.master.finish(t, self.observers)
            self.master.terminate()
            if self.last_steps is not None and self.steps == self.last_steps:
                self._set_status(f"finished at t = {t:.9g} s", "finished")
            else:
                self._set_status(f"stopped at t = {t:.9g} s", "stopped")
        return t

    def _set_status(self, line, code, publish=True):
        self._status = (code, line)
        if publish and hasattr(self, "_sources"):
            self._publish()

    def _publish(self):
        values = self.master.values
        inputs = self.external.input_values() if self.external else {}
        parameters = self._parameter_values
        served = tuple(values[i] if kind == "out" else inputs[i] if kind == "in" else parameters[i]
                       for kind, i in self._sources)
        code, line = self._status
        snapshot = Snapshot(self.time(), self.steps, served, line, STATUS_CODES[code])
        self._snapshot = snapshot
        for listener in self.listeners:
            listener(snapshot)
