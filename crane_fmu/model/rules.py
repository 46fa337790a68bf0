"""Parameter rules as data: each rule declared once, beside its component's variable table.

A :class:`Rule` is a condition on a component's parameter values and the message a user sees when it
fails, one line naming the field, the rule and the value: ``l1 must be > 0 and finite, got -1.0``. From
the same declaration come the Python check (:func:`check`, which every component's ``configure`` calls
first, in the order of its ``RULES``) and the C check of its native twin (:func:`c_function`, which
``crane-fmu build`` generates into ``<model>_variables.h`` and the registration of ``component.h`` runs
before the model file's ``configure()``). The first rule that fails is the one reported, in Python and in C alike.

A condition is a Python expression over the component's parameter names, in a small language that means
the same in Python and in C (IEEE doubles in both, no exceptions):

- numbers, ``pi``, ``inf``, strings, ``+ - * /``;
- comparisons, chained too (``l1_min <= l1 <= l1_max``), ``in`` and ``not in`` a tuple of numbers or of
  strings (a String parameter is compared with strings only), ``and``, ``or``, ``not``;
- ``finite(x)``, ``whole(x)`` (finite, no fraction) and ``unlimited(x)`` (``+-inf`` where ``x`` lies at
  or beyond ``+-``:data:`NO_LIMIT`: a limit that is off, see :mod:`.limits`).

A message's ``{expression}`` fields show values as Python's ``repr()`` does (the C twin's ``py_repr``).
A rule with ``when`` applies only where that condition holds.

The kinds of rule the components need are one line each: :func:`in_range` (and its presets
:func:`positive`, :func:`non_negative`, :func:`finite`, :func:`limit`), :func:`one_of`, :func:`whole`,
and :func:`rule` for a relation between parameters. Rules that need a computation beyond this language
(an MPC horizon counted in intervals, a design that must exist) stay code in ``configure``.
"""

import ast
import math
import re
from dataclasses import dataclass

NO_LIMIT = 1e60  # "no limit": a limit's value at or beyond it (limits.py says why a finite one)

FUNCTIONS = {"finite": "isfinite", "whole": "is_whole", "unlimited": "unlimited"}  # Python name: C name (rules.h)
CONSTANTS = {"pi": math.pi, "inf": math.inf}
RESERVED = {*FUNCTIONS, *CONSTANTS}
_FIELD = re.compile(r"\{([^{}]*)\}")
_C_OPERATORS = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!=",
                ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.And: "&&", ast.Or: "||"}


def unlimited(value):
    """``value``, or +-inf where it lies at or beyond +-:data:`NO_LIMIT` (no limit)."""
    return math.copysign(math.inf, value) if abs(value) >= NO_LIMIT else value


def _whole(value):
    return math.isfinite(value) and value == int(value)


_NAMESPACE = {"finite": math.isfinite, "whole": _whole, "unlimited": unlimited, **CONSTANTS}


@dataclass(frozen=True)
class Rule:
    """One parameter rule.

    Attributes
    ----------
    test : str
        The condition the values must meet (the language above).
    message : str
        What a user reads when they do not, with ``{expression}`` fields.
    when : str, optional
        The condition under which the rule applies (always if None).
    """

    test: str
    message: str
    when: str | None = None

    def __post_init__(self):  # parsed once; kept beside the fields (which alone are the rule's data)
        condition = _parse(f"not ({self.when}) or ({self.test})" if self.when else self.test)
        fields = [_parse(text) for text in _FIELD.findall(self.message)]
        names, strings = [], set()
        for tree in [_parse(self.test), *([_parse(self.when)] if self.when else []), *fields]:
            _read(tree.body, names, strings)
        object.__setattr__(self, "_names", tuple(names))
        object.__setattr__(self, "_strings", frozenset(strings))
        object.__setattr__(self, "_condition", compile(condition, "<rule>", "eval"))
        object.__setattr__(self, "_fields", tuple(compile(tree, "<rule>", "eval") for tree in fields))

    def __reduce__(self):  # pickled as its data (its compiled code is made again)
        return Rule, (self.test, self.message, self.when)

    @property
    def names(self):
        """The parameters the rule reads, in order."""
        return self._names

    @property
    def strings(self):
        """Those of :attr:`names` that are String parameters (compared with strings)."""
        return self._strings

    def holds(self, values):
        """Whether ``values`` (``{name: value}``) meet the rule (or it does not apply)."""
        return _holds(self, {**values, **_NAMESPACE})

    def text(self, values):
        """The message for ``values``."""
        space = {**values, **_NAMESPACE}
        shown = iter(self._fields)
        return _FIELD.sub(lambda m: repr(eval(next(shown), _NO_BUILTINS, space)), self.message)


