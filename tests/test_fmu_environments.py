"""Every built FMU where other people's tools run it: a clean environment, each CPython, a careless host.

A C host, compiled for FMI 2.0 and 3.0 against the official headers, runs one FMU alone for
``STEPS`` steps with inputs that vary with time, and prints every Real output. It is started the
way a service, a CI job or a tool launched from a desktop menu starts: ``env -i
PATH=/usr/bin:/bin``, no HOME, no pyenv shims, no PYTHONHOME. The FMUs must find a Python and
its standard library on their own (``fmu_src/find_python.h``) and, built once, give the same
bits with each CPython (the bundled core uses no float path that changed between versions,
such as ``sum()`` in 3.12). A second mode hands the FMU state functions pointers that are not
the FMU's states, as Reference-FMUs' fmusim v0.0.39 does: each must get an error, never a crash.
"""

import glob
import os
import subprocess

import numpy as np
import pytest
from helpers import PYTHONS, compile_hosts, installed_python, unpack_fmu

from crane_fmu import components
from crane_fmu.build_scripts.build_fmus import fmi3_dir

HOST = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#define SYM(name) ((name##TYPE *)dlsym(so, #name))
#define EXPECT(call, want) do { int got_ = (call); if (got_ != (want)) { \
    printf("%s gave %d, not %d\n", #call, got_, (want)); return 7; } } while (0)
#if FMI == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String f, ...) {
    va_list args; va_start(args, f);
    fprintf(stderr, "[%d] ", s); vfprintf(stderr, f, args); fputc('\n', stderr);
    va_end(args);
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
typedef fmi2FMUstate State;
#define NEW(name) SYM(fmi2Instantiate)(name, fmi2CoSimulation, token, resources, &cb, fmi2False, fmi2True)
#define INIT(c) (SYM(fmi2SetupExperiment)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) || \
    SYM(fmi2EnterInitializationMode)(c) || SYM(fmi2ExitInitializationMode)(c))
#define SET(c, vr, n, v) SYM(fmi2SetReal)(c, vr, n, v)
#define GET(c, vr, n, v) SYM(fmi2GetReal)(c, vr, n, v)
#define STEP(c, t, h) SYM(fmi2DoStep)(c, t, h, fmi2True)
#define GET_STATE(c, s) SYM(fmi2GetFMUstate)(c, s)
#define SET_STATE(c, s) SYM(fmi2SetFMUstate)(c, s)
#define FREE_STATE(c, s) SYM(fmi2FreeFMUstate)(c, s)
#define STATE_SIZE(c, s, n) SYM(fmi2SerializedFMUstateSize)(c, s, n)
#define SERIALIZE(c, s, b, n) SYM(fmi2SerializeFMUstate)(c, s, b, n)
#define DESERIALIZE(c, b, n, s) SYM(fmi2DeSerializeFMUstate)(c, b, n, s)
#define FREE(c) SYM(fmi2FreeInstance)(c)
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    fprintf(stderr, "[%d] %s\n", s, m);
}
typedef fmi3FMUState State;
static fmi3Boolean flag;
static fmi3Float64 last;
#define NEW(name) SYM(fmi3InstantiateCoSimulation)(name, token, resources, fmi3False, fmi3True, fmi3False, \
    fmi3False, NULL, 0, NULL, logger, NULL)
#define INIT(c) (SYM(fmi3EnterInitializationMode)(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) || \
    SYM(fmi3ExitInitializationMode)(c))
#define SET(c, vr, n, v) SYM(fmi3SetFloat64)(c, vr, n, v, n)
#define GET(c, vr, n, v) SYM(fmi3GetFloat64)(c, vr, n, v, n)
#define STEP(c, t, h) SYM(fmi3DoStep)(c, t, h, fmi3True, &flag, &flag, &flag, &last)
#define GET_STATE(c, s) SYM(fmi3GetFMUState)(c, s)
#define SET_STATE(c, s) SYM(fmi3SetFMUState)(c, s)
#define FREE_STATE(c, s) SYM(fmi3FreeFMUState)(c, s)
#define STATE_SIZE(c, s, n) SYM(fmi3SerializedFMUStateSize)(c, s, n)
#define SERIALIZE(c, s, b, n) SYM(fmi3SerializeFMUState)(c, s, b, n)
#define DESERIALIZE(c, b, n, s) SYM(fmi3DeserializeFMUState)(c, b, n, s)
#define FREE(c) SYM(fmi3FreeInstance)(c)
#endif

