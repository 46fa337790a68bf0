"""Parameter rules as data (crane_fmu/model/rules.py): one declaration, the same verdict and message everywhere.

For every component with a native twin, hypothesis (derandomised) draws parameter values, mostly the defaults
with one to three changed to values near the rules' edges (zeros, signs, the limits' 1e60, infinities, NaN,
other parameters' values, whole and half numbers, any float), and requires the same verdict and the same
message from the Python model's ``check``, the Python FMU and the native FMU (fmpy: set the values, enter and
exit initialisation, read the FMU's log). One instance of each FMU is loaded per component and reset between
examples. The language's own pieces (its C, its refusals) are checked without FMUs.
"""

import ast
import ctypes
import itertools
import math
import pickle
import random
import re
import struct
import subprocess

import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
)
from fmpy.logging import addLoggerProxy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from native_fmus import LOG, LOGGER, compiler, extracted

from crane_fmu import components
from crane_fmu.build_scripts.native import FOLDERS, native_dir
from crane_fmu.model import rules
from crane_fmu.model.component import Component
from crane_fmu.model.tables import parameter

NATIVE = [c.model_identifier for c in components.registered() if c.native]
EXAMPLES = 100  # random draws per component (12 components), besides one edge case per rule
INF, NAN = math.inf, math.nan
EDGES = (0.0, -0.0, 1.0, -1.0, 0.5, 1.5, 2.0, 100.0, 101.0, 2.0 ** 32, 2.0 ** 32 - 1, 1e60, -1e60, 1e300, -1e300,
         5e-324, INF, -INF, NAN, math.pi / 2, 1e-3)
TEXTS = ("", "ZV", "it's", 'a"b\\', "é")  # besides the strings the rules name

_LIBC = ctypes.CDLL(None)
_LIBC.calloc.restype, _LIBC.calloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t, ctypes.c_size_t]
_LIBC.free.argtypes = [ctypes.c_void_p]


def logger():
    """``(log, callbacks)``: FMI 2.0 callbacks whose logger appends each message to ``log``. fmpy's logger proxy
    keeps one logger for the process: the FMUs of a test share these, made anew for the test."""
    log, callbacks = [], fmi2CallbackFunctions()
    LOG[0] = log  # the process's one logger (native_fmus.LOGGER): fmpy's proxy keeps it past this test
    callbacks.logger = LOGGER
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_LIBC.calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_LIBC.free)
    addLoggerProxy(ctypes.byref(callbacks))
    return log, callbacks


class Judge:
    """One FMI 2.0 instance of the FMU at ``path``, loaded once and logging into ``log`` (:func:`logger`):
    :meth:`verdict` of parameter values."""

    def __init__(self, path, log, callbacks, items):
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.log, self.items = log, items  # items: an Enumeration's names, by parameter
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extracted(path),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName="rules")
        self.fmu.instantiate(callbacks=callbacks)
        self.used = False

    def _refused_set(self, name):
        """An Enumeration's name no item has cannot be carried by FMI: the number no item has (0) is refused as it is
        set; ``("set", message)`` (the next verdict resets the instance)."""
        with pytest.raises(FMICallException):
            self.fmu.setInteger([self.vr[name]], [0])
        assert len(self.log) == 1, self.log
        return "set", self.log[0]

    def verdict(self, values):
        """None where initialisation ends with ``values`` set, else what the FMU logged (without the FMI
        function's name); every other message it logged must be none."""
        if self.used:
            self.fmu.reset()
        self.used, self.log[:] = True, []
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        reals = {k: v for k, v in values.items() if not isinstance(v, str)}
        self.fmu.setReal([self.vr[k] for k in reals], list(reals.values()))
        for name, value in values.items():
            if isinstance(value, str) and name in self.items:  # an Enumeration: its item's number (from 1)
                if value not in self.items[name]:
                    return self._refused_set(name)
                self.fmu.setInteger([self.vr[name]], [self.items[name].index(value) + 1])
            elif isinstance(value, str):
                self.fmu.setString([self.vr[name]], [value])
        try:
            self.fmu.exitInitializationMode()
        except FMICallException:
            assert len(self.log) == 1, self.log
            function, _, message = self.log[0].partition(": ")
            assert function == "fmi2ExitInitializationMode"
            return message
        assert self.log == []
        return None

    def close(self):
        self.fmu.freeInstance()