_NO_BUILTINS = {"__builtins__": {}}


def _holds(rule, space):
    return bool(eval(rule._condition, _NO_BUILTINS, space))


def check(rules, values):
    """Raise ValueError with the message of the first of ``rules`` that ``values`` fail.

    A value of the wrong type (a number where a string belongs, a bool, None) fails with
    ``"name must be a number, got 'x'"`` at the first rule that reads it.
    """
    space = {**values, **_NAMESPACE}
    for r in rules:
        for name in r.names:
            value = values[name]
            if name in r.strings:
                if not isinstance(value, str):
                    raise ValueError(f"{name} must be a string, got {value!r}")
            elif isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"{name} must be a number, got {value!r}")
        if not _holds(r, space):
            raise ValueError(r.text(values))


# ---- the kinds of rule --------------------------------------------------------------------------------------------

def rule(test, message, when=None):
    """A relation, or any other condition: ``rule("x_min < x_max", "x_min must be < x_max, got {x_min} and
    {x_max}")``."""
    return Rule(test, message, when)


def _number(value):
    return repr(int(value)) if float(value).is_integer() and abs(value) < 1e16 else repr(float(value))


def in_range(name, low=None, high=None, low_open=False, high_open=False, finite=True, note=None, when=None):
    """``name`` within ``[low, high]`` (an end ``None``: none; ``*_open``: the end excluded), finite unless
    ``finite`` is False (both ends given: finite anyway); ``note`` in parentheses after the rule's words.

    The message: ``"h must be > 0 and finite, got -1.0"``.
    """
    tests, words = [], []
    if low is not None:
        tests.append(f"{name} {'>' if low_open else '>='} {_number(low)}")
        words.append(f"{'>' if low_open else '>='} {_number(low)}")
    if high is not None:
        tests.append(f"{name} {'<' if high_open else '<='} {_number(high)}")
        words.append(f"{'<' if high_open else '<='} {_number(high)}")
    if finite and (low is None or high is None):
        tests.insert(0, f"finite({name})")
        words.append("finite")
    text = " and ".join(words) + (f" ({note})" if note else "")
    return Rule(" and ".join(tests), f"{name} must be {text}, got {{{name}}}", when)


def positive(*names, when=None):
    """``> 0 and finite``, for each of ``names``."""
    return tuple(in_range(name, 0, low_open=True, when=when) for name in names)


def non_negative(*names):
    """``>= 0 and finite``, for each of ``names``."""
    return tuple(in_range(name, 0) for name in names)


def finite(*names):
    """``finite``, for each of ``names``."""
    return tuple(in_range(name) for name in names)


def limit(*names, note="inf: no limit"):
    """``> 0``, infinity allowed (no limit), for each of ``names``: ``"u_max must be > 0 (inf: no limit), got
    0.0"``."""
    return tuple(in_range(name, 0, low_open=True, finite=False, note=note) for name in names)


def one_of(name, choices, words=None):
    """``name`` one of ``choices`` (numbers, or strings for a String parameter); ``words`` say what they mean
    (default ``"one of a, b"``)."""
    words = words or "one of " + ", ".join(map(str, choices))
    return Rule(f"{name} in ({', '.join(map(repr, choices))},)", f"{name} must be {words}, got {{{name}}}")


