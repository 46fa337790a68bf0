"""Every argument check of the standard's get, set, step and state functions, FMI 2.0 and 3.0, on the Python FMUs
and the native components alike (issue 50, item 7: a class of bad call was no longer refused and no test made that
call): a NULL instance, NULL arrays, a value reference the FMU does not have, lengths that do not match (FMI 3.0),
a NULL or foreign FMU state, a call in the wrong state. Each is first made with good arguments on a fresh instance
(OK: the control), then with the bad one on another fresh instance: fmi*Error (3), and the process goes on.

The functions are called through ctypes as a C host calls them, without fmpy's checks in between.
"""

import ctypes
import zipfile
from ctypes import POINTER, byref, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CoSimulation,
)
from fmpy.fmi3 import FMU3Slave, fmi3IntermediateUpdateCallback, fmi3LogMessageCallback
from fmpy.logging import addLoggerProxy
from fmu_kinds import FMU_KINDS
from native_fmus import LOG, LOGGER, close, extracted, open_native

OK, ERROR = 0, 3
VR = POINTER(c_uint)
_LIBC = ctypes.CDLL(None)
_LIBC.calloc.restype, _LIBC.calloc.argtypes = c_void_p, [c_size_t, c_size_t]
_LIBC.free.argtypes = [c_void_p]


def _calloc(n, size):
    return _LIBC.calloc(n, size)


def _free(pointer):
    _LIBC.free(pointer)


def _fresh(folder, version, initialised=True):
    """A CranePlant instance (ended initialisation unless not ``initialised``): ``(fmu, dll, instance, vr)``."""
    path = folder / "CranePlant.fmu"
    fmu, vr, _, _ = open_native(path, version)
    if initialised:
        fmu.exitInitializationMode()
    return fmu, fmu.dll, c_void_p(fmu.component), vr


def _raw(dll, name, restype=c_int):
    function = getattr(dll, name)
    function.restype = restype
    function.argtypes = None
    return function