def python_verdict(component, values):
    """What the Python FMU logs where ``component.check`` refuses ``values`` (a ValueError's message, any other
    exception as ``Type: message``: fmu_src/python/python_model.c), or None."""
    try:
        component.check(values)
    except Exception as exc:
        return str(exc) if isinstance(exc, ValueError) and str(exc) else f"{type(exc).__name__}: {exc}"
    return None


def draws(component):
    """A strategy of ``{parameter: value}``: one to three parameters changed from their defaults."""
    parameters = [v for v in component.variables if v.causality == "parameter"]
    starts = sorted({v.start for v in parameters if v.type == "Real"})
    near = sorted({*EDGES, *starts, *(-v for v in starts), *(2 * v for v in starts)}, key=repr)
    texts = sorted({*TEXTS, *(v.start for v in parameters if v.type in ("String", "Enumeration")),
                    *(c for r in component.rules for c in _strings_in(r))})
    real = st.one_of(st.sampled_from(near), st.floats(allow_nan=True, allow_infinity=True))
    value = {v.name: st.sampled_from(texts) if v.type in ("String", "Enumeration") else real for v in parameters}
    changed = st.lists(st.sampled_from(list(value)), min_size=1, max_size=3, unique=True)

    @st.composite
    def values(draw):
        return {name: draw(value[name]) for name in draw(changed)}

    return values()


def _strings_in(rule):
    """The strings a rule names (the choices of a String parameter)."""
    return [n.value for n in ast.walk(ast.parse(rule.test)) if isinstance(n, ast.Constant) and isinstance(n.value, str)]


def edge_cases(component):
    """For each rule, in order, the first values of its parameters from EDGES (TEXTS for a String) that make it the
    first rule the defaults so changed fail: every rule's refusal, found by search rather than luck."""
    found, named = [], tuple(dict.fromkeys(c for r in component.rules for c in _strings_in(r)))
    for target in component.rules:  # a String's edges: TEXTS, then the strings the rules name ('measured' ...)
        choices = [TEXTS + named if name in target.strings else EDGES for name in target.names]
        for combination in itertools.product(*choices):
            values = dict(zip(target.names, combination))
            if _first_failing(component, values) is target:
                found.append(values)
                break
        else:
            raise AssertionError(f"{component.model_identifier}: no values of EDGES break {target.test!r} first")
    return found


def _first_failing(component, values):
    full = {**component.defaults(), **values}
    return next((r for r in component.rules if not r.holds(full)), None)


@pytest.fixture(scope="module")
def folders(fmu_dir):
    folders = {"python": fmu_dir, "native": native_dir(fmu_dir, 2)}
    if not (folders["native"] / "CranePlant.fmu").exists():
        pytest.fail("the build made no native FMUs (no C compiler?)")
    return folders


@pytest.mark.parametrize("name", NATIVE)
def test_the_python_model_the_python_fmu_and_the_native_fmu_give_the_same_verdict_and_message(folders, name):
    component = components.get(name)
    log, callbacks = logger()
    items = {v.name: v.items for v in component.variables if v.type == "Enumeration"}
    python, native = (Judge(folders[kind] / f"{name}.fmu", log, callbacks, items) for kind in ("python", "native"))
    seen = {"refused": set(), "accepted": 0}

    @settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(draws(component))
    def same(values):
        expected = python_verdict(component, values)
        verdicts = python.verdict(values), native.verdict(values)
        if isinstance(verdicts[0], tuple):  # a name no item of an Enumeration has: refused before any rule runs
            assert expected is not None and verdicts[0] == verdicts[1]
        else:
            assert verdicts == (expected, expected)
        if expected is None:
            seen["accepted"] += 1
        else:
            seen["refused"].add(expected.split(" ")[0])

    try:
        for values in edge_cases(component):  # every rule refuses, in both FMUs with its message
            assert python_verdict(component, values) is not None
            same.hypothesis.inner_test(values)
        same()
    finally:
        python.close()
        native.close()
    # the draws reach both verdicts, and refusals by several rules (not only the first one)
    assert seen["accepted"] > 0 and len(seen["refused"]) >= 3, seen


