"""The stepping algorithm with fake FMU instances: ordering, delays, time, errors."""

import ctypes

import pytest

from crane_fmu.cosim import FmiError
from crane_fmu.cosim.algorithms import ALGORITHMS, Algorithm, IterativeJacobi
from crane_fmu.cosim.connections import Connection
from crane_fmu.cosim.exchange import AlgebraicLoop, find_loop
from crane_fmu.cosim.master import Master, communication_points
from crane_fmu.cosim.recorder import ArrayRecorder

pytestmark = pytest.mark.quick  # no build: in the quick subset


class FakeInstance:
    """Python stand-in for an FMU instance: ``outputs(values)`` computes outputs from inputs and state.

    ``feedthrough``: every output reads every input at the same instant, or none does; or
    ``{output: (input, ...)}``, what each output reads."""

    def __init__(self, name, inputs, outputs, feedthrough, step=None, compute=None):
        self.name, self.inputs, self.outputs = name, inputs, outputs
        self.dependencies = (feedthrough if isinstance(feedthrough, dict) else
                             {o: tuple(inputs) if feedthrough else () for o in outputs})
        self.feedthrough = any(self.dependencies.values())
        self.values = {n: 0.0 for n in inputs + outputs}
        self._step_function, self._compute = step, compute
        self.calls = []
        self.set_status = 0

    def vr_array(self, names):
        index = self.inputs + self.outputs
        return (ctypes.c_uint * len(names))(*(index.index(n) for n in names))

    def _names(self, vrs):
        index = self.inputs + self.outputs
        return [index[v] for v in vrs]

    def reader(self, vrs, values):
        def get():
            if self._compute:
                self.values.update(self._compute(self.values))
            for i, n in enumerate(self._names(vrs)):
                values[i] = self.values[n]
            return 0
        return get, "get"

    def writer(self, vrs, values):
        def set_():
            for i, n in enumerate(self._names(vrs)):
                self.values[n] = values[i]
            return self.set_status
        return set_, "set"

    def stepper(self):
        def do_step(t, h):
            self.calls.append(t)
            if self._step_function:
                self.values.update(self._step_function(self.values, h))
            return 0
        return do_step, "step"

    def fail(self, function, status, time):
        raise RuntimeError(f"{self.name}: {function} returned {status} at t={time}")

    def setup(self, t0, stop=None):
        pass

    def set(self, name, value):
        self.values[name] = value

    enter_initialization = exit_initialization = terminate = free = lambda self: None


def _loop(gain=1.0):
    """Integrator y' = u (no feedthrough) closed by u = -gain*y (feedthrough)."""
    integ = FakeInstance("integ", ["u"], ["y"], False,
                         step=lambda v, h: {"y": v["y"] + h * v["u"]})
    ctrl = FakeInstance("ctrl", ["y"], ["u"], True, compute=lambda v: {"u": -gain * v["y"]})
    conns = [Connection("integ", "y", "ctrl", "y"), Connection("ctrl", "u", "integ", "u")]
    return {"ctrl": ctrl, "integ": integ}, conns


@pytest.mark.parametrize("mode", ["gauss-seidel", "jacobi"])
def test_exchange_order_and_delay(mode):
    instances, conns = _loop()
    instances["integ"].values["y"] = 1.0
    rec = ArrayRecorder()
    Master(instances, conns, mode).run(0.0, 0.5, 0.1, [rec])
    y = rec.columns()["integ.y"]
    h, expected = 0.1, [1.0]
    previous = 1.0
    for _ in range(5):
        current = expected[-1]
        u = -(current if mode == "gauss-seidel" else previous)  # jacobi: one step late
        previous = current
        expected.append(current + h * u)
    assert list(y) == pytest.approx(expected, rel=1e-15)
    assert mode == "jacobi" or list(rec.columns()["ctrl.u"]) == pytest.approx([-v for v in expected])


def test_time_is_start_plus_k_times_step():
    instances, conns = _loop()
    rec = ArrayRecorder()
    Master(instances, conns).run(0.3, 1.3, 0.1, [rec])
    assert list(rec.columns()["time"]) == [0.3 + k * 0.1 for k in range(10)] + [1.3]
    assert instances["integ"].calls == [0.3 + k * 0.1 for k in range(10)]


