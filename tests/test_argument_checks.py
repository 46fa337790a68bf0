"""Every argument check of the standard's get, set, step and state functions, FMI 2.0 and 3.0, on the Python FMUs
and the native components alike (issue 50, item 7: a class of bad call was no longer refused and no test made that
call): a NULL instance, NULL arrays, a value reference the FMU does not have, lengths that do not match (FMI 3.0),
a NULL or foreign FMU state, a call in the wrong state. Each is first made with good arguments on a fresh instance
(OK: the control), then with the bad one on another fresh instance: fmi*Error (3), and the process goes on.

The functions are called through ctypes as a C host calls them, without fmpy's checks in between.
"""

import ctypes
from ctypes import POINTER, byref, c_double, c_int, c_size_t, c_uint, c_void_p

import pytest
from fmpy import read_model_description
from fmu_kinds import FMU_KINDS
from native_fmus import close, open_native

OK, ERROR = 0, 3
VR = POINTER(c_uint)


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
