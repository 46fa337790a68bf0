"""Many runs of one system on the same instances: reset between runs, the whole step loop in C.

A :class:`ReusedRunner` opens a system's FMUs once. Each run resets every instance (``fmi2Reset`` /
``fmi3Reset``: back to the state right after instantiation; an instance whose reset fails is freed
and instantiated again), initialises them as :class:`~crane_fmu.cosim.master.Master` does, and steps
from the start to the stop time in one call into the master's compiled loop (``step_loop.c``
``run_points``), keeping only the outputs asked for. The calls are the master's, in its order and
with its arguments (but the Real parameters of an instance, set in one call, and the Strings in
another), made by ``step_loop.c`` ``run_calls`` without Python between them, so a run gives the
numbers of a run on fresh instances through :func:`simulate` (a test holds them equal bit for bit,
and one fails when a state survives a reset). Where one of those calls fails, the run is initialised
again the master's way, which raises the master's error.

It needs the compiled loop and an algorithm with a fixed plan (Gauss-Seidel, Jacobi): :func:`can_reuse`.
"""

import ctypes

import numpy as np

from .adapters import open_instance
from .compiled_loop import (
    CALL,
    ENTER_3,
    GET_SET_2,
    GET_SET_3,
    SET_INT64S_3,
    SET_INTEGERS_2,
    SET_STRINGS_2,
    SET_STRINGS_3,
    SETUP_2,
    Operation,
    _operations,
    library,
)
from .instance import FmiError
from .master import Master, communication_points


def can_reuse(algorithm="gauss-seidel"):
    """Whether runs can go through a :class:`ReusedRunner`: a C compiler for the compiled loop, an algorithm with a
    fixed plan."""
    return library() is not None and algorithm in ("gauss-seidel", "jacobi")