@pytest.mark.parametrize("mode", ["gauss-seidel", "jacobi"])
def test_a_failing_call_stops_the_run_naming_instance_function_and_time(mode):
    instances, conns = _loop()
    integ, ctrl = instances["integ"], instances["ctrl"]

    def step_then_fail(values, h):
        if len(integ.calls) == 3:  # the exchange after the third step fails
            ctrl.set_status = 3
        return {"y": values["y"] + h * values["u"]}

    integ._step_function = step_then_fail
    with pytest.raises(RuntimeError, match=r"^ctrl: set returned 3 at t=0.30000000000000004$"):
        Master(instances, conns, mode).run(0.0, 1.0, 0.1)
    assert integ.calls == [0.0, 0.1, 0.2]


def test_feedthrough_instance_is_ordered_after_its_source():
    instances, conns = _loop()
    assert [p.instance.name for p in Master(instances, conns).wiring.order] == ["integ", "ctrl"]


def test_algebraic_loop_is_refused():
    a = FakeInstance("a", ["i"], ["o"], True, compute=lambda v: {"o": v["i"]})
    b = FakeInstance("b", ["i"], ["o"], True, compute=lambda v: {"o": v["i"]})
    conns = [Connection("a", "o", "b", "i"), Connection("b", "o", "a", "i")]
    with pytest.raises(ValueError, match="algebraic loop"):
        Master({"a": a, "b": b}, conns)


def _partly_feedthrough(gain=2.0):
    """A cart whose position ``y`` reads no input and whose acceleration ``a`` reads its force ``f`` at the same
    instant (``y' = v, v' = f``), closed by ``f = -gain*y`` (feedthrough): per instance both are feedthrough and
    wait for each other; per variable ``ctrl.f`` reads ``cart.y`` and nothing reads ``cart.a``: no loop."""
    cart = FakeInstance("cart", ["f"], ["y", "a"], {"y": (), "a": ("f",)},
                        step=lambda v, h: {"y": v["y"] + h * v["v"], "v": v["v"] + h * v["f"]},
                        compute=lambda v: {"a": v["f"]})
    cart.values.update(y=1.0, v=0.0)
    ctrl = FakeInstance("ctrl", ["y"], ["f"], True, compute=lambda v: {"f": -gain * v["y"]})
    return {"cart": cart, "ctrl": ctrl}, [Connection("cart", "y", "ctrl", "y"), Connection("ctrl", "f", "cart", "f")]


def test_a_partly_feedthrough_instance_in_a_closed_loop_is_no_algebraic_loop():
    """Judged per variable (ModelStructure's dependencies per output): the cart is read first for the controller,
    and again once its force is set, so the acceleration observed is the force of the same instant."""
    instances, conns = _partly_feedthrough()
    wiring = Master(instances, conns).wiring
    calls = [(instance.name, function) for _, function, instance in wiring.propagation()]
    assert calls == [("cart", "get"), ("ctrl", "set"), ("ctrl", "get"), ("cart", "set"), ("cart", "get")]
    rec = ArrayRecorder()
    Master(instances, conns).run(0.0, 0.5, 0.1, [rec])
    c = rec.columns()
    assert list(c["cart.a"]) == list(c["ctrl.f"]) == [-2.0 * y for y in c["cart.y"]]
    y, v = [1.0], 0.0
    for _ in range(5):  # Gauss-Seidel: each step with the force of its start
        y, v = y + [y[-1] + 0.1 * v], v + 0.1 * (-2.0 * y[-1])
    assert list(c["cart.y"]) == pytest.approx(y, rel=1e-15)


