"""Bad input to the built FMUs: every refusal is an FMI error status with a message naming the rule."""

import math
import subprocess
import sys
import textwrap

import pytest

from crane_fmu.cli import main
from crane_fmu.cosim import FmiError, open_instance, simulate
from crane_fmu.cosim.fmi2 import Fmi2Instance


def _initialise(path, values):
    inst = open_instance(path, "fmu")
    inst.setup(0.0)
    for name, value in values.items():
        inst.set(name, value)
    inst.enter_initialization()
    return inst


@pytest.mark.parametrize("fmu, values, message", [
    ("plant", {"m1": 0.0}, "m1 must be > 0 and finite, got 0.0"),
    ("plant", {"m2": -1.0}, "m2 must be >= 0 and finite, got -1.0"),
    ("plant", {"l1": -1.0}, "l1 must be > 0 and finite, got -1.0"),
    ("plant", {"l2": math.inf}, "l2 must be > 0 and finite, got inf"),
    ("plant", {"g": math.nan}, "g must be > 0 and finite, got nan"),
    ("plant", {"max_substep": 0.0}, "max_substep must be > 0 and finite, got 0.0"),
    ("controller", {"K2_theta2": math.nan}, "K2_theta2 must be finite, got nan"),
    ("controller", {"w_theta1": -2.0}, "w_theta1 must be >= 0 and finite, got -2.0"),
    ("controller", {"w_x": 0.0}, "w_x must be > 0 (b'Wb must not vanish), got 0.0"),
    ("controller", {"b3_form": "guessed"}, "b3_form must be one of derived, printed, got 'guessed'"),
    ("controller", {"l1": 0.0}, "l1 must be > 0 and finite, got 0.0"),
])
def test_invalid_parameters_fail_initialisation_with_the_rule(crane_fmus, fmu, values, message):
    inst = _initialise(crane_fmus[fmu], values)
    try:
        with pytest.raises(FmiError) as err:
            inst.exit_initialization()
        assert (err.value.function, err.value.status) == ("fmi2ExitInitializationMode", "error")
        assert err.value.messages[-1] == f"fmi2ExitInitializationMode: {message}"
        assert str(err.value) == f"fmu: fmi2ExitInitializationMode returned error at t=0 s: {message}"
        assert "fmi2ExitInitializationMode" in str(err.value.__cause__)  # fmpy's exception is kept as the cause
    finally:
        inst.free()


@pytest.mark.parametrize("fmu, name, value", [
    ("plant", "u", math.nan), ("plant", "u", -math.inf),
    ("controller", "theta1", math.inf), ("controller", "dx", math.nan),
])
def test_non_finite_inputs_are_refused(crane_fmus, fmu, name, value):
    inst = _initialise(crane_fmus[fmu], {})
    try:
        inst.exit_initialization()
        with pytest.raises(FmiError, match=f"input {name} must be finite, got {value!r}"):
            inst.set(name, value)
        assert inst.get(name) == 0.0  # the refused value was not taken
    finally:
        inst.free()


@pytest.mark.parametrize("fmu, name, message", [
    ("plant", "x", "x is an output of CranePlant; only parameters and inputs can be set"),
    ("controller", "u", "u is an output of BacksteppingController; only parameters and inputs can be set"),
])
def test_setting_an_output_is_refused_with_its_name_and_the_rule(crane_fmus, fmu, name, message):
    """A host's mistake (or an SSV file naming plant.x): the variable and the rule, not a KeyError."""
    inst = _initialise(crane_fmus[fmu], {})
    try:
        with pytest.raises(FmiError) as err:
            inst.set(name, 1.0)
        assert err.value.messages[-1] == f"fmi2SetReal: {message}"
    finally:
        inst.free()


@pytest.mark.parametrize("step, message", [
    (0.0, "communication step must be > 0 and finite, got 0.0"),
    (-1e-3, "communication step must be > 0 and finite, got -0.001"),
    (1e300, "needs more than 10000000 RK4 sub-steps"),
])
def test_unusable_step_sizes_are_errors_not_hangs(crane_fmus, step, message):
    inst = _initialise(crane_fmus["plant"], {})
    try:
        inst.exit_initialization()
        with pytest.raises(FmiError, match=message):
            inst.do_step(0.0, step)
        with pytest.raises(FmiError, match=r"fmi2DoStep must not be called when the instance is in error state "
                                           r"\(after an fmi2Error; fmi2Reset or fmi2SetFMUstate recover it\)"):
            inst.do_step(0.0, 0.01)  # FMI 2.0: after fmi2Error the instance is in its error state
    finally:
        inst.free()


