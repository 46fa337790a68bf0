"""Compiles the Python FMUs' Linux binaries: per FMI version, a loader and the FMI wrapper.

``fmu_src/python/fmi<N>_loader.c`` becomes ``binaries/<platform>/<model>.so``: it has no
dependency on Python; when the FMU is instantiated it finds a CPython 3.10 or newer
(``fmu_src/python/find_python.h``: the host's own, ``CRANE_FMU_PYTHON``, the one recorded
here, the dynamic linker's search, python3 on PATH) and loads the wrapper, shipped next to
it as ``PythonWrapper.so``: the FMI framework of every FMU (``fmu_src/framework``) over the
Python model (``fmu_src/python/python_model.c``). The wrapper is compiled against Python's
limited API (3.10) and not linked to any libpython, so one build runs with every CPython
from 3.10 on. Both include the official FMI headers that fmpy ships.
"""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import fmpy

import crane_fmu.fmu_src as fmu_src

SOURCES = Path(fmu_src.__file__).parent
FRAMEWORK, PYTHON = SOURCES / "framework", SOURCES / "python"
# the other CPythons' sonames, newest first, tried after the recorded one (find_python.h)
FALLBACK_SONAMES = tuple(f"libpython3.{minor}.so.1.0" for minor in (13, 12, 11, 10))


class WrapperUnavailable(RuntimeError):
    """The binaries cannot be compiled here (no C compiler, not Linux, or no shared libpython)."""


def fmi_headers():
    """The folder of the official FMI 2.0 and 3.0 headers, as shipped by fmpy."""
    folder = Path(fmpy.__file__).parent / "c-code"
    if not (folder / "fmi2Functions.h").exists() or not (folder / "fmi3Functions.h").exists():
        raise WrapperUnavailable(f"fmpy's FMI headers are missing from {folder}")
    return folder


def _run(command, source):
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:  # a bug, not a missing tool: stop the build
        raise RuntimeError(f"compiling {source.name} failed: {done.stderr.strip()}")


def compile_binaries(out_dir, libpython=None, fallback_sonames=FALLBACK_SONAMES):
    """Build ``{fmi_version: (loader, wrapper)}`` for FMI 2.0 and 3.0 into ``out_dir``.

    ``libpython`` overrides the libpython recorded as the loader's guess (default:
    this Python's); the tests use missing ones, and fewer ``fallback_sonames``, to see
    each step of the search and its message.
    """
    if not sys.platform.startswith("linux"):
        raise WrapperUnavailable(f"the binaries are built for Linux only, this is {sys.platform}")
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        raise WrapperUnavailable("no C compiler found (set CC or install gcc)")
    library = sysconfig.get_config_var("LDLIBRARY") or ""
    soname = sysconfig.get_config_var("INSTSONAME") or library
    libdir = sysconfig.get_config_var("LIBDIR")
    if not library.endswith(".so") or not libdir or not Path(libdir, library).exists():
        raise WrapperUnavailable(f"this Python has no shared libpython ({library!r} in {libdir!r})")
    libpython = libpython or str(Path(libdir, soname))
    out_dir = Path(out_dir)
    flags = ["-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-Wall", "-Werror", "-I", str(FRAMEWORK),
             "-I", str(PYTHON), "-I", str(fmi_headers())]
    binaries = {}
    for version in (2, 3):
        folder = out_dir / f"fmi{version}"
        folder.mkdir(parents=True, exist_ok=True)
        loader, wrapper = folder / "loader.so", folder / "PythonWrapper.so"
        source = PYTHON / f"fmi{version}_loader.c"
        _run([compiler, *flags, f'-DLIBPYTHON="{libpython}"', f'-DLIBPYTHON_SONAME="{Path(libpython).name}"',
              f'-DFALLBACK_SONAMES="{":".join(fallback_sonames)}"', str(source), "-o", str(loader), "-ldl",
              "-lpthread"], source)
        sources = [PYTHON / "python_model.c", *(FRAMEWORK / f for f in (
            f"fmi{version}Functions.c", "instance.c", "continuous.c", "py_repr.c"))]
        _run([compiler, *flags, f"-DFMI_VERSION={version}", "-I", sysconfig.get_paths()["include"],
              *map(str, sources), "-o", str(wrapper), "-lpthread", "-lm"], sources[0])
        binaries[version] = loader, wrapper
    return binaries
