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

No write ends the run: a written value must lie in its range (:mod:`.write_ranges`), and where every FMU
can save its state, the steps are taken in blocks of at most :data:`BLOCK`, each from a saved state: a block
that an FMU refuses (a state that would become non-finite, a rail end passed) is rolled back to it and
:class:`StepRefused` raised, the run going on from there. :meth:`Runner.stop` (a signal) ends a request of
many steps at the next block boundary. One request takes at most :data:`MAX_STEPS` steps.

A ``guard`` (see :class:`Runner`) knows what the FMUs do not say: a block that ends in a state from which no
value the program may write keeps the run going (a state the next steps must leave through a refusal) is refused
like an FMU's refusal, and in real time the external instance's outputs are held, after a refusal and until the
program writes again, at the values the guard gives for the state reached, cycle by cycle, so that the run leaves
the refused state by itself. Without a guard they are held at zero.
"""

import math
import secrets
import threading
import time
from collections import namedtuple
from concurrent.futures import Future

from .external import ExternalInstance
from .instance import FmiError
from .pacing import Pacer
from .recorder import ArrayRecorder
from .write_ranges import write_ranges

Served = namedtuple("Served", "name role unit description writable")
Served.__doc__ = ("A served variable: ``name`` is ``instance.variable``; ``role`` is ``output``, ``input`` (of the "
                  "external instance) or ``parameter``; ``writable`` by the program outside.")

Snapshot = namedtuple("Snapshot", "time steps values status code")
Snapshot.__doc__ = ("What is served at one moment: the simulated ``time``, the ``steps`` taken, ``values`` (in the "
                    "order of :attr:`Runner.variables`), the ``status`` line and its ``code`` (:data:`STATUS_CODES`).")

# status codes, as the Modbus register map gives them
STATUS_CODES = {"waiting": 1, "running": 2, "holding": 3, "finished": 4, "failed": 5, "stopped": 6}
MAX_STEPS = 65535  # the most communication steps one request takes (as Modbus' 16-bit step register holds)
BLOCK = 1000  # steps between two saved states and two looks for a stop


class Refusal(Exception):
    """A block the runner's guard refused (its line)."""