def whole(name, bounds, words):
    """``name`` a whole number meeting ``bounds`` (a condition), described by ``words``:
    ``whole("delay", "0 <= delay <= 100", "a whole number of steps in [0, 100]")``."""
    return Rule(f"whole({name}) and {bounds}", f"{name} must be {words}, got {{{name}}}")


# ---- the language: parsed, checked, and written in C --------------------------------------------------------------

def _parse(text):
    """The expression ``text`` as an AST, refused (ValueError) where it leaves the language."""
    tree = ast.parse(text, mode="eval")
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS and len(node.args) == 1
                    and not node.keywords):
                raise ValueError(f"rule {text!r}: a call must be one of {', '.join(FUNCTIONS)} of one value")
        elif isinstance(node, ast.Compare):
            for op, right in zip(node.ops, node.comparators):
                if isinstance(op, (ast.In, ast.NotIn)) and not (
                        isinstance(right, ast.Tuple) and all(isinstance(e, ast.Constant) for e in right.elts)):
                    raise ValueError(f"rule {text!r}: 'in' takes a tuple of constants")
                if not isinstance(op, (ast.In, ast.NotIn, *(k for k in _C_OPERATORS if issubclass(k, ast.cmpop)))):
                    raise ValueError(f"rule {text!r}: no comparison {type(op).__name__}")
        elif isinstance(node, ast.BinOp) and type(node.op) not in _C_OPERATORS:
            raise ValueError(f"rule {text!r}: no operator {type(node.op).__name__}")
        elif isinstance(node, ast.Constant) and (isinstance(node.value, bool) or
                                                 not isinstance(node.value, (int, float, str))):
            raise ValueError(f"rule {text!r}: no constant {node.value!r}")
        elif not isinstance(node, (ast.Expression, ast.BoolOp, ast.UnaryOp, ast.Name, ast.Load, ast.Tuple,
                                   ast.Constant, ast.BinOp, ast.Call, ast.Compare, ast.boolop, ast.operator,
                                   ast.cmpop, ast.unaryop)) or isinstance(node, ast.Invert):
            raise ValueError(f"rule {text!r}: {type(node).__name__} is not in the rules' language")
    return tree


def _read(node, names, strings):
    """Collect the parameter names ``node`` reads (into ``names``, in order) and those compared with strings."""
    if isinstance(node, ast.Name) and node.id not in RESERVED and node.id not in names:
        names.append(node.id)
    if isinstance(node, ast.Compare):
        operands = [node.left, *node.comparators]
        constants = [c for e in operands for c in (e.elts if isinstance(e, ast.Tuple) else [e])]
        if any(isinstance(c, ast.Constant) and isinstance(c.value, str) for c in constants):
            strings.update(e.id for e in operands if isinstance(e, ast.Name))
    for child in ast.iter_child_nodes(node):
        if not (isinstance(node, ast.Call) and child is node.func):
            _read(child, names, strings)


def c_double(value):
    """A C double literal that reads back as ``value`` exactly."""
    value = float(value)
    if math.isinf(value):
        return "INFINITY" if value > 0 else "(-INFINITY)"
    text = repr(value)
    return text if "." in text or "e" in text else text + ".0"


