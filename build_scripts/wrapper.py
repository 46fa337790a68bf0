"""Compiles the FMUs' Linux binaries against this Python: the loader and the FMI wrapper.

``fmu_src/fmi2_loader.c`` becomes ``binaries/linux64/<model>.so``: it has no dependency on
Python, loads this Python's libpython when an FMU is instantiated (with a clear log message
where it is missing) and forwards every call to ``fmu_src/fmi2_wrapper.c``, shipped next to
it as ``PythonWrapper.so`` and linked against libpython.
"""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import crane_fmu.fmu_src as fmu_src

WRAPPER = Path(fmu_src.__file__).parent / "fmi2_wrapper.c"
LOADER = Path(fmu_src.__file__).parent / "fmi2_loader.c"


class WrapperUnavailable(RuntimeError):
    """The binaries cannot be compiled here (no C compiler, not Linux, or no shared libpython)."""


def _run(command, source):
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:  # a bug, not a missing tool: stop the build
        raise RuntimeError(f"compiling {source.name} failed: {done.stderr.strip()}")


def compile_binaries(out_dir, libpython=None):
    """Build ``(loader, wrapper)`` into ``out_dir`` and return their paths.

    ``libpython`` overrides the Python library the loader looks for (the tests
    use a missing one to see the loader's message).
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
    soname = Path(libpython).name if libpython != str(Path(libdir, soname)) else soname
    out_dir = Path(out_dir)
    loader, wrapper = out_dir / "loader.so", out_dir / "PythonWrapper.so"
    flags = ["-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-Wall"]
    _run([compiler, *flags, f'-DLIBPYTHON="{libpython}"', f'-DLIBPYTHON_SONAME="{soname}"', str(LOADER),
          "-o", str(loader), "-ldl"], LOADER)
    _run([compiler, *flags, "-I", sysconfig.get_paths()["include"], str(WRAPPER), "-o", str(wrapper),
          "-L", libdir, "-l" + library[3:-3], f"-Wl,-rpath,{libdir}", "-ldl"], WRAPPER)
    return loader, wrapper
