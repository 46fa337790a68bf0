"""The FMUs in a plain C program (dlopen, no LD_PRELOAD), with every CPython from 3.10 to 3.13.

One C host, compiled for FMI 2.0 or 3.0 against the official headers that fmpy ships, runs
the closed loop, or with ``probe`` only instantiates the plant. The FMUs find their Python
themselves (``fmu_src/find_python.h``); these tests walk each place they look.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import PYTHONS, compile_hosts, installed_python, unpack_fmu

from crane_fmu.build_scripts.build_fmus import build_fmu, fmi3_dir
from crane_fmu.build_scripts.wrapper import compile_binaries
from crane_fmu.cosim import simulate
from crane_fmu.model import plant
from crane_fmu.model.tables import STATE

HOST = r"""
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#define SYM(so, name) ((name##TYPE *)dlsym(so, #name))
#if FMI == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String format, ...) {
    va_list args; va_start(args, format);
    fprintf(stderr, "[%d] ", status); vfprintf(stderr, format, args); fputc('\n', stderr);
    va_end(args);
}
static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
typedef fmi2Component Component;
typedef fmi2GetRealTYPE Get;
typedef fmi2SetRealTYPE Set;
typedef fmi2DoStepTYPE Step;
#define GET "fmi2GetReal"
#define SET "fmi2SetReal"
#define STEP "fmi2DoStep"
#define INSTANTIATE(so, name, token, resources) \
    SYM(so, fmi2Instantiate)(name, fmi2CoSimulation, token, resources, &callbacks, fmi2False, fmi2True)
#define INITIALISE(so, c) (SYM(so, fmi2SetupExperiment)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) || \
    SYM(so, fmi2EnterInitializationMode)(c) || SYM(so, fmi2ExitInitializationMode)(c))
#define GET_REALS(f, vr, n, v) f.get(f.c, vr, n, v)
#define SET_REALS(f, vr, n, v) f.set(f.c, vr, n, v)
#define DO_STEP(f, t, h) f.step(f.c, t, h, fmi2True)
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    fprintf(stderr, "[%d] %s\n", status, message);
}
typedef fmi3Instance Component;
typedef fmi3GetFloat64TYPE Get;
typedef fmi3SetFloat64TYPE Set;
typedef fmi3DoStepTYPE Step;
#define GET "fmi3GetFloat64"
#define SET "fmi3SetFloat64"
#define STEP "fmi3DoStep"
#define INSTANTIATE(so, name, token, resources) SYM(so, fmi3InstantiateCoSimulation)(name, token, resources, \
    fmi3False, fmi3True, fmi3False, fmi3False, NULL, 0, NULL, logger, NULL)
#define INITIALISE(so, c) (SYM(so, fmi3EnterInitializationMode)(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) || \
    SYM(so, fmi3ExitInitializationMode)(c))
#define GET_REALS(f, vr, n, v) f.get(f.c, vr, n, v, n)
#define SET_REALS(f, vr, n, v) f.set(f.c, vr, n, v, n)
static fmi3Boolean flag;
static fmi3Float64 last;
#define DO_STEP(f, t, h) f.step(f.c, t, h, fmi3True, &flag, &flag, &flag, &last)
#endif