class StepRefused(ValueError):
    """An FMU refused a step: the steps since the last saved state were rolled back; the run goes on.
    ``error`` is the FmiError."""

    def __init__(self, error, time):
        self.error = error
        super().__init__(f"{error}; refused: the run is rolled back to t = {time:.9g} s and goes on")


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
    name : str
        The system's name, served with :attr:`run_id` and :attr:`started` so that a client can tell which run
        it drives.
    guard : object or None
        Where states can be saved: ``guard.start(master, cycle, ranges)`` once initialised (``cycle`` [s]: the
        real-time period, or the step in lock-step; ``ranges``: :attr:`ranges`), then ``guard.refuses(before,
        after, seconds)``, the master's values before and after each block of ``seconds``: None, or the one line
        that refuses it (rolled back as an FMU's refusal); ``guard.hold(values)``: ``{external output: value}`` to
        hold while the run is held after a refusal (real time), re-asked every cycle until the program writes.

    Attributes
    ----------
    run_id : int
        A random 64-bit number, new for every runner.
    started : float or None
        The wall-clock time (Unix time, s) :meth:`start` was called at.
    """

    def __init__(self, master, start_time, step, stop_time=None, parameters=None, observers=(), lock_step=False,
                 period_steps=1, watchdog=None, writable=False, clock=time.monotonic, sleep=None, log=None, name="",
                 guard=None):
        if not isinstance(period_steps, int) or period_steps < 1:
            raise ValueError(f"steps per period must be a whole number >= 1, got {period_steps!r}")
        self.master, self.start_time, self.step, self.stop_time = master, start_time, step, stop_time
        self.parameters, self.observers = parameters or {}, list(observers)
        self.lock_step, self.period_steps, self.watchdog = lock_step, period_steps, watchdog
        self.clock, self.log = clock, log or (lambda line: None)
        self._refusals = [-math.inf, 0]  # when a refused write was last said, and how many since went unsaid
        self.name, self.run_id, self.started = name, secrets.randbits(64), None
        self._stopping = threading.Event()
        self.sleep = sleep or self._stopping.wait
        self.last_steps = None if stop_time is None else round((stop_time - start_time) / step)
        externals = [inst for inst in master.instances.values() if isinstance(inst, ExternalInstance)]
        if len(externals) > 1:
            raise ValueError("at most one external instance: " + ", ".join(e.name for e in externals))
        self.external = externals[0] if externals else None
        self.variables = self._served(writable)
        self._index = {v.name: i for i, v in enumerate(self.variables)}
        self.listeners = []  # callables getting every new Snapshot, on the runner's thread
        self.steps, self.pacer, self.error = 0, None, None
        self._lock = threading.Lock()  # one advance at a time
        self._pending = {}  # parameter writes, applied by the runner's thread before its next advance
        self._pending_lock = threading.Lock()
        self._last_write = None
        self._status = ("waiting", "starting")  # (code, line)
        self._snapshot = None
        self._publishing = threading.Lock()  # one snapshot made at a time: the steps' and the writes'
        self.ranges = {}  # {name: (low, high)} of the writable variables, known once initialised
        self.guarded = all(isinstance(inst, ExternalInstance) or inst.md.coSimulation.canGetAndSetFMUstate
                           for inst in master.instances.values())
        self.guard = guard if self.guarded else None
        self._holding = False  # real time: the external outputs held after a refusal, until the program writes

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
        advance. ValueError (one line) for a name that is not writable or a value that is not finite or
        lies outside its range (:attr:`ranges`).
        """
        writable = {v.name: v for v in self.variables if v.writable}
        checked = {}
        for name, value in values.items():
            if name not in writable:
                known = any(v.name == name for v in self.variables)
                self.refused(f"{name} is {'read-only' if known else 'not served'}")
                raise ValueError(f"{name} is {'read-only' if known else 'not served'}; writable: "
                                 + (", ".join(writable) or "none"))
            checked[name] = self.check(name, value)
        outputs = {n.partition(".")[2]: v for n, v in checked.items() if writable[n].role == "output"}
        if outputs:
            self.external.set_outputs(outputs)
            self._last_write = self.clock()
            self._holding = False
        with self._pending_lock:
            self._pending.update({n: v for n, v in checked.items() if writable[n].role == "parameter"})
        self._publish(written=checked)  # one table for every protocol: what was written is what is read

    def check(self, name, value):
        """``value`` as a float if it may be written to the writable variable ``name``, else ValueError (one
        line naming the value and the rule)."""
        why = None
        low, high = self.ranges.get(name, (-math.inf, math.inf))
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            why = f"{name} must be a finite number, got {value!r}"
        elif not low <= value <= high:
            unit = next((v.unit for v in self.variables if v.name == name), "")
            why = f"{name} = {value!r} {unit} lies outside its range [{low:g}, {high:g}]"
        if why:
            self.refused(why)
            raise ValueError(why)
        return float(value)

    def refused(self, why):
        """Say on the log that a client's write was refused and why: at most a line a second (a client that sends
        NaN a thousand times a second is one line a second, counting the others)."""
        now = self.clock()
        if now - self._refusals[0] < 1.0:
            self._refusals[1] += 1
            return
        unsaid = f" ({self._refusals[1]} more refused since the last such line)" if self._refusals[1] else ""
        self._refusals[:] = [now, 0]
        self.log(f"t = {self.time():.6g} s: a client's write refused: {why}{unsaid}")

    def request_steps(self, n):
        """Lock-step: take ``n`` communication steps now, on the calling thread; a done Future of the simulated
        time after them.

        The Future holds a ValueError instead when ``n`` is not a whole number from 1 to :data:`MAX_STEPS`,
        when the runner is not in lock-step, when the steps would pass the stop time, when the run has ended or
        is stopped on the way (the steps taken are kept), a :class:`StepRefused` when an FMU refused a step (rolled
        back: the run goes on), or when an FMU failed where no state could be saved (the run then ends;
        :attr:`error` holds the FmiError). Requests from several threads are taken one after another.
        """
        future = Future()
        if not self.lock_step:
            future.set_exception(ValueError("the run is in real time: steps are taken by the clock, not asked for"))
            return future
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_STEPS:
            future.set_exception(ValueError(f"the number of steps must be a whole number from 1 to {MAX_STEPS}, "
                                            f"got {n!r}"))
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
                    taken = self.advance(n)
                    if taken < n:
                        future.set_exception(ValueError(f"the run was stopped at t = {self.time():.9g} s, after "
                                                        f"{taken} of {n} steps"))
                    else:
                        future.set_result(self.time())
                except StepRefused as exc:
                    self.log(str(exc))
                    future.set_exception(exc)
                except FmiError as exc:
                    self._failed(exc)
                    future.set_exception(ValueError(str(exc)))
        return future

    def stop(self):
        """End :meth:`run` at its next safe point (from any thread or a signal handler)."""
        self._stopping.set()

    def wait_idle(self):
        """Wait until no request is taking steps (a stopped one ends at its next block boundary)."""
        with self._lock:
            pass

    # --- the runner's own thread ---

    def start(self):
        """Initialise the master, start the observers and serve the first snapshot."""
        self.started = time.time()
        self.master.initialize(self.start_time, self.stop_time, self.parameters)
        self.ranges = write_ranges(self.master, self.variables, self.external)
        if self.guard is not None:
            self.guard.start(self.master, self.step if self.lock_step else self.period_steps * self.step, self.ranges)
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
        self._refused = None
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
        if self._holding and self.guard is not None:
            self._hold_outputs()
        try:
            self.advance(n)
        except StepRefused as exc:
            self._hold_refused(exc)
            return
        if self._refused is not None:
            self._refused = None
            self.log(f"t = {self.time():.6g} s: the steps are taken again")
            self._set_status("running in real time", "running")

    def _hold_refused(self, exc):
        """Real time: a cycle an FMU (or the guard) refused was rolled back; the run waits at its time (the cycles
        go on, time does not) until the values held or written let it step. The first refusal in a row holds the
        external instance's outputs (at zero, or at the guard's values, cycle by cycle until the program writes)
        and says so; without an external instance no write can change it: the run fails."""
        if self.external is None:
            raise exc.error from None
        if self._refused is None:
            held = self._hold_outputs()
            what = "zero" if not any(held.values()) else ", ".join(f"{k} = {v:.6g}" for k, v in held.items())
            until = "a write lets the run step" if self.guard is None else "the next write"
            self.log(f"{exc}; {self.external.name}'s outputs held at {what} until {until}")
            self._holding = True
        self._refused = exc
        self._set_status(f"holding: {exc}", "holding")

    def _hold_outputs(self):
        """Hold the external instance's outputs at zero, or at the guard's values for the state now; served as
        written. Returns them."""
        held = dict.fromkeys(self.external.outputs, 0.0)
        if self.guard is not None:
            held.update(self.guard.hold(self.master.values))
        self.external.set_outputs(held)
        self._publish(written={f"{self.external.name}.{name}": value for name, value in held.items()
                               if f"{self.external.name}.{name}" in self._index})
        return held

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
        serve the new snapshot; the steps taken (fewer than ``n`` when stopped on the way). In blocks of at most
        :data:`BLOCK` steps, each rolled back if an FMU refuses it (:class:`StepRefused`) where states can be
        saved."""
        self._apply_parameters()
        taken = 0
        try:
            while taken < n and not (taken and self._stopping.is_set()):
                block = min(BLOCK, n - taken)
                self._block(block)
                taken += block
        finally:
            self.master.algorithm.exchange(self.time())
            if self.last_steps is not None and self.steps == self.last_steps:
                self._set_status(f"finished at t = {self.time():.9g} s", "finished")
            else:
                self._publish()
        return taken

    def _block(self, n):
        k = self.steps
        if not self.guarded:
            self.master.advance(self.start_time, self.step, k, k + n, self.observers)
            self.steps = k + n
            return
        saved = {name: inst.get_state() for name, inst in self.master.instances.items()}
        held = ArrayRecorder()  # the block's rows, for the observers once it is taken
        held.start(self.master.output_names)
        before = tuple(self.master.values)
        try:
            self.master.advance(self.start_time, self.step, k, k + n, [held])
            reason = None
            if self.guard is not None:  # the values at the block's end: its last step's outputs
                self.master.algorithm.exchange(self.start_time + (k + n) * self.step)
                reason = self.guard.refuses(before, self.master.values, n * self.step)
            if reason is not None:
                raise Refusal(reason)
        except (FmiError, Refusal) as exc:
            for name, inst in self.master.instances.items():
                inst.set_state(saved[name])
                inst.time = self.time()
            raise StepRefused(exc, self.time()) from exc
        finally:
            for name, inst in self.master.instances.items():
                inst.free_state(saved[name])
        self.steps = k + n
        rows = memoryview(held._rows)
        width = len(held.names)
        for o in self.observers:
            if hasattr(o, "observe_rows"):
                o.observe_rows(rows)
            else:
                for i in range(0, len(rows), width):
                    o.observe(rows[i], rows[i + 1:i + width])

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

    def _publish(self, written=None):
        """Serve a new snapshot: of the values in effect, or the latest one with the values ``written``
        (``{name: value}``) in place, which take effect at the next step."""
        with self._publishing:
            if written is not None:
                if self._snapshot is None:
                    return
                served = list(self._snapshot.values)
                for name, value in written.items():
                    served[self._index[name]] = value
                served = tuple(served)
            else:
                values = self.master.values
                inputs = self.external.input_values() if self.external else {}
                parameters = self._parameter_values
                served = tuple(values[i] if kind == "out" else inputs[i] if kind == "in" else parameters[i]
                               for kind, i in self._sources)
                with self._pending_lock:  # a parameter written, not yet applied, reads as written
                    served = tuple(self._pending.get(v.name, value) for v, value in zip(self.variables, served))
            code, line = self._status
            snapshot = Snapshot(self.time(), self.steps, served, line, STATUS_CODES[code])
            self._snapshot = snapshot
            for listener in self.listeners:
                listener(snapshot)
