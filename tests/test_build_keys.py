"""The incremental build's keys cover every file a built FMU is made from (issue 50, item 7: a change in one
kind of source file was not rebuilt, and no test noticed).

The independent answer is the C compiler's own: ``cc -MM -MG`` lists every file of the project that compiling
an FMU's C files reads (its sources and every header they include, however they are written). Each must be
among the files the FMU's key hashes (``incremental.file_digest``, watched). The Python FMUs' key must cover
every module their bundled core is made of, and the wrapper's C sources with their headers.
"""

import re
import shutil
import subprocess
import sysconfig
from pathlib import Path

import pytest

from crane_fmu import components, systems
from crane_fmu.build_scripts import incremental, native, one_fmu, wrapper
from crane_fmu.build_scripts.build_fmus import _sources as python_sources

pytestmark = pytest.mark.quick  # no build: the compiler lists the dependencies, the keys are computed

ROOT = Path(__file__).resolve().parent.parent
SRC = ROOT / "fmu_src"


@pytest.fixture
def compiler():
    found = shutil.which("cc") or shutil.which("gcc")
    if found is None:
        pytest.skip("no C compiler (cc, gcc): the dependencies cannot be listed")
    return found


@pytest.fixture
def hashed(monkeypatch):
    """The files every key computed in the test hashes (resolved paths)."""
    seen = set()
    digest = incremental.file_digest
    monkeypatch.setattr(incremental, "file_digest", lambda path: seen.add(Path(path).resolve()) or digest(path))
    return seen


def _read_by_compiler(compiler, c_files, include, defines=()):
    """Every file of fmu_src that compiling ``c_files`` reads (``-MG``: a generated header is left out)."""
    done = subprocess.run([compiler, "-MM", "-MG", *defines, *[f"-I{folder}" for folder in include],
                           *map(str, c_files)], capture_output=True, text=True, check=True)
    names = re.split(r"\s+", done.stdout.replace("\\\n", " "))
    files = {Path(name).resolve() for name in names if name and not name.endswith(":")}
    return {f for f in files if f.is_file() and f.is_relative_to(SRC)}


@pytest.mark.parametrize("version", [2, 3])
def test_a_native_fmus_key_covers_every_file_its_compilation_reads(compiler, hashed, version):
    tools = {"linux": compiler, "windows": None}
    missing = {}
    for kind in native.ported():
        component = components.get(kind)
        files = [native.source_path(n) for group in native._sources(component, version) for n in group]
        hashed.clear()
        incremental.native_key(component, version, tools, files)
        c_files = [native.source_path(n) for n in native.compiled(component, version) if n != "fmu_model.c"]
        read = _read_by_compiler(compiler, c_files, native.FOLDERS)
        if read - hashed:
            missing[kind] = sorted(p.name for p in read - hashed)
    assert missing == {}, f"files compiled into the FMU but not in its key: {missing}"


@pytest.mark.parametrize("version", [2, 3])
def test_a_one_fmus_key_covers_every_file_its_compilation_reads(compiler, hashed, version):
    tools = {"linux": compiler, "windows": None}
    missing = {}
    for name in systems.tagged("one-fmu"):
        system = systems.get(name)
        kinds = sorted({Path(str(fmu)).stem for fmu in system.instances.values()})
        if not all(components.get(k).native for k in kinds):
            continue
        hashed.clear()
        incremental.one_fmu_key(system, kinds, version, tools,
                                [native.source_path(n) for n in one_fmu.copied_sources(kinds, version)])
        c_files = [native.source_path(n) for n in one_fmu.compiled_sources(kinds, version)]
        read = _read_by_compiler(compiler, c_files, native.FOLDERS)
        if read - hashed:
            missing[name] = sorted(p.name for p in read - hashed)
    assert missing == {}, f"files compiled into the one-FMU but not in its key: {missing}"


@pytest.mark.parametrize("version", [2, 3])
def test_a_python_fmus_key_covers_its_core_and_its_wrappers_sources(compiler, hashed, version):
    """The core's modules (every file bundled), the wrapper's C files and the headers they read."""
    missing = {}
    wrapper_c = [wrapper.PYTHON / "python_model.c", wrapper.PYTHON / f"fmi{version}_loader.c",
                 *(wrapper.FRAMEWORK / f for f in (f"fmi{version}Functions.c", "instance.c", "continuous.c",
                                                   "py_repr.c"))]
    read = _read_by_compiler(compiler, wrapper_c, [wrapper.FRAMEWORK, wrapper.PYTHON, wrapper.fmi_headers()],
                             [f"-DFMI_VERSION={version}", "-I" + sysconfig.get_paths()["include"]])
    for component in components.registered():
        sources = python_sources(component, version).values()
        hashed.clear()
        incremental.python_fmu_key(component, version, sources)
        needed = read | {Path(p).resolve() for p in sources}
        if needed - hashed:
            missing[component.model_identifier] = sorted(p.name for p in needed - hashed)
    assert missing == {}, f"files built into the Python FMU but not in its key: {missing}"