typedef struct { Component c; Get *get; Set *set; Step *step; } Fmu;
static Fmu load(const char *library, const char *name, const char *token, const char *resources) {
    void *so = dlopen(library, RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); exit(3); }
    Fmu f = {INSTANTIATE(so, name, token, resources), (Get *)dlsym(so, GET), (Set *)dlsym(so, SET),
             (Step *)dlsym(so, STEP)};
    if (!f.c) { printf("instance NULL\n"); exit(4); }
    if (INITIALISE(so, f.c)) exit(5);
    return f;
}
#define CHECK(x) if ((x) > 1) { fprintf(stderr, "call failed at step %d\n", k); return 6; }
int main(int argc, char **argv) {
    /* probe plant.so plant-token plant-resources: instantiate only */
    if (argc == 5 && !strcmp(argv[1], "probe")) { load(argv[2], "plant", argv[3], argv[4]); return 0; }
    /* plant.so token resources ctrl.so token resources steps h, then value references:
       6 plant states, 6 controller inputs, controller u, plant u */
    if (argc != 9 + 14) return 2;
    Fmu plant = load(argv[1], "plant", argv[2], argv[3]);
    Fmu ctrl = load(argv[4], "controller", argv[5], argv[6]);
    int steps = atoi(argv[7]);
    double h = atof(argv[8]), states[6], u[1];
    unsigned state_vr[6], input_vr[6], u_out[1], u_in[1];
    for (int i = 0; i < 6; i++) { state_vr[i] = atoi(argv[9 + i]); input_vr[i] = atoi(argv[15 + i]); }
    u_out[0] = atoi(argv[21]); u_in[0] = atoi(argv[22]);
    for (int k = 0; k <= steps; k++) {
        double t = k * h;
        CHECK(GET_REALS(plant, state_vr, 6, states));
        CHECK(SET_REALS(ctrl, input_vr, 6, states));
        CHECK(GET_REALS(ctrl, u_out, 1, u));
        CHECK(SET_REALS(plant, u_in, 1, u));
        printf("%.17g", t);
        for (int i = 0; i < 6; i++) printf(",%.17g", states[i]);
        printf(",%.17g\n", u[0]);
        if (k < steps) { CHECK(DO_STEP(plant, t, h)); CHECK(DO_STEP(ctrl, t, h)); }
    }
    return 0;
}
"""

CLEAN = ("LD_PRELOAD", "LD_LIBRARY_PATH", "PYTHONPATH", "PYTHONHOME", "CRANE_FMU_PYTHON")


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    return compile_hosts(HOST, tmp_path_factory.mktemp("hosts"))


def _environment(**extra):
    env = {k: v for k, v in os.environ.items() if k not in CLEAN}
    env.update(extra)
    return env


def _closed_loop(host, fmus, tmp_path, steps=500, h=0.002, **env):
    """The C host's rows ``[t, 6 plant states, u]`` and its log, or an assertion with its output."""
    plant_md, plant_so, plant_token, plant_res = unpack_fmu(fmus["plant"], tmp_path / "plant")
    ctrl_md, ctrl_so, ctrl_token, ctrl_res = unpack_fmu(fmus["controller"], tmp_path / "controller")
    vr = {("plant", v.name): v.valueReference for v in plant_md.modelVariables}
    vr.update({("controller", v.name): v.valueReference for v in ctrl_md.modelVariables})
    refs = ([vr["plant", s] for s in STATE] + [vr["controller", s] for s in STATE]
            + [vr["controller", "u"], vr["plant", "u"]])
    proc = subprocess.run([str(host), plant_so, plant_token, plant_res, ctrl_so, ctrl_token, ctrl_res, str(steps),
                           str(h), *map(str, refs)], capture_output=True, text=True, timeout=300,
                          env=_environment(**env), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    return np.array([[float(x) for x in line.split(",")] for line in proc.stdout.splitlines()]), proc.stderr


@pytest.fixture(scope="module")
def reference(crane_fmus, connections):
    """Our master's result for the C host's run, ``[t, 6 plant states, u]`` per row."""
    ours = simulate(crane_fmus, connections, 1.0, 0.002).columns()
    return np.column_stack([ours["time"]] + [ours["plant." + s] for s in STATE] + [ours["controller.u"]])


@pytest.fixture(scope="module")
def fmi3_fmus(fmu_dir):
    folder = fmi3_dir(fmu_dir)
    return {"plant": folder / "CranePlant.fmu", "controller": folder / "BacksteppingController.fmu"}


@pytest.mark.parametrize("version", [2, 3])
def test_c_host_runs_the_closed_loop_bit_for_bit_like_our_master(hosts, crane_fmus, fmi3_fmus, reference, version,
                                                                 tmp_path):
    rows, log = _closed_loop(hosts[version], crane_fmus if version == 2 else fmi3_fmus, tmp_path)
    assert rows.shape == reference.shape == (501, 8)
    assert np.array_equal(rows, reference)  # same Python code, same inputs: bit for bit
    # with logging on, the FMU says which Python it took and how it found it
    assert "[0] using CPython 3.11" in log and "found by: the libpython recorded at build time" in log


@pytest.mark.parametrize("python", list(PYTHONS))
@pytest.mark.parametrize("version", [2, 3])
def test_one_build_runs_with_every_cpython_from_3_10_to_3_13(hosts, crane_fmus, fmi3_fmus, reference, version,
                                                             python, tmp_path):
    """The FMUs built once (here, by 3.11) run with each CPython named by CRANE_FMU_PYTHON: same numbers."""
    executable = installed_python(python)
    rows, log = _closed_loop(hosts[version], crane_fmus if version == 2 else fmi3_fmus, tmp_path,
                             CRANE_FMU_PYTHON=executable)
    minor = python.split("-")[-1]
    assert f"using CPython {minor}." in log and f"found by: CRANE_FMU_PYTHON={executable}" in log, log
    assert np.array_equal(rows, reference)


FMPY_RUN = """
import sys
import numpy as np
from fmpy import simulate_fmu
result = simulate_fmu(sys.argv[1], stop_time=1.0, output_interval=0.01, output=["theta1", "x"])
np.save(sys.argv[2], np.column_stack([result["time"], result["theta1"], result["x"]]))
print(sys.version)
"""


def test_fmpy_under_another_cpython_runs_the_fmus_built_here(crane_fmus, fmi3_fmus, tmp_path):
    """fmpy on CPython 3.12 (a fresh venv) loads the FMUs built by this Python: the host's Python is used."""
    import fmpy

    executable = installed_python("3.12")
    venv = tmp_path / "venv312"
    subprocess.run([executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    # this pip installs into it: fmpy and what simulate_fmu imports (its other requirements serve other commands)
    pip = subprocess.run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"), "install", "-q",
                          "--no-deps", f"fmpy=={fmpy.__version__}", "numpy", "lxml", "attrs"],
                         capture_output=True, text=True, timeout=600)
    if pip.returncode != 0:
        pytest.skip(f"cannot install fmpy into a CPython 3.12 venv: {pip.stderr[-500:]}")
    (tmp_path / "run.py").write_text(FMPY_RUN)
    for fmu in (crane_fmus["plant"], fmi3_fmus["plant"]):
        theirs, ours = tmp_path / "theirs.npy", tmp_path / "ours.npy"
        proc = subprocess.run([str(venv / "bin" / "python"), str(tmp_path / "run.py"), str(fmu), str(theirs)],
                              capture_output=True, text=True, timeout=300, env=_environment())
        assert proc.returncode == 0 and proc.stdout.startswith("3.12"), proc.stderr[-3000:]
        subprocess.run([sys.executable, str(tmp_path / "run.py"), str(fmu), str(ours)], check=True,
                       capture_output=True, env=_environment())
        assert np.array_equal(np.load(theirs), np.load(ours)), fmu


@pytest.fixture(scope="module")
def lost_fmus(tmp_path_factory):
    """Plants whose recorded libpython is missing, with no fallback sonames: ``{version: FMU}``."""
    folder = tmp_path_factory.mktemp("lost")
    binaries = compile_binaries(folder / "bin", libpython="/nonexistent/libpython9.9.so.1.0", fallback_sonames=())
    return {2: build_fmu(plant.COMPONENT, folder / "fmi2", binaries[2]),
            3: build_fmu(plant.COMPONENT, folder / "fmi3", binaries[3], fmi_version=3)}


def _probe(host, fmu, tmp_path, **env):
    _, library, token, resources = unpack_fmu(fmu, tmp_path / "probe")
    return subprocess.run([str(host), "probe", library, token, resources], capture_output=True, text=True,
                          timeout=120, env=_environment(**env), cwd=tmp_path)


@pytest.mark.parametrize("version", [2, 3])
def test_no_python_found_is_one_message_listing_every_place_tried(hosts, lost_fmus, version, tmp_path):
    proc = _probe(hosts[version], lost_fmus[version], tmp_path, PATH=str(tmp_path))
    assert proc.returncode == 4 and "instance NULL" in proc.stdout, proc.stdout + proc.stderr
    function = "fmi2Instantiate" if version == 2 else "fmi3InstantiateCoSimulation"
    message = proc.stderr.strip()
    assert message.count("\n") == 0 and message.startswith(f"[3] {function}: found no CPython 3.10 or newer")
    for place in ["the host process (no Python in it)", "CRANE_FMU_PYTHON (not set)",
                  "the libpython recorded at build time, /nonexistent/libpython9.9.so.1.0 (",
                  "the dynamic linker's search for libpython9.9.so.1.0 (", "python3 on PATH (", "python on PATH (",
                  "Set CRANE_FMU_PYTHON to a Python executable"]:
        assert place in message, place


def test_each_place_of_the_search_finds_a_python(hosts, lost_fmus, tmp_path):
    """CRANE_FMU_PYTHON naming a libpython; python3 on PATH; and, in the real build, the linker's search."""
    debian = "/usr/lib/x86_64-linux-gnu/libpython3.11.so.1.0"
    if not Path(debian).exists():
        pytest.skip("Debian's libpython3.11 is not installed here")
    proc = _probe(hosts[2], lost_fmus[2], tmp_path, CRANE_FMU_PYTHON=debian)
    assert proc.returncode == 0 and f"from {debian} (found by: CRANE_FMU_PYTHON={debian})" in proc.stderr, \
        proc.stderr
    python312 = Path(installed_python("3.12"))
    (tmp_path / "bin").mkdir()
    (tmp_path / "bin" / "python3").symlink_to(python312)
    proc = _probe(hosts[3], lost_fmus[3], tmp_path, PATH=str(tmp_path / "bin"))
    assert proc.returncode == 0 and "using CPython 3.12." in proc.stderr, proc.stderr
    assert "(found by: python3 on PATH)" in proc.stderr
    # the recorded libpython gone, its soname is found by the dynamic linker (Debian's, in /usr/lib)
    binaries = compile_binaries(tmp_path / "bin2", libpython="/nonexistent/libpython3.11.so.1.0")
    fmu = build_fmu(plant.COMPONENT, tmp_path / "fmus", binaries[2])
    proc = _probe(hosts[2], fmu, tmp_path, PATH=str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert "found by: the dynamic linker's search for libpython3.11.so.1.0)" in proc.stderr, proc.stderr


def test_the_binaries_name_no_libpython_and_use_only_the_limited_api(tmp_path):
    """The loader needs no Python; the wrapper leaves Python's symbols to the libpython found."""
    binaries = compile_binaries(tmp_path)
    for version, (loader, wrapper) in binaries.items():
        for library in (loader, wrapper):
            needed = subprocess.run(["readelf", "-d", str(library)], capture_output=True, text=True).stdout
            assert "libpython" not in needed, (version, library.name)
        undefined = subprocess.run(["nm", "-D", "--undefined-only", str(wrapper)], capture_output=True,
                                   text=True).stdout.split()
        python = {s for s in undefined if s.startswith(("Py", "_Py"))}
        assert "PyGILState_Ensure" in python and "Py_InitializeEx" in python
        assert not {s for s in python if s.startswith("_Py") and s not in LIMITED_PRIVATE}, python


# the few underscore names that the limited API's macros call (reference counting, Py_BuildValue, singletons)
LIMITED_PRIVATE = {"_Py_Dealloc", "_Py_BuildValue_SizeT", "_Py_NoneStruct", "_Py_TrueStruct", "_Py_FalseStruct"}