# ---- the language, without FMUs ------------------------------------------------------------------------------------

@pytest.mark.quick
def test_each_kind_of_rule_says_what_it_requires_and_refuses_what_it_must():
    cases = [  # (rule, values, message or None)
        (rules.positive("h")[0], {"h": 1e-3}, None),
        (rules.positive("h")[0], {"h": 0.0}, "h must be > 0 and finite, got 0.0"),
        (rules.positive("h")[0], {"h": INF}, "h must be > 0 and finite, got inf"),
        (rules.non_negative("c")[0], {"c": -0.0}, None),
        (rules.non_negative("c")[0], {"c": NAN}, "c must be >= 0 and finite, got nan"),
        (rules.finite("x")[0], {"x": -INF}, "x must be finite, got -inf"),
        (rules.limit("u")[0], {"u": INF}, None),
        (rules.limit("u")[0], {"u": -1.0}, "u must be > 0 (inf: no limit), got -1.0"),
        (rules.in_range("m", 0, 1, high_open=True), {"m": 1.0}, "m must be >= 0 and < 1, got 1.0"),
        (rules.in_range("m", 0, 1, high_open=True), {"m": 0.0}, None),
        (rules.one_of("s", ("a", "b")), {"s": "c"}, "s must be one of a, b, got 'c'"),
        (rules.one_of("d", (0.0, 1.0), "0 or 1"), {"d": 0.5}, "d must be 0 or 1, got 0.5"),
        (rules.whole("k", "0 <= k <= 3", "a whole number in [0, 3]"), {"k": 2.0}, None),
        (rules.whole("k", "0 <= k <= 3", "a whole number in [0, 3]"), {"k": 2.5}, "k must be a whole number in "
                                                                                "[0, 3], got 2.5"),
        (rules.whole("k", "0 <= k <= 3", "a whole number in [0, 3]"), {"k": INF}, "k must be a whole number in "
                                                                                "[0, 3], got inf"),
        (rules.rule("a <= b <= c", "b must lie in [{a}, {c}], got {b}"), {"a": 0.0, "b": 2.0, "c": 1.0},
         "b must lie in [0.0, 1.0], got 2.0"),
        (rules.rule("b > 0", "b must be > 0, got {b}", when="a != 0"), {"a": 0.0, "b": -1.0}, None),
        (rules.rule("b > 0", "b must be > 0, got {b}", when="a != 0"), {"a": 1.0, "b": -1.0},
         "b must be > 0, got -1.0"),
        (rules.rule("finite(unlimited(u))", "u must be finite, got {unlimited(u)}"), {"u": 1e60}, "u must be finite, "
                                                                                               "got inf"),
        (rules.rule("finite(unlimited(u))", "u must be finite, got {unlimited(u)}"), {"u": 9.9e59}, None),
    ]
    for rule, values, message in cases:
        if message is None:
            rules.check([rule], values)
        else:
            with pytest.raises(ValueError) as refused:
                rules.check([rule], values)
            assert str(refused.value) == message


@pytest.mark.quick
def test_the_first_rule_that_fails_is_reported_and_a_value_of_the_wrong_type_is_named():
    both = (*rules.positive("a"), *rules.finite("b"))
    with pytest.raises(ValueError, match=r"^a must be > 0 and finite, got -1.0$"):
        rules.check(both, {"a": -1.0, "b": NAN})
    with pytest.raises(ValueError, match=r"^b must be finite, got nan$"):
        rules.check(both, {"a": 1.0, "b": NAN})
    with pytest.raises(ValueError, match=r"^a must be a number, got 'x'$"):
        rules.check(both, {"a": "x", "b": 0.0})
    with pytest.raises(ValueError, match=r"^a must be a number, got True$"):
        rules.check(both, {"a": True, "b": 0.0})
    with pytest.raises(ValueError, match=r"^s must be a string, got 1.0$"):
        rules.check([rules.one_of("s", ("a",))], {"s": 1.0})