def _calls(version):
    """``{check: (good call, bad call)}``, each ``call(dll, instance, vr, other) -> status``; ``other`` is a second
    instance of the same FMU (for a foreign state)."""
    v = "fmi2" if version == 2 else "fmi3"
    get, set_ = (f"{v}GetReal", f"{v}SetReal") if version == 2 else (f"{v}GetFloat64", f"{v}SetFloat64")
    out = (c_double * 1)()

    def values(function, instance, refs, n, array, n_values=None):
        args = [instance, refs, c_size_t(n), array]
        if version == 3:
            args.append(c_size_t(n if n_values is None else n_values))
        return function(*args)

    def x(vr):
        return (c_uint * 1)(vr["x"])

    def u(vr):
        return (c_uint * 1)(vr["u"])

    def do_step(dll, instance):
        if version == 2:
            return _raw(dll, "fmi2DoStep")(instance, c_double(0.0), c_double(1e-3), c_int(1))
        flags = [ctypes.c_bool() for _ in range(3)]
        return _raw(dll, "fmi3DoStep")(instance, c_double(0.0), c_double(1e-3), ctypes.c_bool(True),
                                       *map(byref, flags), byref(c_double()))

    def get_state(dll, instance, where):
        return _raw(dll, f"{v}GetFMU{'state' if version == 2 else 'State'}")(instance, where)

    def set_state(dll, instance, state):
        return _raw(dll, f"{v}SetFMU{'state' if version == 2 else 'State'}")(instance, state)

    def foreign_state(dll, instance, vr, other):
        state = c_void_p()
        assert get_state(other.dll, c_void_p(other.component), byref(state)) == OK
        return set_state(dll, instance, state)

    def own_state(dll, instance, vr, other):
        state = c_void_p()
        assert get_state(dll, instance, byref(state)) == OK
        return set_state(dll, instance, state)

    checks = {
        "NULL instance": (lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, out),
                          lambda dll, c, vr, o: values(_raw(dll, get), None, x(vr), 1, out)),
        "NULL value references": (lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, out),
                                  lambda dll, c, vr, o: values(_raw(dll, get), c, None, 1, out)),
        "NULL values (get)": (lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, out),
                              lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, None)),
        "NULL values (set)": (lambda dll, c, vr, o: values(_raw(dll, set_), c, u(vr), 1, (c_double * 1)(0.5)),
                              lambda dll, c, vr, o: values(_raw(dll, set_), c, u(vr), 1, None)),
        "unknown value reference (get)": (lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, out),
                                          lambda dll, c, vr, o: values(_raw(dll, get), c, (c_uint * 1)(99999), 1,
                                                                       out)),
        "unknown value reference (set)": (
            lambda dll, c, vr, o: values(_raw(dll, set_), c, u(vr), 1, (c_double * 1)(0.5)),
            lambda dll, c, vr, o: values(_raw(dll, set_), c, (c_uint * 1)(99999), 1, (c_double * 1)(0.5))),
        "NULL state pointer": (lambda dll, c, vr, o: get_state(dll, c, byref(c_void_p())),
                               lambda dll, c, vr, o: get_state(dll, c, None)),
        "a foreign FMU state": (own_state, foreign_state),
        "a step in initialisation mode": (lambda dll, c, vr, o: do_step(dll, c), None),
    }
    if version == 3:
        checks["nValues != nValueReferences"] = (
            lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, out),
            lambda dll, c, vr, o: values(_raw(dll, get), c, x(vr), 1, (c_double * 2)(), n_values=2))
    return checks


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", list(FMU_KINDS))
def test_every_bad_argument_is_refused_and_the_good_one_taken(fmu_kinds, kind, version):
    folder = fmu_kinds[kind][version]
    read_model_description(str(folder / "CranePlant.fmu"))
    results = {}
    for check, (good, bad) in _calls(version).items():
        statuses = []
        for call, initialised in ((good, True), (bad, True) if bad else (good, False)):
            fmu, dll, instance, vr = _fresh(folder, version, initialised)
            other = _fresh(folder, version)[0] if check == "a foreign FMU state" else None
            try:
                statuses.append(call(dll, instance, vr, other))
            finally:
                for f in (fmu, other):
                    if f is not None:
                        try:
                            close(f)
                        except Exception:
                            f.freeInstance()
        results[check] = tuple(statuses)
    assert results == {check: (OK, ERROR) for check in results}


# ---- instantiation: every argument the standard's instantiate functions check --------------------------------------

# FMI 2.0's logger is variadic: fmpy's proxy formats the message for the tests' logger, which lives as long as the
# process (native_fmus.py says why); FMI 3.0's takes the message itself.
_MESSAGES = []
_CALLBACKS2 = fmi2CallbackFunctions(logger=LOGGER, allocateMemory=fmi2CallbackAllocateMemoryTYPE(_calloc),
                                    freeMemory=fmi2CallbackFreeMemoryTYPE(_free))
_LOG3 = fmi3LogMessageCallback(lambda env, status, category, message: _MESSAGES.append(message.decode()))
ANOTHER_BUILDS_TOKEN = "{00000000-0000-0000-0000-000000000000}"


