"""Helpers for the tests of the native (C) FMUs against the Python ones: open, close, and a logged FMI 2.0 run.

``open_native`` gives an instance of any FMU (native or Python, FMI 2.0 or 3.0) in initialisation mode;
``messages`` runs an FMI 2.0 instance call by call with a logger and returns its statuses and messages,
so that a native FMU's refusals and errors can be compared with the Python FMU's; ``python_folder`` and
``compare_to_python`` hold a native component's outputs to its Python FMU's (conftest.py's ``native`` fixture gives
the native FMUs' folders).
"""

import ctypes
import shutil
import sys
import tempfile

import fmpy
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.logging import addLoggerProxy

from crane_fmu.build_scripts.build_fmus import fmi3_dir

_UNZIPPED = []  # this test process's folder of extracted FMUs, made at the first, removed at the session's end


def extracted(path):
    """``fmpy.extract`` into a folder :func:`remove_extracted` removes (fmpy's own one in /tmp is never removed)."""
    if not _UNZIPPED:
        _UNZIPPED.append(tempfile.mkdtemp(prefix="crane-test-unzipped-"))
    return fmpy.extract(str(path), unzipdir=tempfile.mkdtemp(dir=_UNZIPPED[0]))


def remove_extracted():
    """Remove what :func:`extracted` made (conftest's ``pytest_sessionfinish``: xdist's workers skip ``atexit``)."""
    while _UNZIPPED:
        shutil.rmtree(_UNZIPPED.pop(), ignore_errors=True)


_LIBC = ctypes.CDLL(None)
_LIBC.calloc.restype, _LIBC.calloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t, ctypes.c_size_t]
_LIBC.free.argtypes = [ctypes.c_void_p]

# fmpy's logger proxy keeps the last logger it was given for the whole process (one global pointer), and an FMU
# opened with fmpy's default callbacks logs through it: a logger made for one test and then freed crashes a later
# test. Ours lives as long as the process and writes to the log of the run that set it (LOG[0]).
LOG = [[]]
LOGGER = fmi2CallbackLoggerTYPE(lambda env, name, status, category, message: LOG[0].append(message.decode()))


def enumerations(md):
    """``{variable: {item: value}}`` of the Enumeration variables of a model description."""
    return {v.name: {item.name: int(item.value) for item in v.declaredType.items}
            for v in md.modelVariables if v.type == "Enumeration"}


def item_value(items, value):
    """An Enumeration's value given by its item's name (a str) or as a number."""
    return items[value] if isinstance(value, str) else int(value)


def open_native(path, version, parameters=None, instance_name="c", model_exchange=False):
    """An instance in initialisation mode with ``parameters`` set: ``(fmu, vr, set, get)``.

    The real parameters are set in one call, in their order, then each str one as a String, an Enumeration (by
    its item's name or value) as an Integer (Int64). With
    ``model_exchange`` an instance of the FMU's Model Exchange interface.
    """
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    interface = md.modelExchange if model_exchange else md.coSimulation
    name, unzipped = interface.modelIdentifier, extracted(path)
    if version == 2:
        fmu = (FMU2Model if model_exchange else FMU2Slave)(guid=md.guid, unzipDirectory=unzipped,
                                                          modelIdentifier=name, instanceName=instance_name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        set_, get = fmu.setReal, fmu.getReal
    else:
        fmu = (FMU3Model if model_exchange else FMU3Slave)(guid=md.instantiationToken, unzipDirectory=unzipped,
                                                          modelIdentifier=name, instanceName=instance_name)
        fmu.instantiate()
        fmu.enterInitializationMode(startTime=0.0)
        set_, get = fmu.setFloat64, fmu.getFloat64
    enums = enumerations(md)
    reals = {k: v for k, v in (parameters or {}).items() if not isinstance(v, str) and k not in enums}
    if reals:
        set_([vr[k] for k in reals], list(reals.values()))
    for key, value in (parameters or {}).items():
        if key in enums:
            (fmu.setInteger if version == 2 else fmu.setInt64)([vr[key]], [item_value(enums[key], value)])
        elif isinstance(value, str):
            fmu.setString([vr[key]], [value])
    return fmu, vr, set_, get


def close(fmu):
    fmu.terminate()
    fmu.freeInstance()


def messages(path, settings, steps=(), read=(), read_at_end=(), instance_name="c", logging_on=False):
    """``(statuses, log)`` of an FMI 2.0 run, call by call, of the FMU at ``path``.

    The run sets ``settings`` in initialisation mode (one call each; a str is set as a String, an Enumeration
    by its item's name or value as an Integer), gets ``read``
    (names; a call named ``get``) before and after initialisation ends, makes ``steps``, each ``(t, h)`` or
    ``(t, h, {input: value})`` with the inputs set before the step, and at last gets ``read_at_end`` (a call
    named ``get`` and the names). It stops at the first call that fails; that call's name and status end the
    statuses, then ``end``. With ``logging_on`` the FMU logs its information too (status OK).
    """
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log = LOG[0] = []
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = LOGGER
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_LIBC.calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_LIBC.free)
    addLoggerProxy(ctypes.byref(callbacks))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extracted(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName=instance_name)
    fmu.instantiate(callbacks=callbacks, loggingOn=logging_on)

    enums = enumerations(md)

    def setter(name, value):
        if name in enums:
            return lambda: fmu.setInteger([vr[name]], [item_value(enums[name], value)])
        if isinstance(value, str):
            return lambda: fmu.setString([vr[name]], [value])
        return lambda: fmu.setReal([vr[name]], [value])

    calls = [("setup", lambda: fmu.setupExperiment(startTime=0.0)), ("enter", fmu.enterInitializationMode)]
    calls += [(f"set {name}", setter(name, value)) for name, value in settings.items()]
    get = ("get", lambda: fmu.getReal([vr[name] for name in read]))
    calls += [get, ("exit", fmu.exitInitializationMode), get] if read else [("exit", fmu.exitInitializationMode)]
    for t, h, *inputs in steps:  # inputs: none, or one dict
        calls += [(f"set {name}", setter(name, value)) for name, value in dict(*inputs).items()]
        calls.append((f"step {t}", lambda t=t, h=h: fmu.doStep(t, h)))
    if read_at_end:
        calls.append((" ".join(["get", *read_at_end]), lambda: fmu.getReal([vr[name] for name in read_at_end])))
    statuses = []
    try:
        for name, call in calls:
            try:
                call()
            except FMICallException as exc:
                statuses.append(f"{name}: {exc.status}")
                break
        statuses.append("end")
    finally:
        fmu.freeInstance()
    return statuses, log