def test_a_diverging_plant_discards_the_step_with_its_reason(crane_fmus, connections):
    with pytest.raises(FmiError) as err:
        simulate(crane_fmus, connections, 5.0, 0.01)  # the paper's law diverges at h = 10 ms
    assert (err.value.instance, err.value.function, err.value.status) == ("plant", "fmi2DoStep", "discard")
    assert "plant state became non-finite in the step from t=" in str(err.value)


def test_every_instance_is_freed_after_a_failure(crane_fmus, connections, monkeypatch):
    freed = []
    original = Fmi2Instance.free
    monkeypatch.setattr(Fmi2Instance, "free", lambda self: (freed.append(self.name), original(self)))
    with pytest.raises(FmiError):
        simulate(crane_fmus, connections, 5.0, 0.01)
    assert sorted(freed) == ["controller", "plant"]


def test_same_run_twice_gives_bit_identical_csv(fmu_dir, tmp_path, capsys):
    runs = []
    for name in ("a.csv", "b.csv"):
        assert main(["simulate", "--fmu-dir", str(fmu_dir), "--stop-time", "3", "--out", str(tmp_path / name)]) == 0
        runs.append((tmp_path / name).read_bytes())
    assert runs[0] == runs[1] and len(runs[0]) > 100_000


FUZZ = textwrap.dedent("""
    import ctypes, math, sys
    from hypothesis import given, settings, strategies as st, HealthCheck
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
    from fmpy.logging import addLoggerProxy

    path, examples = sys.argv[1], int(sys.argv[2])
    md = read_model_description(path)
    unzip = str(extract(path))
    reals = [v for v in md.modelVariables if v.type == "Real"]
    strings = [v for v in md.modelVariables if v.type == "String"]
    libc = ctypes.CDLL(None)
    libc.calloc.restype = ctypes.c_void_p
    libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    messages = []
    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, cat, msg: messages.append(msg))
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(libc.calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(libc.free)
    addLoggerProxy(ctypes.byref(cb))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="fuzz")
    dll = fmu.dll
    numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from(
        [0.0, -0.0, 1e308, -1e308, 5e-324, -1.0, 1e-3, 0.01, 1.0]))
    operations = st.one_of(
        st.tuples(st.just("set_real"), st.sampled_from(reals), numbers),
        st.tuples(st.just("get_real"), st.sampled_from(reals + strings)),
        st.tuples(st.just("set_string"), st.sampled_from(strings or reals), st.text(max_size=12)),
        st.tuples(st.just("do_step"), numbers, numbers),
        st.tuples(st.sampled_from(["setup", "enter", "exit", "reset", "terminate", "get_state", "status"])),
    )
    calls = 0

    def check(status):
        global calls
        calls += 1
        assert status in (0, 1, 2, 3, 4), status

    @settings(max_examples=examples, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
    @given(st.lists(operations, max_size=25))
    def run(ops):
        c = dll.fmi2Instantiate(b"fuzz", 1, md.guid.encode(), ("file://" + unzip + "/resources").encode(),
                                ctypes.byref(cb), 0, 0)
        assert c
        try:
            for op in ops:
                kind = op[0]
                if kind == "set_real":
                    vr = (ctypes.c_uint * 1)(op[1].valueReference)
                    check(dll.fmi2SetReal(c, vr, 1, (ctypes.c_double * 1)(op[2])))
                elif kind == "get_real":
                    vr = (ctypes.c_uint * 1)(op[1].valueReference)
                    check(dll.fmi2GetReal(c, vr, 1, (ctypes.c_double * 1)()))
                elif kind == "set_string":
                    vr = (ctypes.c_uint * 1)(op[1].valueReference)
                    text = op[2].encode("utf-8", "replace").replace(b"\\0", b"")
                    check(dll.fmi2SetString(c, vr, 1, (ctypes.c_char_p * 1)(text)))
                elif kind == "do_step":
                    check(dll.fmi2DoStep(c, ctypes.c_double(op[1]), ctypes.c_double(op[2]), 1))
                elif kind == "setup":
                    check(dll.fmi2SetupExperiment(c, 0, ctypes.c_double(0), ctypes.c_double(0), 0,
                                                  ctypes.c_double(0)))
                elif kind == "enter":
                    check(dll.fmi2EnterInitializationMode(c))
                elif kind == "exit":
                    check(dll.fmi2ExitInitializationMode(c))
                elif kind == "reset":
                    check(dll.fmi2Reset(c))
                elif kind == "terminate":
                    check(dll.fmi2Terminate(c))
                elif kind == "get_state":  # get, serialise, set back and free a state
                    state = ctypes.c_void_p()
                    status = dll.fmi2GetFMUstate(c, ctypes.byref(state))
                    check(status)
                    if status == 0:
                        size = ctypes.c_size_t()
                        check(dll.fmi2SerializedFMUstateSize(c, state, ctypes.byref(size)))
                        check(dll.fmi2SetFMUstate(c, state))
                        check(dll.fmi2FreeFMUstate(c, ctypes.byref(state)))
                elif kind == "status":
                    value = ctypes.c_double()
                    check(dll.fmi2GetRealStatus(c, 2, ctypes.byref(value)))
        finally:
            dll.fmi2FreeInstance(c)

    run()

    # Sessions in a valid call order with bad values, long steps and diverging inputs: each kind of
    # call has one expected status, and the counts show that every path was taken.
    inputs = [v for v in reals if v.causality == "input"]
    parameters = [v for v in reals if v.causality == "parameter"]
    values = st.one_of(st.floats(-5, 5), st.sampled_from([1e6, -1e6, math.nan, math.inf, -math.inf]))
    steps = st.lists(st.tuples(st.sampled_from(inputs), values, st.sampled_from([1e-3, 0.01, 0.1, 0.5, 1.0])),
                     min_size=1, max_size=20)
    counts = dict(bad_parameter_refused=0, non_finite_input_refused=0, discarded=0, long_step_ok=0)

    def instantiate():
        c = dll.fmi2Instantiate(b"fuzz", 1, md.guid.encode(), ("file://" + unzip + "/resources").encode(),
                                ctypes.byref(cb), 0, 0)
        assert c
        return c

    @settings(max_examples=examples, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
    @given(st.one_of(st.none(), st.sampled_from(parameters)), steps)
    def session(nan_parameter, ops):
        c = instantiate()
        try:
            assert dll.fmi2SetupExperiment(c, 0, ctypes.c_double(0), ctypes.c_double(0), 0, ctypes.c_double(0)) == 0
            if nan_parameter is not None:
                vr = (ctypes.c_uint * 1)(nan_parameter.valueReference)
                assert dll.fmi2SetReal(c, vr, 1, (ctypes.c_double * 1)(math.nan)) == 0  # judged when init ends
            assert dll.fmi2EnterInitializationMode(c) == 0
            status = dll.fmi2ExitInitializationMode(c)
            if nan_parameter is not None:
                assert status == 3, (nan_parameter.name, status)  # fmi2Error
                counts["bad_parameter_refused"] += 1
                return
            assert status == 0
            t = 0.0
            for variable, value, step in ops:
                vr = (ctypes.c_uint * 1)(variable.valueReference)
                status = dll.fmi2SetReal(c, vr, 1, (ctypes.c_double * 1)(value))
                if not math.isfinite(value):
                    assert status == 3, (variable.name, value, status)
                    counts["non_finite_input_refused"] += 1
                    # now in the error state: no more steps, but reset recovers
                    assert dll.fmi2DoStep(c, ctypes.c_double(t), ctypes.c_double(step), 1) == 3
                    assert dll.fmi2Reset(c) == 0
                    return
                else:
                    assert status == 0, (variable.name, value, status)
                status = dll.fmi2DoStep(c, ctypes.c_double(t), ctypes.c_double(step), 1)
                assert status in (0, 2), status  # ok, or a diverged state discarded
                if status == 2:
                    counts["discarded"] += 1
                    return
                counts["long_step_ok"] += step >= 0.5
                t += step
        finally:
            dll.fmi2FreeInstance(c)

    session()
    print("survived", calls, "calls", len(messages), "messages", " ".join(f"{k}={v}" for k, v in counts.items()))
""")


@pytest.mark.parametrize("fmu", ["plant", "controller"])
def test_random_fmi_call_sequences_never_crash_or_hang_the_host(crane_fmus, fmu, tmp_path):
    pytest.importorskip("hypothesis")
    proc = subprocess.run([sys.executable, "-c", FUZZ, str(crane_fmus[fmu]), "300"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"host died or failed (status {proc.returncode}): {proc.stderr[-3000:]}"
    survived = proc.stdout.split()
    assert survived[0] == "survived" and int(survived[1]) > 1000, proc.stdout
    assert int(survived[3]) > 0  # refusals came with messages
    counts = dict(item.split("=") for item in survived[5:])
    paths = ["bad_parameter_refused", "non_finite_input_refused", "long_step_ok"] + (["discarded"] if fmu == "plant"
                                                                                      else [])
    for path in paths:  # every path was taken
        assert int(counts[path]) > 0, (path, proc.stdout)