def _instantiations(md, unzipped, version):
    """``{check: (made, refused)}``: whether the good call made an instance and the bad one (the same call with
    one argument wrong) made none (freed when made). fmi2Instantiate and fmi3InstantiateCoSimulation (and
    fmi3InstantiateModelExchange where the FMU has Model Exchange) through ctypes as a C host calls them."""
    if version == 2:
        LOG[0] = _MESSAGES
        addLoggerProxy(byref(_CALLBACKS2))
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName="c")
        location, token, callbacks = Path(unzipped, "resources").as_uri().encode(), md.guid.encode(), byref(_CALLBACKS2)

        def call(name=b"c", guid=token, where=location, callbacks=callbacks, kind=fmi2CoSimulation):
            return fmu.fmi2Instantiate(name, kind, guid, where, callbacks, False, False)

        free = fmu.fmi2FreeInstance
        bad = {"another build's GUID": {"guid": ANOTHER_BUILDS_TOKEN.encode()}, "NULL instance name": {"name": None},
               "NULL callback functions": {"callbacks": None}}
    else:
        fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipped,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="c")
        location, token = (str(Path(unzipped, "resources")) + "/").encode(), md.instantiationToken.encode()

        def call(name=b"c", guid=token, where=location, event_mode=False, model_exchange=False):
            if model_exchange:
                return fmu.fmi3InstantiateModelExchange(name, guid, where, False, False, None, _LOG3)
            return fmu.fmi3InstantiateCoSimulation(name, guid, where, False, False, event_mode, False, None, 0, None,
                                                   _LOG3, fmi3IntermediateUpdateCallback())

        free = fmu.fmi3FreeInstance
        bad = {"another build's token": {"guid": ANOTHER_BUILDS_TOKEN.encode()}, "NULL instance name": {"name": None},
               "event mode asked for (it has none)": {"event_mode": True}}
        if md.modelExchange is not None:
            bad["another build's token (Model Exchange)"] = {"guid": ANOTHER_BUILDS_TOKEN.encode(),
                                                              "model_exchange": True}
    results = {}
    try:
        for check, wrong in bad.items():
            made = []
            for arguments in ({k: v for k, v in wrong.items() if k == "model_exchange"}, wrong):
                instance = call(**arguments)
                made.append(bool(instance))
                if instance:
                    free(instance)
            results[check] = (made[0], not made[1])
    finally:
        fmu.freeLibrary()
    return results


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", list(FMU_KINDS))
def test_every_bad_instantiation_is_refused_and_the_good_one_made(fmu_kinds, kind, version, tmp_path):
    """Another build's GUID / instantiation token (a modelDescription.xml beside the wrong binary: the Python FMUs,
    whose runtime is shared, took any), a NULL instance name, NULL callbacks (FMI 2.0), an event mode the FMU does
    not have (FMI 3.0): no instance, and a refusal of the token says so in one message. Each is first made with
    the good arguments (an instance: the control). Every FMU of the kind's build, not only the plant."""
    folder = fmu_kinds[kind][version]
    paths = sorted(folder.glob("*.fmu"))
    assert len(paths) >= 5
    for path in paths:
        md = read_model_description(str(path))
        unzipped = tmp_path / path.stem
        with zipfile.ZipFile(path) as archive:
            archive.extractall(unzipped)
        _MESSAGES.clear()
        results = _instantiations(md, unzipped, version)
        assert results == {check: (True, True) for check in results}, path.name
        assert sum("not this FMU's" in m for m in _MESSAGES) == len([c for c in results if "another build" in c])


# ---- calling order: each function called in a mode the standard forbids it in --------------------------------------

# The stages an instance is brought to before the call, in the standard's state machine (FMI 2.0 section 4.2.4,
# FMI 3.0 section 4.2): after instantiation, in initialisation mode, stepping (initialisation ended), terminated.
STAGES = ("instantiated", "initialisation", "stepping", "terminated")


def _staged(folder, version, stage):
    """A fresh CranePlant instance brought to ``stage`` through fmpy: ``(fmu, dll, instance, vr)``."""
    md = read_model_description(str(folder / "CranePlant.fmu"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extracted(folder / "CranePlant.fmu")
    if version == 2:
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName="c")
        fmu.instantiate()
        if stage != "instantiated":
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
    else:
        fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipped,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="c")
        fmu.instantiate()
        if stage != "instantiated":
            fmu.enterInitializationMode(startTime=0.0)
    if stage in ("stepping", "terminated"):
        fmu.exitInitializationMode()
    if stage == "terminated":
        fmu.terminate()
    return fmu, fmu.dll, c_void_p(fmu.component), vr