/* run: the parameters set, then every Real output at each step, input i held at 0.05 sin(0.9 t + i)
   over each step. */
static int run(void *so, const char *token, const char *resources, int steps, double h, int nin,
               const unsigned *in, int nout, const unsigned *out, int npar, const unsigned *par, const double *value) {
    void *c = NEW("alone");
    if (!c) return 5;
    for (int i = 0; i < npar; i++) if (SET(c, &par[i], 1, &value[i]) > 1) return 5;
    if (INIT(c)) return 5;
    double u[64], y[64];
    for (int k = 0; k <= steps; k++) {
        double t = k * h;
        for (int i = 0; i < nin; i++) u[i] = 0.05 * sin(0.9 * t + i);
        if (nin && SET(c, in, nin, u) > 1) return 6;
        if (GET(c, out, nout, y) > 1) return 6;
        printf("%.17g", t);
        for (int i = 0; i < nout; i++) printf(",%.17g", y[i]);
        printf("\n");
        if (k < steps && STEP(c, t, h) > 1) return 6;
    }
    FREE(c);
    return 0;
}

/* abuse: pointers that are not this instance's FMU states, each refused; then the instance works. */
static int abuse(void *so, const char *token, const char *resources) {
    void *c = NEW("abused"), *other = NEW("other");
    if (!c || !other || INIT(c) || INIT(other)) return 5;
    State state = NULL, foreign = NULL, freed = NULL, garbage = (State)&garbage;
    char bytes[64] = "not a state";
    size_t size = 0;
    EXPECT(GET_STATE(c, &state), 0);
    EXPECT(GET_STATE(other, &foreign), 0);
    EXPECT(GET_STATE(c, &freed), 0);
    State copy = freed;
    EXPECT(FREE_STATE(c, &copy), 0);  /* freed: a dangling pointer now */
    EXPECT(FREE_STATE(c, (State *)state), 3);   /* the state where its address belongs (fmusim) */
    EXPECT(FREE_STATE(c, &garbage), 3);
    EXPECT(FREE_STATE(c, &foreign), 3);          /* another instance's */
    EXPECT(FREE_STATE(c, &freed), 3);            /* freed before */
    EXPECT(SET_STATE(c, garbage), 3);
    EXPECT(SET_STATE(c, foreign), 3);
    EXPECT(SET_STATE(c, freed), 3);
    EXPECT(STATE_SIZE(c, garbage, &size), 3);
    EXPECT(STATE_SIZE(c, (State)&state, &size), 3);
    EXPECT(SERIALIZE(c, foreign, bytes, sizeof bytes), 3);
    EXPECT(GET_STATE(c, (State *)state), 3);
    EXPECT(GET_STATE(c, &garbage), 3);
    EXPECT(DESERIALIZE(c, bytes, sizeof bytes, &garbage), 3);
    /* the instance was refused, not broken: its own state still works */
    EXPECT(STEP(c, 0.0, 0.001), 0);
    EXPECT(SET_STATE(c, state), 0);
    EXPECT(STEP(c, 0.0, 0.001), 0);
    EXPECT(FREE_STATE(c, &state), 0);
    EXPECT(FREE_STATE(other, &foreign), 0);
    FREE(c);
    FREE(other);
    printf("ok\n");
    return 0;
}