def test_a_loop_through_the_feedthrough_output_is_found_and_named_along_its_variables():
    """The same cart with its acceleration fed back into the controller (a second input): now a chain of direct
    feedthrough closes, cart.f -> cart.a -> ctrl.a -> ctrl.f -> cart.f, and Gauss-Seidel refuses it."""
    instances, conns = _partly_feedthrough()
    ctrl = FakeInstance("ctrl", ["y", "a"], ["f"], True, compute=lambda v: {"f": -2.0 * v["y"] - 0.1 * v["a"]})
    instances["ctrl"] = ctrl
    conns = conns + [Connection("cart", "a", "ctrl", "a")]
    with pytest.raises(AlgebraicLoop, match=r"^algebraic loop through direct-feedthrough instances: cart, ctrl "
                                            r"\((\S+ -> ){4}\S+\)$") as loop:
        Master(instances, conns, "gauss-seidel")
    cycle = loop.value.path
    assert cycle[0] == cycle[-1] and sorted(cycle[:-1]) == ["cart.a", "cart.f", "ctrl.a", "ctrl.f"]
    assert find_loop({"cart": instances["cart"].dependencies, "ctrl": ctrl.dependencies}, conns[:2]) is None
    # iterative Jacobi settles it: f = -2 y - 0.1 f, so f = -2 y / 1.1
    rec = ArrayRecorder()
    Master(instances, conns, IterativeJacobi(tolerance=1e-15)).run(0.0, 0.1, 0.1, [rec])
    assert rec.columns()["ctrl.f"][0] == pytest.approx(-2.0 / 1.1, rel=1e-12)


def test_whole_instance_calls_that_cannot_order_a_loop_free_system_are_refused_in_one_line():
    """Two channels of one instance (s.o1 reads s.i1, s.o2 reads s.i2) with a feedthrough instance between them:
    no loop of variables, but setting s's inputs in one call would need a's output before s is read."""
    s = FakeInstance("s", ["i1", "i2"], ["o1", "o2"], {"o1": ("i1",), "o2": ("i2",)})
    a = FakeInstance("a", ["i"], ["o"], True)
    src = FakeInstance("src", [], ["o"], False)
    conns = [Connection("src", "o", "s", "i1"), Connection("s", "o1", "a", "i"), Connection("a", "o", "s", "i2")]
    with pytest.raises(AlgebraicLoop, match=r"^algebraic loop through direct-feedthrough instances: a, s; no loop of "
                                            r"variables, but an exchange of whole-instance calls"):
        Master({"src": src, "s": s, "a": a}, conns, "gauss-seidel")
    Master({"src": src, "s": s, "a": a}, conns, "jacobi", initial_exchange=False).run(0.0, 0.2, 0.1)  # as it is


@pytest.mark.parametrize("conn, message", [
    (Connection("nope", "y", "ctrl", "y"), "unknown instance 'nope'"),
    (Connection("integ", "u", "ctrl", "y"), "integ.u is not an output"),
    (Connection("integ", "y", "ctrl", "u"), "ctrl.u is not an input"),
])
def test_bad_connections_are_named(conn, message):
    """The master checks connections with the one check that systems use (same errors, same words)."""
    instances, _ = _loop()
    with pytest.raises(ValueError, match=message):
        Master(instances, [conn])


def test_unknown_mode_is_refused():
    instances, conns = _loop()
    with pytest.raises(ValueError, match="master algorithm must be one of gauss-seidel, jacobi, iterative-jacobi, "
                                         "got 'euler'"):
        Master(instances, conns, "euler")


def test_iterative_jacobi_reaches_gauss_seidels_values_where_there_is_no_loop():
    """Repeating the Jacobi exchange until nothing changes gives Gauss-Seidel's consistent inputs, exactly."""
    results = {}
    for mode in ("gauss-seidel", "iterative-jacobi"):
        instances, conns = _loop(gain=3.0)
        instances["integ"].values["y"] = 1.0
        rec = ArrayRecorder()
        Master(instances, conns, mode).run(0.0, 1.0, 0.1, [rec])
        results[mode] = rec.columns()
    for name in ("integ.y", "ctrl.u"):
        assert list(results["iterative-jacobi"][name]) == list(results["gauss-seidel"][name])


def _algebraic_loop(gain):
    """Two feedthrough instances in a loop: a.o = gain b.o + 1 and b.o = gain a.o."""
    a = FakeInstance("a", ["i"], ["o"], True, compute=lambda v: {"o": gain * v["i"] + 1.0})
    b = FakeInstance("b", ["i"], ["o"], True, compute=lambda v: {"o": gain * v["i"]})
    return {"a": a, "b": b}, [Connection("a", "o", "b", "i"), Connection("b", "o", "a", "i")]