def _ordered_calls(version):
    """``{check: (call, stage it is allowed in, stage the standard forbids it in)}``; ``call(dll, instance, vr)``."""
    v = "fmi2" if version == 2 else "fmi3"
    get, set_ = (f"{v}GetReal", f"{v}SetReal") if version == 2 else (f"{v}GetFloat64", f"{v}SetFloat64")

    def values(function, name, value=None):
        def call(dll, instance, vr):
            args = [instance, (c_uint * 1)(vr[name]), c_size_t(1), (c_double * 1)(0.0 if value is None else value)]
            if version == 3:
                args.append(c_size_t(1))
            return _raw(dll, function)(*args)
        return call

    def do_step(dll, instance, vr):
        if version == 2:
            return _raw(dll, "fmi2DoStep")(instance, c_double(0.0), c_double(1e-3), c_int(1))
        flags = [ctypes.c_bool() for _ in range(3)]
        return _raw(dll, "fmi3DoStep")(instance, c_double(0.0), c_double(1e-3), ctypes.c_bool(True),
                                       *map(byref, flags), byref(c_double()))

    def enter(dll, instance, vr):
        if version == 2:
            return _raw(dll, "fmi2EnterInitializationMode")(instance)
        return _raw(dll, "fmi3EnterInitializationMode")(instance, ctypes.c_bool(False), c_double(0.0),
                                                        c_double(0.0), ctypes.c_bool(False), c_double(0.0))

    def plain(name):
        return lambda dll, instance, vr: _raw(dll, f"{v}{name}")(instance)

    checks = {
        # m1: causality parameter, variability fixed: settable until initialisation ends, never after
        "a fixed parameter set once initialisation has ended": (values(set_, "m1", 1.5), "initialisation",
                                                                "stepping"),
        "an input set once terminated": (values(set_, "u", 0.5), "stepping", "terminated"),
        "a value got before initialisation": (values(get, "x"), "initialisation", "instantiated"),
        "a step before initialisation has ended": (do_step, "stepping", "initialisation"),
        "a step once terminated": (do_step, "stepping", "terminated"),
        "initialisation entered twice": (enter, "instantiated", "initialisation"),
        "initialisation entered once stepping": (enter, "instantiated", "stepping"),
        "initialisation ended twice": (plain("ExitInitializationMode"), "initialisation", "stepping"),
        "terminate during initialisation": (plain("Terminate"), "stepping", "initialisation"),
        "terminate twice": (plain("Terminate"), "stepping", "terminated"),
    }
    if version == 2:
        checks["setupExperiment in initialisation mode"] = (
            lambda dll, instance, vr: _raw(dll, "fmi2SetupExperiment")(instance, c_int(0), c_double(0.0),
                                                                       c_double(0.0), c_int(0), c_double(0.0)),
            "instantiated", "initialisation")
    return checks


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", list(FMU_KINDS))
def test_every_call_in_a_mode_the_standard_forbids_is_refused_and_in_its_own_mode_taken(fmu_kinds, kind, version):
    """The calling order, a class of check apart from the arguments above: a fixed parameter set after
    initialisation, an input set or a step taken once terminated, a value got before initialisation, a step before
    it ends, initialisation entered or ended twice, terminate in initialisation or twice (FMI 2.0: setupExperiment
    in initialisation mode). Each call is made on a fresh instance in a mode the standard allows it in (OK: the
    control), then on another fresh instance in a mode it forbids it in: fmi*Error (3), and the process goes on."""
    folder = fmu_kinds[kind][version]
    results = {}
    for check, (call, allowed, forbidden) in _ordered_calls(version).items():
        statuses = []
        for stage in (allowed, forbidden):
            fmu, dll, instance, vr = _staged(folder, version, stage)
            try:
                statuses.append(call(dll, instance, vr))
            finally:
                fmu.freeInstance()
        results[check] = tuple(statuses)
    assert results == {check: (OK, ERROR) for check in results}


