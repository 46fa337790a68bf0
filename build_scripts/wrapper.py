"""Compiles fmu_src/fmi2_wrapper.c, the FMUs' Linux binary, against this Python's libpython."""

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import fmu_src

SOURCE = Path(fmu_src.__file__).parent / "fmi2_wrapper.c"


class WrapperUnavailable(RuntimeError):
    """The wrapper cannot be compiled here (no C compiler, not Linux, or no shared libpython)."""


def compile_wrapper(out_dir):
    """Build the wrapper library into ``out_dir`` and return its path.

    It links against this interpreter's shared libpython, with libpython's folder
    as rpath, so a C host loads it without LD_PRELOAD or environment variables.
    """
    if not sys.platform.startswith("linux"):
        raise WrapperUnavailable(f"the wrapper is built for Linux only, this is {sys.platform}")
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        raise WrapperUnavailable("no C compiler found (set CC or install gcc)")
    library = sysconfig.get_config_var("LDLIBRARY") or ""
    libdir = sysconfig.get_config_var("LIBDIR")
    if not library.endswith(".so") or not libdir or not Path(libdir, library).exists():
        raise WrapperUnavailable(f"this Python has no shared libpython ({library!r} in {libdir!r})")
    out = Path(out_dir) / "fmi2_wrapper.so"
    command = [compiler, "-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-Wall",
               "-I", sysconfig.get_paths()["include"], str(SOURCE), "-o", str(out),
               "-L", libdir, "-l" + library[3:-3], f"-Wl,-rpath,{libdir}", "-ldl"]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise WrapperUnavailable(f"compiling {SOURCE.name} failed: {done.stderr.strip()}")
    return out