/* one run: argv = run library token resources steps h nin vr... nout vr... [vr=value ...] */
static int run_command(int argc, char **argv) {
    void *so = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
    unsigned in[64], out[64], par[64];
    double value[64];
    int nin = atoi(argv[6]), nout = atoi(argv[7 + nin]), npar = argc - 8 - nin - nout;
    for (int i = 0; i < nin; i++) in[i] = (unsigned)atoi(argv[7 + i]);
    for (int i = 0; i < nout; i++) out[i] = (unsigned)atoi(argv[8 + nin + i]);
    for (int i = 0; i < npar; i++) sscanf(argv[8 + nin + nout + i], "%u=%lf", &par[i], &value[i]);
    return run(so, argv[2], argv[3], atoi(argv[4]), atof(argv[5]), nin, in, nout, out, npar, par, value);
}
int main(int argc, char **argv) {
    /* run ... [-- run ...]: each FMU in turn in this one process, its rows then a line "end"
       |  abuse library token resources */
    if (!strcmp(argv[1], "abuse")) {
        void *so = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
        if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
        return abuse(so, argv[3], argv[4]);
    }
    for (int first = 1, last; first < argc; first = last + 1) {
        for (last = first; last < argc && strcmp(argv[last], "--"); last++) {}
        int status = run_command(last - first, argv + first);
        if (status) return status;
        printf("end\n");
        fflush(stdout);
    }
    return 0;
}"""

STEPS, H = 300, 0.01
CLEAN_PATH = "/usr/bin:/bin"  # no pyenv shims, no venv: what `env -i PATH=/usr/bin:/bin` leaves
COMPONENTS = sorted(c.model_identifier for c in components.registered())
PARAMETERS = {"TrajectoryPlanner": {"x_d": 2.0}}  # its default move is none: all outputs zero


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    return compile_hosts(HOST.replace("#include <dlfcn.h>", "#include <dlfcn.h>\n#include <stdarg.h>", 1),
                         tmp_path_factory.mktemp("env_hosts"))


def _fmu(fmu_dir, name, version):
    return (fmu_dir if version == 2 else fmi3_dir(fmu_dir)) / f"{name}.fmu"


def _unpacked(fmu, tmp_path):
    return unpack_fmu(fmu, tmp_path / f"{fmu.stem}-{fmu.parent.name}")


def _arguments(fmu, tmp_path):
    """The host's ``run`` arguments for ``fmu``: every Real input and output; and the number of outputs."""
    md, library, token, resources = _unpacked(fmu, tmp_path)
    real = [v for v in md.modelVariables if v.type in ("Real", "Float64")]
    inputs = [str(v.valueReference) for v in real if v.causality == "input"]
    outputs = [str(v.valueReference) for v in real if v.causality == "output"]
    parameters = [f"{v.valueReference}={PARAMETERS[md.coSimulation.modelIdentifier][v.name]!r}" for v in real
                  if v.name in PARAMETERS.get(md.coSimulation.modelIdentifier, {})]
    return ["run", library, token, resources, str(STEPS), str(H), str(len(inputs)), *inputs, str(len(outputs)),
            *outputs, *parameters], len(outputs)


def _run_each(host, fmus, tmp_path, env):
    """Every Real output of each of ``fmus``, each run alone in turn in one C host process under exactly
    ``env``: ``([rows of each], log)``."""
    runs = [_arguments(fmu, tmp_path) for fmu in fmus]
    command = [str(host), *[arg for i, (args, _) in enumerate(runs) for arg in (["--"] if i else []) + args]]
    proc = subprocess.run(command, capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path)
    names = ", ".join(fmu.name for fmu in fmus)
    assert proc.returncode == 0, f"{names} exited {proc.returncode}: {proc.stdout[-500:]}{proc.stderr[-2000:]}"
    blocks = proc.stdout.split("end\n")
    assert len(blocks) == len(fmus) + 1 and not blocks[-1], names
    results = []
    for fmu, block, (_, n_outputs) in zip(fmus, blocks, runs):
        rows = np.array([[float(x) for x in line.split(",")] for line in block.splitlines()])
        assert rows.shape == (STEPS + 1, n_outputs + 1) and np.isfinite(rows).all(), fmu.name
        results.append(rows)
    return results, proc.stderr


def _run_alone(host, fmu, tmp_path, env):
    """Every Real output of ``fmu`` run alone in the C host under exactly ``env``: ``(rows, log)``."""
    (rows,), log = _run_each(host, [fmu], tmp_path, env)
    return rows, log


@pytest.mark.parametrize("version", [2, 3])
def test_every_fmu_runs_in_a_clean_environment(hosts, fmu_dir, version, tmp_path):
    """``env -i PATH=/usr/bin:/bin``: the FMU finds the Python that built it and that Python's own
    standard library (it used to import Debian's, the first python3 on that PATH, and fail)."""
    for name in COMPONENTS:
        _, log = _run_alone(hosts[version], _fmu(fmu_dir, name, version), tmp_path, {"PATH": CLEAN_PATH})
        assert "found by: the libpython recorded at build time" in log and ", its home /" in log, log


