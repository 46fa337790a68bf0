"""The FMUs outside this project: fmpy's command line, and a Python that cannot see crane_fmu."""

import csv
import math
import subprocess
import sys
import textwrap

import pytest

# Run inside a fresh interpreter: block every import of this project's packages,
# then simulate an FMU with plain fmpy and report what was imported.
ISOLATED = textwrap.dedent("""
    import importlib.abc, os, sys
    class Block(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("crane_fmu", "fmu_src", "build_scripts"):
                raise ImportError("blocked: " + name)
    sys.meta_path.insert(0, Block())
    sys.path = [p for p in sys.path if p and not os.path.exists(os.path.join(p, "crane_fmu"))]
    try:
        import crane_fmu
    except ImportError:
        pass
    else:
        raise SystemExit("crane_fmu is importable")
    from fmpy import simulate_fmu
    start = {k: float(v) for k, v in (arg.split("=") for arg in sys.argv[3:])}
    res = simulate_fmu(sys.argv[1], stop_time=2.0, output_interval=0.01, start_values=start)
    core = sorted(m for m in sys.modules if m.startswith("crane_core2_"))
    print(repr(float(res[sys.argv[2]][-1])), core[0], sys.modules[core[0]].__file__)
""")


def test_plant_runs_under_fmpy_simulate_command(crane_fmus, tmp_path):
    out = tmp_path / "free.csv"
    subprocess.run([sys.executable, "-m", "fmpy", "simulate", str(crane_fmus["plant"]),
                    "--output-file", str(out)], check=True, cwd=tmp_path, capture_output=True, timeout=120)
    rows = list(csv.DictReader(out.open()))
    assert float(rows[0]["time"]) == 0.0 and float(rows[-1]["time"]) == 20.0  # the default experiment
    assert float(rows[0]["theta1"]) == pytest.approx(math.pi / 18, rel=1e-15)
    assert max(abs(float(r["theta2"])) for r in rows) > 0.1  # the payload swings


def test_controller_runs_under_fmpy_simulate_command(crane_fmus, tmp_path):
    out = tmp_path / "u.csv"
    subprocess.run([sys.executable, "-m", "fmpy", "simulate", str(crane_fmus["controller"]),
                    "--stop-time", "1", "--start-values", "theta1", "0.1", "--output-file", str(out)],
                   check=True, cwd=tmp_path, capture_output=True, timeout=120)
    rows = list(csv.DictReader(out.open()))
    assert len(rows) > 10 and all(float(r["u"]) != 0.0 for r in rows)


@pytest.mark.parametrize("name, output, args", [("plant", "theta1", []), ("controller", "u", ["theta1=0.1"])])
def test_fmu_runs_where_crane_fmu_is_not_importable(crane_fmus, tmp_path, name, output, args):
    proc = subprocess.run([sys.executable, "-I", "-c", ISOLATED, str(crane_fmus[name]), output, *args],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    value, core, path = proc.stdout.splitlines()[-1].split(" ")
    assert math.isfinite(float(value)) and float(value) != 0.0
    assert core.startswith("crane_core2_") and "resources" in path  # the FMU's bundled core ran


@pytest.mark.quick
def test_importing_crane_fmu_imports_no_numeric_library():
    code = ("import sys, crane_fmu, crane_fmu.model; "
            "print([m for m in ('fmpy', 'numpy', 'scipy', 'pythonfmu') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.quick
def test_runtime_core_imports_only_the_standard_library():
    import ast
    from pathlib import Path

    import crane_fmu.model

    for path in Path(crane_fmu.model.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                names = [node.module]
            else:
                continue
            for name in names:
                assert name.split(".")[0] in sys.stdlib_module_names, f"{path.name} imports {name}"