@pytest.mark.quick
def test_a_rule_is_its_data_compared_and_pickled_by_it():
    rule = rules.rule("b > 0", "b must be > 0, got {b}", when="a != 0")
    again = pickle.loads(pickle.dumps(rule))
    assert again == rule and repr(again) == repr(rule) and again.names == ("b", "a")
    assert not again.holds({"a": 1.0, "b": -1.0}) and again.holds({"a": 0.0, "b": -1.0})


@pytest.mark.quick
@pytest.mark.parametrize("test", ["__import__('os')", "x ** 2 > 0", "abs(x) > 0", "x.real > 0", "[x][0] > 0",
                                  "x in y", "x if y else z", "lambda: 0", "x > True", "~x"])
def test_the_rules_language_refuses_what_it_cannot_write_in_c(test):
    with pytest.raises((ValueError, SyntaxError)):
        rules.rule(test, "no")


@pytest.mark.quick
def test_a_rule_reads_only_parameters_of_its_component_a_string_as_a_string():
    table = (parameter("h", 1.0, "s", "step"), parameter("s", "a", None, "a choice", "String"))
    for bad in (rules.positive("k"), rules.positive("s"), (rules.one_of("h", ("a",)),)):
        with pytest.raises(ValueError, match="rule"):
            Component("X", "controller", "", table, lambda values: None, lambda *a: (), rules=bad)
    Component("X", "controller", "", table, lambda values: None, lambda *a: (),
              rules=(*rules.positive("h"), rules.one_of("s", ("a", "b"))))


@pytest.mark.quick
def test_every_rule_of_every_component_is_written_in_c_with_its_message():
    """The generated check holds one test per rule, in order, each with the rule's message as a printf format
    of the same fields."""
    for component in components.registered():
        text = rules.c_function(component.rules)
        assert text.count("return report(r, MODEL_ERROR, ") == len(component.rules)
        formats = [line.split('MODEL_ERROR, "', 1)[1].split('"', 1)[0] for line in text.splitlines()
                   if "MODEL_ERROR" in line]
        for rule, written in zip(component.rules, formats):
            assert written == re.sub(r"\{[^{}]*\}", "%s", rule.message.replace("%", "%%")).replace('"', '\\"')


PRINT_REPRS = r"""
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "py_repr.h"

int main(void) { /* each line of stdin a double's bits in hex: its py_repr() */
    char line[64], out[REPR_SIZE];
    while (fgets(line, sizeof line, stdin)) {
        uint64_t bits = strtoull(line, NULL, 16);
        double value;
        memcpy(&value, &bits, sizeof value);
        puts(py_repr(value, out));
    }
    return 0;
}
"""


def test_the_c_messages_show_a_double_as_pythons_repr_does(tmp_path):
    """py_repr (fmu_src/framework) against repr() at every power of two and its neighbours (where the decimal
    rounded from a double may not read back, but its neighbour does) and at random bit patterns."""
    (tmp_path / "main.c").write_text(PRINT_REPRS)
    framework = FOLDERS[0]
    subprocess.run([compiler(), "-O2", "-Wall", "-Werror", f"-I{framework}", str(tmp_path / "main.c"),
                    str(framework / "py_repr.c"), "-o", str(tmp_path / "reprs"), "-lm"], check=True)
    rng = random.Random(48)
    values = [0.0, -0.0, 5e-324, 1.7976931348623157e308, 1e16, 1e-5, 1e23, 0.1, 2.0 ** -24]
    for e in range(-1074, 1024):
        values += [2.0 ** e, math.nextafter(2.0 ** e, INF), math.nextafter(2.0 ** e, 0.0)]
    values += [struct.unpack("<d", rng.getrandbits(64).to_bytes(8, "little"))[0] for _ in range(20000)]
    values = [v for value in values if not math.isnan(value) for v in (value, -value)]
    bits = "".join(f"{struct.unpack('<Q', struct.pack('<d', v))[0]:x}\n" for v in values)
    shown = subprocess.run([str(tmp_path / "reprs")], input=bits, capture_output=True, text=True,
                           check=True).stdout.splitlines()
    assert [(repr(v), s) for v, s in zip(values, shown) if repr(v) != s] == []
    assert len(shown) == len(values)