# ---- Model Exchange: the arrays and pointers of its own functions ---------------------------------------------------


def _model_exchange(folder, version, continuous_time, model_exchange=True):
    """A fresh native CranePlant instance after initialisation (Model Exchange: in event mode, or in continuous-time
    mode): ``(fmu, dll, instance, numbers of states and of event indicators)``."""
    path = folder / "CranePlant.fmu"
    md = read_model_description(str(path))
    fmu = open_native(path, version, model_exchange=model_exchange)[0]
    fmu.exitInitializationMode()
    if model_exchange and continuous_time:
        fmu.enterContinuousTimeMode()
    return fmu, fmu.dll, c_void_p(fmu.component), len(md.derivatives), md.numberOfEventIndicators


def _model_exchange_calls(version):
    """``{check: (good call, bad call, continuous-time mode, bad on a co-simulation instance)}``, each call
    ``call(dll, instance, n_states, n_indicators)``."""
    v = "fmi2" if version == 2 else "fmi3"
    names = {"derivatives": f"{v}GetDerivatives" if version == 2 else "fmi3GetContinuousStateDerivatives",
             "indicators": f"{v}GetEventIndicators", "states": f"{v}GetContinuousStates",
             "completed": f"{v}CompletedIntegratorStep"}
    flag = c_int if version == 2 else ctypes.c_bool

    def array(name, length=lambda nx, ni: nx, null=False, short=0):
        def call(dll, instance, nx, ni):
            n = length(nx, ni) + short
            return _raw(dll, names[name])(instance, None if null else (c_double * max(n, 1))(), c_size_t(n))
        return call

    def completed(null):
        def call(dll, instance, nx, ni):
            event, terminate = flag(), flag()
            return _raw(dll, names["completed"])(instance, flag(1), None if null else byref(event),
                                                 None if null else byref(terminate))
        return call

    def indicators(nx, ni):
        return ni

    return {
        "derivatives: an array one shorter than the states": (array("derivatives"), array("derivatives", short=-1),
                                                              False, False),
        "derivatives: an array one longer than the states": (array("derivatives"), array("derivatives", short=1),
                                                             False, False),
        "event indicators: an array one shorter": (array("indicators", indicators),
                                                   array("indicators", indicators, short=-1), False, False),
        "continuous states: a NULL array": (array("states"), array("states", null=True), False, False),
        "completed integrator step: NULL output pointers": (completed(False), completed(True), True, False),
        "derivatives of a co-simulation instance": (array("derivatives"), array("derivatives"), False, True),
    }


@pytest.mark.parametrize("version", [2, 3])
def test_every_bad_model_exchange_array_or_pointer_is_refused_and_the_good_one_taken(fmu_kinds, version):
    """The Model Exchange functions' own checks, a third class (the native FMUs: the Python ones have no Model
    Exchange): an array of states or event indicators shorter or longer than the model's, a NULL array, NULL output
    pointers of CompletedIntegratorStep, a Model Exchange function called on a co-simulation instance. Each is first
    made with good arguments on a fresh Model Exchange instance (OK), then with the bad one on another: fmi*Error."""
    folder = fmu_kinds["native"][version]
    results = {}
    for check, (good, bad, continuous_time, on_co_simulation) in _model_exchange_calls(version).items():
        statuses = []
        for call, model_exchange in ((good, True), (bad, not on_co_simulation)):
            fmu, dll, instance, nx, ni = _model_exchange(folder, version, continuous_time, model_exchange)
            try:
                statuses.append(call(dll, instance, nx, ni))
            finally:
                fmu.freeInstance()
        results[check] = tuple(statuses)
    assert results == {check: (OK, ERROR) for check in results}


