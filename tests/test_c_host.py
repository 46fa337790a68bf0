"""The FMUs in a plain C program: dlopen, no LD_PRELOAD, no environment variables."""

import os
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description

from crane_fmu.cosim import simulate
from crane_fmu.model.tables import STATE

# What both C hosts share: the FMI 2.0 callbacks and a logger printing "[status] message" to stdout.
PRELUDE = r"""
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
typedef struct {
    void (*logger)(void *, const char *, int, const char *, const char *, ...);
    void *(*alloc)(size_t, size_t); void (*release)(void *); void *step_finished; void *env;
} Callbacks;
static void logger(void *env, const char *name, int status, const char *category, const char *format, ...) {
    va_list args; va_start(args, format);
    fprintf(stderr, "[%d] ", status); vfprintf(stderr, format, args); fputc('\n', stderr);
    va_end(args);
}
typedef void *(*Instantiate)(const char *, int, const char *, const char *, const Callbacks *, int, int);
"""

# Gauss-Seidel closed loop: read plant states, set controller inputs, read u, set plant u, step both.
HOST = PRELUDE + r"""
typedef int (*Call)(void *);
typedef int (*Setup)(void *, int, double, double, int, double);
typedef int (*Reals)(void *, const unsigned *, size_t, double *);
typedef int (*DoStep)(void *, double, double, int);
typedef struct { void *c; Reals get, set; DoStep step; } Fmu;
static Fmu load(const char *library, const char *name, const char *guid, const char *resources, Callbacks *cb) {
    void *so = dlopen(library, RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); exit(3); }
    Fmu f = {((Instantiate)dlsym(so, "fmi2Instantiate"))(name, 1, guid, resources, cb, 0, 0),
             (Reals)dlsym(so, "fmi2GetReal"), (Reals)dlsym(so, "fmi2SetReal"), (DoStep)dlsym(so, "fmi2DoStep")};
    if (!f.c) { fprintf(stderr, "fmi2Instantiate failed for %s\n", name); exit(4); }
    if (((Setup)dlsym(so, "fmi2SetupExperiment"))(f.c, 0, 0.0, 0.0, 0, 0.0) ||
        ((Call)dlsym(so, "fmi2EnterInitializationMode"))(f.c) ||
        ((Call)dlsym(so, "fmi2ExitInitializationMode"))(f.c)) exit(5);
    return f;
}
#define CHECK(x) if ((x) > 1) { fprintf(stderr, "call failed at step %d\n", k); return 6; }
int main(int argc, char **argv) {
    /* plant.so plant-guid plant-resources ctrl.so ctrl-guid ctrl-resources steps h then value references:
       6 plant states, 6 controller inputs, controller u, plant u */
    if (argc != 9 + 14) return 2;
    Callbacks cb = {logger, calloc, free, NULL, NULL};
    Fmu plant = load(argv[1], "plant", argv[2], argv[3], &cb);
    Fmu ctrl = load(argv[4], "controller", argv[5], argv[6], &cb);
    int steps = atoi(argv[7]);
    double h = atof(argv[8]), states[6], u[1];
    unsigned state_vr[6], input_vr[6], u_out[1], u_in[1];
    for (int i = 0; i < 6; i++) { state_vr[i] = atoi(argv[9 + i]); input_vr[i] = atoi(argv[15 + i]); }
    u_out[0] = atoi(argv[21]); u_in[0] = atoi(argv[22]);
    for (int k = 0; k <= steps; k++) {
        double t = k * h;
        CHECK(plant.get(plant.c, state_vr, 6, states));
        CHECK(ctrl.set(ctrl.c, input_vr, 6, states));
        CHECK(ctrl.get(ctrl.c, u_out, 1, u));
        CHECK(plant.set(plant.c, u_in, 1, u));
        printf("%.17g", t);
        for (int i = 0; i < 6; i++) printf(",%.17g", states[i]);
        printf(",%.17g\n", u[0]);
        if (k < steps) { CHECK(plant.step(plant.c, t, h, 1)); CHECK(ctrl.step(ctrl.c, t, h, 1)); }
    }
    return 0;
}
"""


def _unpack(fmu, folder):
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    library = folder / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    return md, library, (folder / "resources").as_uri()


def test_c_host_runs_the_closed_loop_like_our_master(crane_fmus, connections, tmp_path):
    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler")
    (tmp_path / "host.c").write_text(HOST)
    subprocess.run([compiler, str(tmp_path / "host.c"), "-o", str(tmp_path / "host"), "-ldl"], check=True)
    plant_md, plant_so, plant_res = _unpack(crane_fmus["plant"], tmp_path / "plant")
    ctrl_md, ctrl_so, ctrl_res = _unpack(crane_fmus["controller"], tmp_path / "controller")
    vr = {("plant", v.name): v.valueReference for v in plant_md.modelVariables}
    vr.update({("controller", v.name): v.valueReference for v in ctrl_md.modelVariables})
    refs = ([vr["plant", s] for s in STATE] + [vr["controller", s] for s in STATE]
            + [vr["controller", "u"], vr["plant", "u"]])
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "LD_LIBRARY_PATH", "PYTHONPATH",
                                                            "PYTHONHOME")}
    proc = subprocess.run([str(tmp_path / "host"), str(plant_so), plant_md.guid, plant_res, str(ctrl_so),
                           ctrl_md.guid, ctrl_res, "500", "0.002", *map(str, refs)],
                          capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    c_rows = np.array([[float(x) for x in line.split(",")] for line in proc.stdout.splitlines()])
    ours = simulate(crane_fmus, connections, 1.0, 0.002).columns()
    expected = np.column_stack([ours["time"]] + [ours["plant." + s] for s in STATE] + [ours["controller.u"]])
    assert c_rows.shape == expected.shape == (501, 8)
    assert np.array_equal(c_rows, expected)  # same Python code, same inputs: bit for bit


MISSING = PRELUDE + r"""
int main(int argc, char **argv) {
    void *so = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!so) { printf("dlopen failed: %s\n", dlerror()); return 3; }
    Callbacks cb = {logger, calloc, free, NULL, NULL};
    void *c = ((Instantiate)dlsym(so, "fmi2Instantiate"))("plant", 1, "", argv[2], &cb, 0, 0);
    printf("instance %s\n", c ? "created" : "NULL");
    return 0;
}
"""


def test_missing_python_is_a_message_from_fmi2instantiate(tmp_path):
    """An FMU whose Python is absent still loads; fmi2Instantiate says what is missing and returns NULL."""
    from crane_fmu.build_scripts.build_fmus import build_fmu
    from crane_fmu.build_scripts.wrapper import compile_binaries
    from crane_fmu.model import plant

    compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if compiler is None:
        pytest.skip("no C compiler")
    binaries = compile_binaries(tmp_path, libpython="/nonexistent/libpython9.9.so.1.0")
    fmu = build_fmu(plant.COMPONENT, tmp_path / "fmus", binaries)
    md, library, resources = _unpack(fmu, tmp_path / "plant")
    (tmp_path / "missing.c").write_text(MISSING)
    subprocess.run([compiler, str(tmp_path / "missing.c"), "-o", str(tmp_path / "missing"), "-ldl"], check=True)
    proc = subprocess.run([str(tmp_path / "missing"), str(library), resources], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "instance NULL" in proc.stdout
    assert ("[3] fmi2Instantiate: this FMU runs Python models and needs the CPython it was built with "
            "(libpython9.9.so.1.0, at /nonexistent/libpython9.9.so.1.0)") in proc.stderr
