"""Bad input to the built FMUs: every refusal is an FMI error status with a message naming the rule."""

import math
import subprocess
import sys
import textwrap

import pytest
from fmu_kinds import FMU_KINDS

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
    import atexit, ctypes, math, shutil, sys
    from hypothesis import given, settings, strategies as st, HealthCheck
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
    from fmpy.logging import addLoggerProxy

    path, examples = sys.argv[1], int(sys.argv[2])
    md = read_model_description(path)
    unzip = str(extract(path))
    atexit.register(shutil.rmtree, unzip, True)  # fmpy's folder in /tmp, removed when this process ends
    plant = md.coSimulation.modelIdentifier == "CranePlant"
    reals = [v for v in md.modelVariables if v.type == "Real"]
    strings = [v for v in md.modelVariables if v.type == "String"]
    libc = ctypes.CDLL(None)
    libc.calloc.restype = ctypes.c_void_p
    libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
    libc.free.argtypes = [ctypes.c_void_p]
    messages = []  # (status, text) of every message the FMU logs
    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, cat, msg: messages.append((status, msg)))
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(libc.calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(libc.free)
    addLoggerProxy(ctypes.byref(cb))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="fuzz")
    dll = fmu.dll

    # Random call sequences, each call classified before it is made by a shadow of the FMI 2.0 state
    # machine (section 4.2.4), with the one status its class allows:
    #   valid: allowed in the state, good values: OK;  wrong_state: error, the state unchanged;
    #   bad_value: a non-finite input, a NaN or unknown parameter judged when initialisation ends, a step
    #     that is not > 0 and finite (or, for the plant, needs over 10^7 sub-steps), a value of the wrong
    #     type: error;  long_step: 0.5 or 1 s: OK;
    #   diverging (plant): u = 1e300 m/s2 over 1 s overflows the state: discard;
    #   warning (plant): the hoist at 100 m/s2 reaches a cable limit (0.8 or 1.2 m) within 1 s: OK, with a
    #     warning message.
    # Every status from discard on comes with a message of that level at least, every OK without one.
    # Plant inputs are kept moderate (|u|, |F| <= 10, hoist only by the warning call), so that only the
    # diverging call diverges; parameters are set to NaN or to their start value.
    INS, INI, STP, DSC, TRM, ERR = range(6)
    CHOICES = {"b3_form": ("derived", "printed"), "shaper": ("zv", "zvd", "ei", "none")}  # README's tables
    inputs = [v for v in reals if v.causality == "input" and not (plant and v.name == "hoist")]
    parameters = [v for v in reals if v.causality == "parameter" and v.name not in ("l1_min", "l1_max")]
    outputs = [v for v in reals if v.causality == "output"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    moderate = st.floats(-10, 10)
    non_finite = st.sampled_from([math.nan, math.inf, -math.inf])
    operations = st.one_of(
        st.tuples(st.just("set_input"), st.sampled_from(inputs or outputs), st.one_of(moderate, non_finite)),
        st.tuples(st.just("set_parameter"), st.sampled_from(parameters), st.booleans()),
        st.tuples(st.just("set_output"), st.sampled_from(outputs)),
        st.tuples(st.just("get_real"), st.sampled_from(reals + strings)),
        st.tuples(st.just("set_string"), st.sampled_from(strings or reals), st.text(max_size=12)),
        st.tuples(st.just("do_step"), st.sampled_from([1e-3, 0.01, 0.1, 0.5, 1.0, 0.0, -1e-3, math.nan,
                                                        math.inf, 1e300])),
        st.tuples(st.sampled_from(["setup", "enter", "exit", "reset", "terminate", "get_state", "status"])),
        st.just(("advance",)), st.just(("advance",)),  # twice: sessions get to step mode, and past it
        *[st.tuples(st.sampled_from(["diverge", "warning"]))] * (6 if plant else 0),  # the plant's own paths, often
    )
    counts = dict(valid=0, wrong_state=0, bad_value=0, long_step=0, diverging=0, warning=0)

    def real(value):
        return (ctypes.c_double * 1)(value)

    def ref(name_or_variable):
        v = name_or_variable
        return (ctypes.c_uint * 1)(vr[v] if isinstance(v, str) else v.valueReference)

    class Session:
        def __init__(self, c):
            self.c, self.mode, self.bad = c, INS, set()
            self.limits()

        def limits(self):  # the plant's hoist runs between 0.8 and 1.2 m
            if plant:
                self.expect(dll.fmi2SetReal(self.c, ref("l1_min"), 1, real(0.8)), 0, "valid")
                self.expect(dll.fmi2SetReal(self.c, ref("l1_max"), 1, real(1.2)), 0, "valid")

        def expect(self, status, expected, kind, level=None):
            seen = len(messages)
            new = messages[self.seen:] if hasattr(self, "seen") else []
            self.seen = seen
            assert status == expected, (kind, "expected", expected, "got", status, new)
            if status >= 2:
                assert any(level_ >= 2 for level_, _ in new), (kind, status, "without a message saying why")
            else:
                assert not any(level_ >= 2 for level_, _ in new), (kind, status, "with an error message", new)
            if level is not None:
                assert any(level_ == level for level_, _ in new), (kind, "without a message of level", level)
            counts[kind] += 1

        def refuse_unless(self, status, allowed):
            if self.mode in allowed:
                return True
            self.expect(status, 3, "wrong_state")
            return False

        def do(self, op):
            if op[0] == "advance":  # the call that moves the session on from its state
                op = {INS: ("enter",), INI: ("exit",), STP: ("do_step", 0.5)}.get(self.mode, ("reset",))
            kind, c, m = op[0], self.c, self.mode
            settable, gettable = (INS, INI, STP), (INI, STP, DSC, TRM, ERR)
            if kind == "set_input":
                variable, value = op[1], op[2]
                status = dll.fmi2SetReal(c, ref(variable), 1, real(value))
                if self.refuse_unless(status, settable):
                    bad = not math.isfinite(value) or variable.causality != "input"
                    self.expect(status, 3 if bad else 0, "bad_value" if bad else "valid")
                    self.mode = ERR if bad else m
            elif kind == "set_parameter":
                if m == STP:
                    return  # a fixed parameter is not the fuzzer's business after initialisation
                variable, nan = op[1], op[2]
                status = dll.fmi2SetReal(c, ref(variable), 1, real(math.nan if nan else float(variable.start)))
                if self.refuse_unless(status, settable):
                    self.expect(status, 0, "valid")
                    (self.bad.add if nan else self.bad.discard)(variable.name)
            elif kind == "set_output":
                status = dll.fmi2SetReal(c, ref(op[1]), 1, real(0.0))
                if self.refuse_unless(status, settable):
                    self.expect(status, 3, "bad_value")
                    self.mode = ERR
            elif kind == "set_string":
                if m == STP:
                    return
                variable, text = op[1], op[2].encode("utf-8", "replace").replace(b"\\0", b"")
                status = dll.fmi2SetString(c, ref(variable), 1, (ctypes.c_char_p * 1)(text))
                if self.refuse_unless(status, settable):
                    if variable.type != "String":
                        self.expect(status, 3, "bad_value")
                        self.mode = ERR
                    else:
                        self.expect(status, 0, "valid")
                        good = text.decode() in CHOICES[variable.name]
                        (self.bad.discard if good else self.bad.add)(variable.name)
            elif kind == "get_real":
                variable = op[1]
                status = dll.fmi2GetReal(c, ref(variable), 1, real(0.0))
                if self.refuse_unless(status, gettable):
                    # a String is not a Real; a calculated variable (an output, a Model Exchange FMU's states,
                    # derivatives and event indicators) is computed from the parameters: with a bad one set,
                    # before the initialisation ended, that fails
                    calculated = variable.causality == "output" or variable.initial == "calculated"
                    bad = variable.type != "Real" or (calculated and self.bad and m in (INI, ERR))
                    self.expect(status, 3 if bad else 0, "bad_value" if bad else "valid")
                    self.mode = ERR if bad else m
            elif kind == "do_step":
                h = op[1]
                status = dll.fmi2DoStep(c, ctypes.c_double(0.0), ctypes.c_double(h), 1)
                if self.refuse_unless(status, (STP,)):
                    bad = not (0 < h < math.inf) or (plant and h > 1e4)
                    self.expect(status, 3 if bad else 0, "bad_value" if bad else "long_step" if h >= 0.5 else "valid")
                    self.mode = ERR if bad else STP
            elif kind == "setup":
                status = dll.fmi2SetupExperiment(c, 0, ctypes.c_double(0), ctypes.c_double(0), 0, ctypes.c_double(0))
                if self.refuse_unless(status, (INS,)):
                    self.expect(status, 0, "valid")
            elif kind == "enter":
                if self.refuse_unless(dll.fmi2EnterInitializationMode(c), (INS,)):
                    self.expect(0, 0, "valid")
                    self.mode = INI
            elif kind == "exit":
                status = dll.fmi2ExitInitializationMode(c)
                if self.refuse_unless(status, (INI,)):
                    self.expect(status, 3 if self.bad else 0, "bad_value" if self.bad else "valid")
                    self.mode = ERR if self.bad else STP
            elif kind == "reset":
                self.expect(dll.fmi2Reset(c), 0, "valid")
                self.mode, self.bad = INS, set()
                self.limits()
            elif kind == "terminate":
                status = dll.fmi2Terminate(c)
                if self.refuse_unless(status, (STP, DSC)):
                    self.expect(status, 0, "valid")
                    self.mode = TRM
            elif kind == "get_state":  # get, serialise, set back and free a state: allowed in every state
                state, size = ctypes.c_void_p(), ctypes.c_size_t()
                self.expect(dll.fmi2GetFMUstate(c, ctypes.byref(state)), 0, "valid")
                self.expect(dll.fmi2SerializedFMUstateSize(c, state, ctypes.byref(size)), 0, "valid")
                self.expect(dll.fmi2SetFMUstate(c, state), 0, "valid")
                self.expect(dll.fmi2FreeFMUstate(c, ctypes.byref(state)), 0, "valid")
            elif kind == "status":
                status = dll.fmi2GetRealStatus(c, 2, ctypes.byref(ctypes.c_double()))  # fmi2LastSuccessfulTime
                if self.refuse_unless(status, (STP, DSC, TRM)):
                    self.expect(status, 0, "valid")
            elif kind == "diverge":
                if m == STP:
                    self.expect(dll.fmi2SetReal(c, ref("u"), 1, real(1e300)), 0, "valid")
                status = dll.fmi2DoStep(c, ctypes.c_double(0.0), ctypes.c_double(1.0), 1)
                if self.refuse_unless(status, (STP,)):
                    self.expect(status, 2, "diverging")
                    self.mode = DSC
            elif kind == "warning":
                if m == STP:
                    l1 = real(0.0)
                    self.expect(dll.fmi2GetReal(c, ref("l1_now"), 1, l1), 0, "valid")
                    self.expect(dll.fmi2SetReal(c, ref("hoist"), 1, real(-100.0 if l1[0] >= 1.0 else 100.0)), 0,
                                "valid")
                status = dll.fmi2DoStep(c, ctypes.c_double(0.0), ctypes.c_double(1.0), 1)
                if self.refuse_unless(status, (STP,)):
                    self.expect(status, 0, "warning", level=1)

    @settings(max_examples=examples, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
    @given(st.booleans(), st.lists(operations, max_size=25))
    def run(started, ops):  # started: the session begins in step mode (initialisation done)
        c = dll.fmi2Instantiate(b"fuzz", 1, md.guid.encode(), ("file://" + unzip + "/resources").encode(),
                                ctypes.byref(cb), 0, 0)
        assert c
        try:
            session = Session(c)
            session.seen = len(messages)
            for op in [("advance",), ("advance",)] * started + ops:
                session.do(op)
        finally:
            dll.fmi2FreeInstance(c)

    run()
    print("classes", " ".join(f"{k}={v}" for k, v in counts.items()))
""")


FUZZ_MINIMUM = 10  # calls per class and FMU: every path taken several times, not once by luck


@pytest.mark.parametrize("name", ["CranePlant", "BacksteppingController", "TrajectoryPlanner"])
@pytest.mark.parametrize("kind", FMU_KINDS)
def test_random_fmi_call_sequences_get_the_status_their_class_requires(fmu_kinds, kind, name, tmp_path):
    """Hypothesis drives FMI 2.0 call sequences through fmpy's binding in a subprocess (so that a crash is a
    failed test, not a dead run); each call must get the one status its class allows (see FUZZ). Discards
    and warnings come only from the plant: the controller and the planner cannot diverge or warn."""
    pytest.importorskip("hypothesis")
    proc = subprocess.run([sys.executable, "-c", FUZZ, str(fmu_kinds[kind][2] / f"{name}.fmu"), "300"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"host died or failed (status {proc.returncode}): {proc.stderr[-3000:]}"
    words = proc.stdout.split()
    assert words[0] == "classes", proc.stdout
    counts = {k: int(v) for k, v in (item.split("=") for item in words[1:])}
    print(f"FMI 2.0 {kind} {name}:", counts)
    required = list(counts) if name == "CranePlant" else ["valid", "wrong_state", "bad_value", "long_step"]
    assert all(counts[k] >= FUZZ_MINIMUM for k in required), (f"fewer than {FUZZ_MINIMUM} calls in a class", counts)