def compiler():
    """The machine's C compiler, as the build finds it (``native.compilers``); the test skips without one."""
    from crane_fmu.build_scripts.native import NativeUnavailable, compilers

    try:
        return compilers()["linux"]
    except NativeUnavailable as exc:
        pytest.skip(str(exc))


def steps_after_restore(fmu, version, steps, k0, n):
    """``(first, again, third)``: ``steps(k0, n)`` (the rows they give) run after saving the FMU state, again after
    restoring it, and a third time after restoring a serialised and deserialised copy of it."""
    state = fmu.getFMUState() if version == 3 else fmu.getFMUstate()
    serialized = fmu.serializeFMUState(state) if version == 3 else fmu.serializeFMUstate(state)
    first = steps(k0, n)
    fmu.setFMUState(state) if version == 3 else fmu.setFMUstate(state)
    again = steps(k0, n)
    restored = fmu.deserializeFMUState(serialized) if version == 3 else fmu.deSerializeFMUstate(serialized)
    fmu.setFMUState(restored) if version == 3 else fmu.setFMUstate(restored)
    return first, again, steps(k0, n)


def python_folder(fmu_dir, version):
    """The Python FMUs of an FMI version."""
    return fmu_dir if version == 2 else fmi3_dir(fmu_dir)


def python_run_equal_to_native(system, fmu_dir, native, version):
    """The Python FMUs' columns of ``system``, checked: the native FMUs give every column within 1e-9 (bit for bit
    on Linux, glibc's libm in both models)."""
    from crane_fmu.cosim import run

    theirs = run(system, python_folder(fmu_dir, version)).columns()
    ours = run(system, native[version]).columns()
    assert list(ours) == list(theirs) and len(theirs["time"]) == round(system.stop_time / system.step) + 1
    worst = max(float(np.max(np.abs(ours[k] - theirs[k]))) for k in theirs)
    assert worst <= 1e-9
    if sys.platform.startswith("linux"):
        assert worst == 0.0
    return theirs


def compare_to_python(ours, theirs):
    """Worst relative deviation (scale at least 1) within 1e-12, returned; on Linux (glibc's libm in both models)
    also bit equality, the signs of zeros too."""
    ours, theirs = np.array(ours), np.array(theirs)
    assert ours.shape == theirs.shape and np.all(np.isfinite(theirs))
    worst = float(np.max(np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1.0)))
    assert worst <= 1e-12
    if sys.platform.startswith("linux"):
        assert np.array_equal(ours.view(np.int64), theirs.view(np.int64))
    return worst


def outputs_beside_python(path, version, component, parameter_sets, steps, random_inputs, rng, longest_step):
    """``(ours, theirs)``: the outputs of the native FMU at ``path`` and of ``component``'s Python model, for each
    of ``parameter_sets`` over ``steps`` steps, the same random inputs (``random_inputs(rng)``) and step lengths
    (1 ms or up to ``longest_step``) given to both."""
    inputs, outputs = component.names("input"), component.names("output")
    ours, theirs = [], []
    for parameters in parameter_sets:
        fmu, vr, set_, get = open_native(path, version, parameters)
        config = component.check(parameters)
        state, t = component.initial_state(config), 0.0
        for j in range(steps):
            values = tuple(random_inputs(rng))
            if inputs:
                set_([vr[n] for n in inputs], values)
            ours.append(get([vr[n] for n in outputs]))
            theirs.append(component.output(config, state, values))
            if j == 0:
                fmu.exitInitializationMode()
            h = rng.choice([1e-3, rng.uniform(1e-3, longest_step)])
            fmu.doStep(t, h)
            state, t = component.update(config, state, values, t, h), t + h
        close(fmu)
    return ours, theirs