def test_iterative_jacobi_solves_an_algebraic_loop_that_gauss_seidel_refuses():
    """With gain 1/2 the loop is a contraction with the fixed point a.o = 1/(1 - 1/4) = 4/3, b.o = 2/3."""
    instances, conns = _algebraic_loop(0.5)
    with pytest.raises(ValueError, match="algebraic loop through direct-feedthrough instances: a, b"):
        Master(instances, conns, "gauss-seidel")
    rec = ArrayRecorder()
    Master(instances, conns, IterativeJacobi(tolerance=1e-14)).run(0.0, 0.2, 0.1, [rec])
    columns = rec.columns()
    assert list(columns["a.o"]) == pytest.approx([4 / 3] * 3, abs=1e-12)
    assert list(columns["b.o"]) == pytest.approx([2 / 3] * 3, abs=1e-12)


def test_iterative_jacobi_names_a_loop_without_fixed_point():
    instances, conns = _algebraic_loop(2.0)  # each exchange doubles the change: diverges
    with pytest.raises(FmiError, match=r"^master: iterative-jacobi exchange returned error at t=0 s: no fixed "
                                       r"point within 100 exchanges: a.o still changed by"):
        Master(instances, conns, "iterative-jacobi").run(0.0, 0.2, 0.1)


def test_a_new_algorithm_is_one_class_and_one_registration():
    """The seam: a subclass registered by name runs through the master like the built-in ones."""
    from crane_fmu.cosim import algorithms

    class EveryOther(algorithms.Jacobi):
        name = "test-every-other"  # Jacobi, but the exchange only at every second point

        def bind(self, wiring):
            super().bind(wiring)
            self._count = 0

        def exchange(self, time):
            self._count += 1
            if self._count % 2:
                super().exchange(time)

    algorithms.register(EveryOther)
    try:
        instances, conns = _loop()
        instances["integ"].values["y"] = 1.0
        rec = ArrayRecorder()
        Master(instances, conns, "test-every-other").run(0.0, 0.4, 0.1, [rec])
        assert isinstance(Master(*_loop(), "test-every-other").algorithm, Algorithm)
        # the integrator is fed u = -1 until the exchange at t = 0.2 brings it y = 0.8, read back at t = 0.4
        assert list(rec.columns()["ctrl.u"]) == pytest.approx([-1.0, -1.0, -1.0, -1.0, -0.8], abs=1e-15)
        # observers see the outputs read at the last exchange; the integrator itself moved every step
        assert list(rec.columns()["integ.y"]) == pytest.approx([1.0, 1.0, 0.8, 0.8, 0.6], abs=1e-15)
    finally:
        del ALGORITHMS["test-every-other"]


@pytest.mark.parametrize("start, stop, step, message", [
    (0.0, 1.0, 0.0, "step must be > 0, got 0.0"),
    (0.0, 1.0, -0.1, "step must be > 0"),
    (0.0, 1.0, 0.3, "must divide the interval"),
    (1.0, 1.0, 0.1, "stop time must be > start time"),
])
def test_communication_points_reject_bad_grids(start, stop, step, message):
    with pytest.raises(ValueError, match=message):
        communication_points(start, stop, step)


def test_communication_points_tolerate_rounding():
    assert communication_points(0.0, 20.0, 1e-3) == 20000
    assert communication_points(0.0, 0.3, 0.1) == 3


def test_cosim_names_nothing_of_the_crane():
    """crane_fmu.cosim is a general co-simulation library: no crane instance, variable or FMU in it."""
    import re
    from pathlib import Path

    import crane_fmu.cosim

    words = re.compile(r"plant|controller|crane(?!_fmu)|trolley|theta|payload|hook|backstepping", re.I)
    for path in Path(crane_fmu.cosim.__file__).parent.glob("*.py"):
        found = words.findall(path.read_text())
        assert not found, f"{path.name} names {found}"