# ---- the String and Integer (Enumeration) functions -----------------------------------------------------------------

# (FMU, its variable of the type, a good value) per type
TYPED = {"String": ("BacksteppingController.fmu", "b3_form", b"printed"),
         "Integer": ("TrajectoryPlanner.fmu", "shaper", 2)}


def _typed_calls(version, kind):
    """``{check: (good call, bad call, initialised)}`` of the ``kind`` functions (String; Integer: FMI 2.0's
    fmi2*Integer, FMI 3.0's fmi3*Int64, which set an Enumeration), each ``call(dll, instance, vr, real)``: ``vr`` the
    variable's reference, ``real`` a Real's."""
    v = "fmi2" if version == 2 else "fmi3"
    suffix = kind if (kind == "String" or version == 2) else "Int64"
    get, set_ = f"{v}Get{suffix}", f"{v}Set{suffix}"
    item = ctypes.c_char_p if kind == "String" else (c_int if version == 2 else ctypes.c_int64)
    good = TYPED[kind][2]

    def call(function, instance=True, refs=True, values=True, setting=False, n_values=None):
        def made(dll, c, vr, real):
            array = (item * 1)(good) if setting else (item * 1)()
            args = [c if instance else None, (c_uint * 1)(vr if refs is True else refs) if refs else None,
                    c_size_t(1), array if values else None]
            if version == 3:
                args.append(c_size_t(1 if n_values is None else n_values))
            return _raw(dll, function)(*args)
        return made

    checks = {
        "NULL instance (get)": (call(get), call(get, instance=False), True),
        "NULL value references (get)": (call(get), call(get, refs=None), True),
        "NULL values (get)": (call(get), call(get, values=False), True),
        "NULL values (set)": (call(set_, setting=True), call(set_, values=False, setting=True), False),
        "unknown value reference (get)": (call(get), call(get, refs=99999), True),
        "unknown value reference (set)": (call(set_, setting=True), call(set_, refs=99999, setting=True), False),
        "a Real's value reference (get)": (call(get), lambda dll, c, vr, real: call(get, refs=real)(dll, c, vr, real),
                                           True),
        # the calling order: a fixed parameter set once initialisation has ended (in initialisation mode: taken)
        "a fixed parameter set once initialisation has ended": (call(set_, setting=True), call(set_, setting=True),
                                                                (False, True)),
    }
    if version == 3:
        checks["nValues != nValueReferences"] = (call(get), call(get, n_values=2), True)
    return checks


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", list(FMU_KINDS))
@pytest.mark.parametrize("typed", list(TYPED))
def test_every_bad_string_or_integer_argument_is_refused_and_the_good_one_taken(fmu_kinds, kind, version, typed):
    """The first test's argument checks for the String and Integer (Enumeration: FMI 3.0's Int64) get and set
    functions, on the FMUs that have such a variable (BacksteppingController's b3_form, TrajectoryPlanner's
    shaper): NULL instance, references or values, a reference the FMU does not have or of a Real, FMI 3.0's
    nValues; and the fixed parameter set once initialisation has ended. Each bad call against the good one on a
    fresh instance; a set in initialisation mode, a get after it. On main fmi2GetInteger took NULL values (status
    OK) and the Python FMUs took a String set after initialisation."""
    folder = fmu_kinds[kind][version]
    name, variable, _ = TYPED[typed]
    md = read_model_description(str(folder / name))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    real = next(v.valueReference for v in md.modelVariables if v.type in ("Real", "Float64"))
    results = {}
    for check, (good, bad, initialised) in _typed_calls(version, typed).items():
        statuses = []
        for call, ended in zip((good, bad), initialised if isinstance(initialised, tuple) else (initialised,) * 2):
            fmu = open_native(folder / name, version)[0]
            if ended:
                fmu.exitInitializationMode()
            try:
                statuses.append(call(fmu.dll, c_void_p(fmu.component), refs[variable], real))
            finally:
                fmu.freeInstance()
        results[check] = tuple(statuses)
    assert results == {check: (OK, ERROR) for check in results}