class ReusedRunner:
    """Runs of the FMUs ``fmus`` (``{instance: .fmu path}``) wired by ``connections``, on instances reused.

    Parameters
    ----------
    fmus : dict
    connections : list of Connection
    algorithm : str
        A master algorithm with a fixed plan (``gauss-seidel``, ``jacobi``).

    Raises
    ------
    ValueError
        When the runs cannot go through the compiled loop (see :func:`can_reuse`).
    """

    def __init__(self, fmus, connections, algorithm="gauss-seidel"):
        self.fmus, self.connections, self.algorithm = dict(fmus), list(connections), algorithm
        self.instances, self.master, self.fresh = {}, None, 0
        self._open()
        self.output_names = self.master.output_names
        self._used = False  # reset before a run, unless the instances were just made
        self._rows = None  # the block runs record into

    def _open(self):
        """Instantiate every FMU (again) and wire them: the master's compiled loop over the new instances."""
        self.close()
        for name, path in self.fmus.items():
            self.instances[name] = open_instance(path, name)
        self.fresh += 1
        self._plans = {}  # the operations of run_calls by the parameters' names (of these instances)
        self.master = Master(self.instances, self.connections, self.algorithm)
        if self.master.compiled is None:
            self.close()
            raise ValueError(f"the {self.algorithm} runs of these FMUs cannot go through the compiled loop")
        # the initial exchange (the master's, whatever the algorithm): the propagation in dependency order
        initial = _operations(self.master.wiring.propagation())[0]
        self._initial = (initial, [(None, None)] * len(initial), None)  # a failure there: the master's way again

    def close(self):
        """Free every instance."""
        for inst in self.instances.values():
            inst.free()
        self.instances = {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _reset(self):
        """Every instance back to its state right after instantiation; all of them made again if one cannot."""
        try:
            for inst in self.instances.values():
                inst.reset()
        except FmiError:
            self._open()

    def _operations(self, parameters):
        """``(init, exits, ends)``: the operations of run_calls that reset (unless the instances are new), set up,
        set ``parameters`` and enter initialisation; exit it; terminate; each ``(Operation array, [(instance,
        function)] of each, what they point to)``. None where a parameter is neither a Real nor a String nor an
        Enumeration (the master's way sets it). Made once for the instances and the parameters' names (the
        :meth:`_plan`), then only the values written in place."""
        parameters = parameters or {}
        key = (self._used, tuple((name, tuple(values)) for name, values in parameters.items()))
        if key not in self._plans:
            if len(self._plans) >= 64:  # a bound: runs with ever other names of parameters
                self._plans.clear()
            self._plans[key] = self._plan(parameters)
        plan = self._plans[key]
        if plan is None:
            return None
        operations, fills = plan
        for values, i, kind, inst, name, variable in fills:
            value = parameters[name][variable]
            if kind == "Enumeration":  # by name or value, as the master's set
                values[i] = inst.enumeration_value(variable, value)
            else:
                values[i] = str(value).encode() if kind == "String" else float(value)
        return operations

    def _plan(self, parameters):
        """``(operations, fills)`` of :meth:`_operations` for the names of ``parameters``: the operations (their values
        still to write), and ``(values, index, kind, instance, name, variable)`` where each value goes; None where a
        parameter is of another kind."""
        init, exits, ends = ([], [], []), ([], [], []), ([], [], [])
        fills = []

        def add(ops, inst, kind, function, vr=None, values=None):
            address = ctypes.cast(inst._library[function], ctypes.c_void_p).value
            n = len(values) if values is not None else 0
            ops[0].append(Operation(kind, address, inst._fmu.component, vr and ctypes.addressof(vr), n,
                                    values and ctypes.addressof(values)))
            ops[1].append((inst, function))
            ops[2].extend((vr, values))

        def filled(values, inst, name, kinds):
            fills.extend((values, i, kind, inst, name, variable) for i, (variable, kind) in enumerate(kinds))
            return values

        if self._used:
            for inst in self.instances.values():
                add(init, inst, CALL, f"fmi{inst.md.fmiVersion[0]}Reset")
        for name, inst in self.instances.items():
            fmi3 = inst.md.fmiVersion.startswith("3")
            reals, texts, items = [], [], []
            for variable in parameters.get(name, {}):
                kind = inst._variable(variable).type
                if kind not in ("Real", "Float64", "String", "Enumeration"):
                    return None
                vr = inst.variables[variable].valueReference
                (items if kind == "Enumeration" else texts if kind == "String" else reals).append((vr, variable, kind))
            if not fmi3:
                add(init, inst, SETUP_2, "fmi2SetupExperiment")
            if reals:
                add(init, inst, GET_SET_3 if fmi3 else GET_SET_2, "fmi3SetFloat64" if fmi3 else "fmi2SetReal",
                    (ctypes.c_uint * len(reals))(*(vr for vr, _, _ in reals)),
                    filled((ctypes.c_double * len(reals))(), inst, name, [(v, k) for _, v, k in reals]))
            if texts:
                add(init, inst, SET_STRINGS_3 if fmi3 else SET_STRINGS_2, "fmi3SetString" if fmi3 else "fmi2SetString",
                    (ctypes.c_uint * len(texts))(*(vr for vr, _, _ in texts)),
                    filled((ctypes.c_char_p * len(texts))(), inst, name, [(v, k) for _, v, k in texts]))
            if items:
                add(init, inst, SET_INT64S_3 if fmi3 else SET_INTEGERS_2, "fmi3SetInt64" if fmi3 else "fmi2SetInteger",
                    (ctypes.c_uint * len(items))(*(vr for vr, _, _ in items)),
                    filled(((ctypes.c_longlong if fmi3 else ctypes.c_int) * len(items))(), inst, name,
                           [(v, k) for _, v, k in items]))
            if fmi3:
                add(init, inst, ENTER_3, "fmi3EnterInitializationMode")
            else:
                add(init, inst, CALL, "fmi2EnterInitializationMode")
            add(exits, inst, CALL, f"fmi{inst.md.fmiVersion[0]}ExitInitializationMode")
            add(ends, inst, CALL, f"fmi{inst.md.fmiVersion[0]}Terminate")
        return [((Operation * len(ops)).from_buffer_copy(b"".join(bytes(o) for o in ops)) if ops else
                 (Operation * 0)(), owners, alive) for ops, owners, alive in (init, exits, ends)], fills

    def _calls(self, operations, time, stop):
        """Make ``operations`` (run_calls, at ``time`` with the experiment's ``stop``); ``(instance, function, status)``
        of the one that failed, or None."""
        ops, owners, _ = operations
        status = ctypes.c_int()
        failed = self.master.compiled.lib.run_calls(ops, len(ops), time, stop, ctypes.byref(status))
        return None if failed < 0 else (*owners[failed], status.value)

    def _initialize(self, start_time, stop_time, parameters):
        """Reset (unless the instances are new) and initialise for a run through run_calls; where a call fails
        there, again the master's way (:meth:`Master.initialize`, whose FmiError propagates). Returns the operations
        that terminate, or None (then the master terminates)."""
        operations = self._operations(parameters)
        if operations is not None:
            init, exits, ends = operations
            self._used = True
            if not self._calls(init, start_time, stop_time) and not self._calls(self._initial, start_time, stop_time):
                for inst in self.instances.values():
                    inst.messages.clear()  # as each exit call the master makes through fmpy
                if not self._calls(exits, start_time, stop_time):
                    return ends
        if self._used:
            self._reset()
        self._used = True
        self.master.initialize(start_time, stop_time, parameters)
        return None

    def run(self, start_time, stop_time, step, parameters=None, keep=None):
        """One run from ``start_time`` to ``stop_time``: ``(rows, error)``.

        Parameters
        ----------
        parameters : dict, optional
            ``{instance: {variable: value}}`` set before initialisation.
        keep : list of str, optional
            The outputs (``instance.variable``) each row holds after the time; default every one.

        Returns
        -------
        rows : numpy.ndarray
            One row per communication point reached: the time, then the ``keep`` outputs (the runner's block,
            which its next run overwrites: copy what you keep).
        error : FmiError or None
            Why the run stopped early, as :func:`simulate` raises it (rows then hold the points before it, as a
            recorder of that run holds them); None when it ran to ``stop_time``.
        """
        n = communication_points(start_time, stop_time, step)
        names = self.output_names if keep is None else list(keep)
        index = {name: i for i, name in enumerate(self.output_names)}
        columns = (ctypes.c_size_t * len(names))(*(index[name] for name in names))
        width = len(names) + 1
        if self._rows is None or self._rows.size < (n + 1) * width:
            self._rows = np.empty((n + 1) * width)
        rows = self._rows[:(n + 1) * width].reshape(n + 1, width)
        try:
            ends = self._initialize(start_time, stop_time, parameters)
        except FmiError as exc:
            return rows[:0], exc
        loop = self.master.compiled
        # the steps at start + k*step, then the last point at the stop time itself, as Master.run records it
        address = rows.__array_interface__["data"][0]
        done, failure = loop.run(start_time, step, 0, n, n, columns, len(names), address)
        if not failure:
            last, failure = loop.run(stop_time, step, 0, 1, 0, columns, len(names), address + 8 * width * n)
            done += last
        try:
            if failure:
                self.master.wiring.fail(*failure)
            if ends is None:
                self.master.terminate()
            else:
                for inst in self.instances.values():
                    inst.messages.clear()  # as each terminate call the master makes through fmpy
                failed = self._calls(ends, 0.0, 0.0)
                if failed:
                    inst, function, status = failed
                    inst.fail(function, status, start_time + n * step)  # the time the master's run ends at
        except FmiError as exc:
            return rows[:done], exc
        return rows, None