def c_string(text):
    """A C string literal of ``text`` (UTF-8), for printf when ``printf`` (``%`` doubled)."""
    out = []
    for byte in text.encode():
        char = chr(byte)
        out.append("\\" + char if char in '"\\' else char if 32 <= byte < 127 else f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def _c(node, strings):
    """The C of the expression ``node``: a parameter is ``values[VR_name]`` (``strings[STRING_name]``)."""
    if isinstance(node, ast.Expression):
        return _c(node.body, strings)
    if isinstance(node, ast.Constant):
        return c_string(node.value) if isinstance(node.value, str) else c_double(node.value)
    if isinstance(node, ast.Name):
        if node.id in CONSTANTS:
            return c_double(CONSTANTS[node.id])
        return f"strings[STRING_{node.id}]" if node.id in strings else f"values[VR_{node.id}]"
    if isinstance(node, ast.UnaryOp):
        return f"{'!' if isinstance(node.op, ast.Not) else '-' if isinstance(node.op, ast.USub) else '+'}" \
               f"{_c(node.operand, strings)}"
    if isinstance(node, ast.BinOp):
        return f"({_c(node.left, strings)} {_C_OPERATORS[type(node.op)]} {_c(node.right, strings)})"
    if isinstance(node, ast.BoolOp):
        return "(" + f" {_C_OPERATORS[type(node.op)]} ".join(_c(v, strings) for v in node.values) + ")"
    if isinstance(node, ast.Call):
        return f"{FUNCTIONS[node.func.id]}({_c(node.args[0], strings)})"
    parts, left = [], node.left  # a comparison, chained: each link once
    for op, right in zip(node.ops, node.comparators):
        parts.append(_c_compare(left, op, right, strings))
        left = right
    return parts[0] if len(parts) == 1 else "(" + " && ".join(parts) + ")"


def _c_compare(left, op, right, strings):
    a = _c(left, strings)
    if isinstance(op, (ast.In, ast.NotIn)):
        either = "(" + " || ".join(_c_equal(a, left, e, strings) for e in right.elts) + ")"
        return "!" + either if isinstance(op, ast.NotIn) else either
    if isinstance(op, (ast.Eq, ast.NotEq)) and _is_text(left, strings):
        return f"(strcmp({a}, {_c(right, strings)}) {_C_OPERATORS[type(op)]} 0)"
    return f"({a} {_C_OPERATORS[type(op)]} {_c(right, strings)})"


def _c_equal(a, left, constant, strings):
    if _is_text(left, strings):
        return f"strcmp({a}, {_c(constant, strings)}) == 0"
    return f"{a} == {_c(constant, strings)}"


def _is_text(node, strings):
    return isinstance(node, ast.Name) and node.id in strings or isinstance(node, ast.Constant) and isinstance(
        node.value, str)


def c_rule(r):
    """The C statement of one rule: report its message and return MODEL_ERROR where it fails."""
    test = _c(_parse(r.test), r.strings)
    if r.when:
        test = f"!{_c(_parse(r.when), r.strings)} || {test}"
    pieces = _FIELD.split(r.message)  # text, field, text, field, ..., text
    template = "".join(piece.replace("%", "%%") if i % 2 == 0 else "%s" for i, piece in enumerate(pieces))
    shown = []
    for expression in pieces[1::2]:
        tree = _parse(expression)
        if _is_text(tree.body, r.strings):
            shown.append(f"STR_REPR({_c(tree, r.strings)})")
        else:
            shown.append(f"REPR({_bare(_c(tree, r.strings))})")
    arguments = "".join(", " + s for s in shown)
    return (f"    if (!({_bare(test)}))\n"
            f"        return report(r, MODEL_ERROR, {c_string(template)}{arguments});")


def _bare(text):
    """``text`` without the parentheses around all of it, if any."""
    if not (text.startswith("(") and text.endswith(")")) or '"' in text:
        return text
    depth = 0
    for i, char in enumerate(text):
        depth += {"(": 1, ")": -1}.get(char, 0)
        if depth == 0 and i < len(text) - 1:
            return text
    return text[1:-1]


def c_function(rules):
    """``parameter_rules()``: the C check of ``rules``, in their order and words (for ``<model>_variables.h``)."""
    body = "\n".join(c_rule(r) for r in rules)
    return ("/* The component's parameter rules (its RULES in the Python model), in their order and words: the first\n"
            "   that the values fail is reported. Generated from them, like the rest of this file. */\n"
            "static inline ModelStatus parameter_rules(const double values[], const StringValue strings[],\n"
            "                                          const Reporter *r) {\n"
            "    (void)values, (void)strings;\n"
            f"{body}{chr(10) if body else ''}"
            "    return MODEL_OK;\n"
            "}\n")