# ---- Boolean, FMI 3.0's other integer widths, SetTime, SetContinuousStates, the directional derivative -------------

# FMI 3.0's get/set functions of a type no FMU here has a variable of, with their C item type
WIDTHS = {"Int8": ctypes.c_int8, "UInt8": ctypes.c_uint8, "Int16": ctypes.c_int16, "UInt16": ctypes.c_uint16,
          "Int32": ctypes.c_int32, "UInt32": ctypes.c_uint32, "UInt64": ctypes.c_uint64, "Float32": ctypes.c_float}


def _untyped_calls(version):
    """``{check: (good call, bad call)}`` of the get/set functions of a type the plant has no variable of (Boolean;
    FMI 3.0: every integer width but Int64, and Float32), each ``call(dll, instance, vr)``: the good one asks for
    no value (nothing to do: OK), the bad one names an unknown reference, a Float64's (``x``), or no instance."""
    v = "fmi2" if version == 2 else "fmi3"
    types = {"Boolean": c_int if version == 2 else ctypes.c_bool}
    if version == 3:
        types.update(WIDTHS)

    def call(function, item, n=0, refs=None, instance=True):
        def made(dll, c, vr):
            array = (item * 1)()
            args = [c if instance else None, (c_uint * 1)(vr[refs] if isinstance(refs, str) else (refs or 0)),
                    c_size_t(n), array]
            if version == 3:
                args.append(c_size_t(n))
            return _raw(dll, function)(*args)
        return made

    checks = {}
    for type_, item in types.items():
        for what in ("Get", "Set"):
            name = f"{v}{what}{type_}"
            checks[f"{name}: an unknown value reference"] = (call(name, item), call(name, item, 1, 99999))
            checks[f"{name}: a Float64's value reference"] = (call(name, item), call(name, item, 1, "x"))
            checks[f"{name}: NULL instance"] = (call(name, item), call(name, item, instance=False))
    return checks


def _derivative_calls(version):
    """``{check: (good call, bad call)}`` of the directional derivative of the plant's ``x`` by its input ``u``
    (co-simulation, after initialisation), each ``call(dll, instance, vr)``: the bad one with one array NULL."""
    name = f"{'fmi2' if version == 2 else 'fmi3'}GetDirectionalDerivative"

    def call(null=None, instance=True):
        def made(dll, c, vr):
            arrays = {"unknowns": (c_uint * 1)(vr["x"]), "knowns": (c_uint * 1)(vr["u"]),
                      "seed": (c_double * 1)(1.0), "sensitivity": (c_double * 1)()}
            if null:
                arrays[null] = None
            one = c_size_t(1)
            args = [c if instance else None, arrays["unknowns"], one, arrays["knowns"], one, arrays["seed"]]
            args += [arrays["sensitivity"]] if version == 2 else [one, arrays["sensitivity"], one]
            return _raw(dll, name)(*args)
        return made

    checks = {f"{name}: NULL {array}": (call(), call(array)) for array in ("unknowns", "knowns", "seed", "sensitivity")}
    checks[f"{name}: NULL instance"] = (call(), call(instance=False))
    return checks