@pytest.mark.parametrize("version", [2, 3])
def test_one_build_gives_the_same_bits_with_every_cpython(hosts, fmu_dir, version, tmp_path):
    """Each component, built once, run with each of the five CPythons named by CRANE_FMU_PYTHON in a
    clean environment (one host process per CPython runs every component in turn): identical outputs, bit for
    bit (the build's own Python gives the reference)."""
    fmus = [_fmu(fmu_dir, name, version) for name in COMPONENTS]
    results = {}
    for python in PYTHONS:
        results[python], log = _run_each(hosts[version], fmus, tmp_path, {"PATH": CLEAN_PATH,
                                                                         "CRANE_FMU_PYTHON": installed_python(python)})
        assert f"using CPython {python.split('-')[-1]}." in log and ", its home /" in log, log
    for i, name in enumerate(COMPONENTS):
        reference = results["3.11"][i]
        assert np.abs(reference[:, 1:]).max() > 0, f"{name}: all outputs zero, nothing compared"
        for python, rows in results.items():
            differ = np.argwhere(rows[i] != reference)
            assert differ.size == 0, f"{name} under CPython {python}: first difference at row, column {differ[0]}"


@pytest.mark.parametrize("version", [2, 3])
def test_the_fmus_python_can_be_a_venv_or_the_builds_own_executable(hosts, fmu_dir, version, tmp_path):
    """CRANE_FMU_PYTHON naming a venv's python: its base installation's standard library is used."""
    venv = tmp_path / "venv"
    subprocess.run([installed_python("3.12"), "-m", "venv", "--without-pip", str(venv)], check=True)
    _, log = _run_alone(hosts[version], _fmu(fmu_dir, "CranePlant", version), tmp_path,
                        {"PATH": CLEAN_PATH, "CRANE_FMU_PYTHON": str(venv / "bin" / "python")})
    assert "using CPython 3.12." in log and ", its home /" in log, log


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("named, reason", [
    ("/nowhere/python3", "(/nowhere/python3 did not run, or named no shared libpython)"),
    ("3.9", "is CPython 3.9"),
    ("/nowhere/libpython3.12.so.1.0", "(/nowhere/libpython3.12.so.1.0: cannot open shared object file"),
])
def test_an_unusable_crane_fmu_python_is_refused_with_the_reason(hosts, fmu_dir, version, named, reason, tmp_path):
    """The FMU never quietly takes another Python than the one its user named."""
    if named == "3.9":
        found = sorted(glob.glob(os.path.expanduser("~/.pyenv/versions/3.9.*/bin/python3.9")))
        if not found:
            pytest.skip("no CPython 3.9 here")
        named = found[-1]
    _, library, token, resources = _unpacked(_fmu(fmu_dir, "CranePlant", version), tmp_path)
    proc = subprocess.run([str(hosts[version]), "run", library, token, resources, "1", "0.01", "0", "0"],
                          capture_output=True, text=True, timeout=120,
                          env={"PATH": CLEAN_PATH, "CRANE_FMU_PYTHON": named}, cwd=tmp_path)
    assert proc.returncode == 5, proc.stdout + proc.stderr
    function = "fmi2Instantiate" if version == 2 else "fmi3InstantiateCoSimulation"
    message = proc.stderr.strip()
    assert message.startswith(f"[3] {function}: the CPython named by CRANE_FMU_PYTHON cannot be used: "
                              f"CRANE_FMU_PYTHON={named} "), message
    assert reason in message and "unset it to let the FMU search" in message and "\n" not in message, message


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("name", ["CranePlant", "LqrController"])
def test_pointers_that_are_not_the_fmus_states_are_refused_not_followed(hosts, fmu_dir, version, name, tmp_path):
    _, library, token, resources = _unpacked(_fmu(fmu_dir, name, version), tmp_path)
    proc = subprocess.run([str(hosts[version]), "abuse", library, token, resources], capture_output=True,
                          text=True, timeout=120, env={"PATH": CLEAN_PATH}, cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stdout + proc.stderr[-3000:]
    refusals = [line for line in proc.stderr.splitlines() if line.startswith("[3] ")]
    assert len(refusals) == 13, proc.stderr  # one log line for each of the 13 refused calls of the host
    assert sum("given an FMU state where the address of one belongs" in r for r in refusals) == 2
    assert sum("not an FMU state of this instance (or one already freed)" in r for r in refusals) == 11


@pytest.mark.quick
def test_the_bundled_core_calls_no_sum():
    """``sum()`` of floats is compensated from CPython 3.12 on: the core adds with ``linalg.total``."""
    import ast
    from pathlib import Path

    import crane_fmu.model

    for module in Path(crane_fmu.model.__file__).parent.glob("*.py"):
        calls = [node.lineno for node in ast.walk(ast.parse(module.read_text()))
                 if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "sum"]
        assert not calls, f"{module.name} calls sum() on lines {calls}"