def test_csv_recorder_keeps_the_rows_of_a_run_cut_short(tmp_path):
    from crane_fmu.cosim.recorder import CsvRecorder, read_csv

    path = tmp_path / "cut.csv"
    path.write_text("an earlier result\n")
    recorder = CsvRecorder(path)
    recorder.start(["a.y"])
    for k in range(3):
        recorder.observe(0.5 * k, _values([k + 0.25]))
    assert path.read_text() == "an earlier result\n"  # nothing replaced before close
    recorder.close(reason="a: fmi2DoStep returned discard at t=1 s")
    cut = tmp_path / "cut.cut-short.csv"  # beside the earlier result, which is left as it was
    assert recorder.written == str(cut) and path.read_text() == "an earlier result\n"
    lines = cut.read_text().splitlines()
    assert lines == ["time,a.y", "0,0.25", "0.5,1.25", "1,2.25",
                     "# run cut short: a: fmi2DoStep returned discard at t=1 s"]
    assert list(read_csv(cut)["a.y"]) == [0.25, 1.25, 2.25]
    assert not list(tmp_path.glob("*.partial"))


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".mat"])
def test_a_run_cut_short_never_replaces_an_earlier_result(tmp_path, suffix):
    """Whatever the format, the named file keeps only complete runs; the cut-short one goes beside it."""
    from crane_fmu.cosim.recorder import read_result, recorder_for

    path = tmp_path / f"run{suffix}"
    path.write_bytes(b"a good earlier result")
    recorder = recorder_for(path)
    recorder.start(["a.y"])
    for k in range(3):
        recorder.observe(0.5 * k, _values([k + 0.25]))
    recorder.close(reason="interrupted")
    assert path.read_bytes() == b"a good earlier result"
    assert list(read_result(tmp_path / f"run.cut-short{suffix}")["a.y"]) == [0.25, 1.25, 2.25]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([path.name, f"run.cut-short{suffix}"])


def test_a_chunk_whose_thread_never_began_is_written_once(tmp_path):
    """Ctrl-C inside Thread.start(): the chunk's thread may never run; the next wait writes the chunk itself."""
    import threading

    from crane_fmu.cosim.recorder import CsvRecorder, read_csv

    recorder = CsvRecorder(tmp_path / "run.csv")
    recorder.CHUNK_ROWS = 2
    started = threading.Thread.start
    threading.Thread.start = lambda self: None  # the thread object exists, its start never happened
    try:
        recorder.start(["a.y"])
        for k in range(3):
            recorder.observe(float(k), _values([float(k)]))
    finally:
        threading.Thread.start = started
    recorder.close()
    assert list(read_csv(tmp_path / "run.csv")["a.y"]) == [0.0, 1.0, 2.0]


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_streaming_recorders_write_chunks_in_order_in_the_background(tmp_path, suffix):
    from crane_fmu.cosim.recorder import read_result, recorder_for

    recorder = recorder_for(tmp_path / f"run{suffix}")
    recorder.CHUNK_ROWS = 3  # ten rows: three chunks written by the background thread, the last one by close
    recorder.start(["a.y", "a.z"])
    for k in range(10):
        recorder.observe(0.1 * k, _values([k / 3, -k / 7]))
    recorder.close()
    columns = read_result(tmp_path / f"run{suffix}")
    assert list(columns["time"]) == [0.1 * k for k in range(10)]
    assert list(columns["a.y"]) == [k / 3 for k in range(10)]
    assert list(columns["a.z"]) == [-k / 7 for k in range(10)]


def test_a_chunk_that_cannot_be_written_stops_the_run(tmp_path):
    from crane_fmu.cosim.recorder import CsvRecorder

    class DiskFull(CsvRecorder):
        CHUNK_ROWS = 2

        def _write(self, table):
            raise OSError(28, "No space left on device")

    recorder = DiskFull(tmp_path / "full.csv")
    recorder.start(["a.y"])
    recorder.observe(0.0, _values([1.0]))
    recorder.observe(0.1, _values([2.0]))  # the first chunk fails in the background
    with pytest.raises(OSError, match="No space left on device"):
        for k in range(2, 4):  # the second full chunk waits for the first and reports its error
            recorder.observe(0.1 * k, _values([1.0]))
    assert not (tmp_path / "full.csv").exists()


def _values(values):
    buffer = (ctypes.c_double * len(values))(*values)
    return memoryview(buffer).cast("B").cast("d")