def _time_and_state_calls(version):
    """``{check: (good call, bad call, continuous-time mode, bad on a co-simulation instance)}`` of Model Exchange's
    SetTime and SetContinuousStates, each ``call(dll, instance, n_states)``; the states set are the instance's own."""
    v = "fmi2" if version == 2 else "fmi3"

    def set_time(time, instance=True):
        return lambda dll, c, nx: _raw(dll, f"{v}SetTime")(c if instance else None, c_double(time))

    def set_states(change=0, null=False, poison=False, instance=True):
        def made(dll, c, nx):
            own = (c_double * max(nx, 1))()
            assert _raw(dll, f"{v}GetContinuousStates")(c, own, c_size_t(nx)) == OK
            array = (c_double * max(nx + change, 1))(*own[:nx + change])
            if poison:
                array[0] = float("nan")
            return _raw(dll, f"{v}SetContinuousStates")(c if instance else None, None if null else array,
                                                         c_size_t(nx + change))
        return made

    return {
        "SetTime: NULL instance": (set_time(0.5), set_time(0.5, instance=False), False, False),
        "SetTime: a time that is not a number": (set_time(0.5), set_time(float("nan")), False, False),
        "SetTime: an infinite time": (set_time(0.5), set_time(float("inf")), False, False),
        "SetTime: on a co-simulation instance": (set_time(0.5), set_time(0.5), False, True),
        "SetContinuousStates: NULL instance": (set_states(), set_states(instance=False), True, False),
        "SetContinuousStates: a NULL array": (set_states(), set_states(null=True), True, False),
        "SetContinuousStates: an array one shorter": (set_states(), set_states(-1), True, False),
        "SetContinuousStates: an array one longer": (set_states(), set_states(1), True, False),
        "SetContinuousStates: a state that is not a number": (set_states(), set_states(poison=True), True, False),
        "SetContinuousStates: in event mode": (set_states(), set_states(), (True, False), False),
    }


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", list(FMU_KINDS))
def test_every_bad_boolean_width_or_derivative_argument_is_refused_and_the_good_one_taken(fmu_kinds, kind, version):
    """The get and set functions of the types no FMU here has (Boolean; FMI 3.0's Int8 to UInt64 but Int64, and
    Float32) with an unknown reference, a Float64's, or no instance, against the call that asks for no value (OK);
    the directional derivative (where the FMU has one: the native plant) with each of its arrays NULL, or no
    instance. Each bad call against the good one on a fresh instance after initialisation. On main FMI 3.0's
    Int8, UInt8, Int16, UInt16, UInt32 and Float32 functions refused the good call too (every call: fmi3Error)."""
    folder = fmu_kinds[kind][version]
    calls = _untyped_calls(version)
    if kind == "native":  # the Python FMUs have no directional derivative (every call refused, and said so)
        calls.update(_derivative_calls(version))
    results = {}
    for check, (good, bad) in calls.items():
        statuses = []
        for call in (good, bad):
            fmu, dll, instance, vr = _fresh(folder, version)
            try:
                statuses.append(call(dll, instance, vr))
            finally:
                fmu.freeInstance()
        results[check] = tuple(statuses)
    assert results == {check: (OK, ERROR) for check in results}


@pytest.mark.parametrize("version", [2, 3])
def test_every_bad_set_time_or_continuous_states_argument_is_refused_and_the_good_one_taken(fmu_kinds, version):
    """Model Exchange's SetTime and SetContinuousStates (the native FMUs: the Python ones have no Model Exchange):
    no instance, a time or a state that is not a finite number, an array NULL, one shorter or one longer than the
    states, the states set in event mode, SetTime on a co-simulation instance. Each bad call against the good one
    on a fresh instance (SetTime in event mode, SetContinuousStates in continuous-time mode). On main a time that
    is not finite (NaN, inf) was taken (OK)."""
    folder = fmu_kinds["native"][version]
    results = {}
    for check, (good, bad, continuous_time, on_co_simulation) in _time_and_state_calls(version).items():
        statuses = []
        modes = continuous_time if isinstance(continuous_time, tuple) else (continuous_time,) * 2
        for call, model_exchange, mode in ((good, True, modes[0]), (bad, not on_co_simulation, modes[1])):
            fmu, dll, instance, nx, _ = _model_exchange(folder, version, mode, model_exchange)
            try:
                statuses.append(call(dll, instance, nx))
            finally:
                fmu.freeInstance()
        results[check] = tuple(statuses)
    assert results == {check: (OK, ERROR) for check in results}
