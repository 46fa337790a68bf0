"""The suite's own layout: a helper that test modules share lives in a support module (``helpers.py`` and the
modules it lists), never in a test module; the native FMUs come from conftest.py's one ``native`` fixture."""

import ast
from pathlib import Path

import pytest

pytestmark = pytest.mark.quick  # reads the sources only

TESTS = Path(__file__).parent
TEST_MODULES = {path.stem for path in TESTS.glob("test_*.py")}


def _tree(path):
    return ast.parse(path.read_text(), str(path))


def _imported(tree):
    """``(line, module)`` of every absolute import in a module, anywhere in it (in functions too)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module


def _fixtures(tree):
    """``(line, name)`` of every pytest fixture a module defines (its ``name=`` if given, else the function's)."""
    for node in ast.walk(tree):
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for decorator in node.decorator_list:
            call = decorator if isinstance(decorator, ast.Call) else None
            target = call.func if call else decorator
            if (isinstance(target, ast.Attribute) and target.attr == "fixture") or \
                    (isinstance(target, ast.Name) and target.id == "fixture"):
                names = [k.value.value for k in (call.keywords if call else ()) if k.arg == "name"]
                yield node.lineno, names[0] if names else node.name


def test_no_module_of_the_suite_imports_a_test_module_or_conftest():
    found = [f"{path.name}:{line} imports {module}" for path in sorted(TESTS.glob("*.py"))
             for line, module in _imported(_tree(path))
             if module.split(".")[0] in TEST_MODULES | {"conftest"}]
    assert found == [], "move what they share into helpers.py: " + "; ".join(found)


def test_only_conftest_defines_the_native_fixture():
    found = [f"{path.name}:{line}" for path in sorted(TESTS.glob("test_*.py"))
             for line, name in _fixtures(_tree(path)) if name == "native"]
    assert found == [], "take conftest.py's native fixture instead: " + ", ".join(found)
    assert [name for _, name in _fixtures(_tree(TESTS / "conftest.py"))].count("native") == 1
