"""Random FMI call sequences from a C host, FMI 2.0 and 3.0: no crash, and no error without its message.

The driver picks each call with a seeded xorshift generator: any function in any state, with
bad values (NaN, infinities, zero and negative steps, garbage serialised states), and frees
and instantiates again now and then. It exits non-zero if an FMU crashes it, returns a status
outside 0-4, or returns an error status without logging an error message first.
"""

import subprocess

import pytest
from test_c_host import compile_hosts, unpack_fmu

from crane_fmu.build_scripts.build_fmus import fmi3_dir

DRIVER = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
static uint64_t rng;
static unsigned next(unsigned n) { rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17; return (unsigned)(rng % n); }
static long errors_logged, statuses[5];
static const double values[] = {0.0, -0.0, 1e-3, 0.01, 0.5, -1.0, 3.0, 1e308, -1e308, 5e-324, NAN, INFINITY, -INFINITY};
#define VALUE() values[next(sizeof values / sizeof *values)]
#define SYM(name) ((name##TYPE *)dlsym(so, #name))
#if FMI == 2
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String f, ...) {
    if (s >= fmi2Error) errors_logged++;
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
#define NEW() SYM(fmi2Instantiate)("fuzz", fmi2CoSimulation, token, resources, &cb, fmi2False, next(2))
#define FREE(c) SYM(fmi2FreeInstance)(c)
#else
#include "fmi3Functions.h"
static void logger(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    if (s >= fmi3Error) errors_logged++;
}
#define NEW() SYM(fmi3InstantiateCoSimulation)("fuzz", token, resources, fmi3False, next(2), fmi3False, \
    fmi3False, NULL, 0, NULL, logger, NULL)
#define FREE(c) SYM(fmi3FreeInstance)(c)
#endif

int main(int argc, char **argv) {
    /* library token resources seed calls vr... */
    void *so = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!so) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 3; }
    const char *token = argv[2], *resources = argv[3];
    rng = strtoull(argv[4], NULL, 10) | 1;
    long calls = atol(argv[5]);
    int nvr = argc - 6;
    unsigned vr[64];
    for (int i = 0; i < nvr && i < 64; i++) vr[i] = (unsigned)atoi(argv[6 + i]);
    void *c = NEW();
    if (!c) { fprintf(stderr, "instantiation failed\n"); return 4; }
    void *state = NULL;
    char garbage[64];
    for (long k = 0; k < calls; k++) {
        unsigned op = next(16), v = vr[next(nvr)];
        double x = VALUE(), out[4];
        long before = errors_logged;
        int status = 0;
#if FMI == 2
        switch (op) {
        case 0: status = SYM(fmi2SetupExperiment)(c, next(2), x, 0.0, next(2), VALUE()); break;
        case 1: status = SYM(fmi2EnterInitializationMode)(c); break;
        case 2: status = SYM(fmi2ExitInitializationMode)(c); break;
        case 3: case 4: status = SYM(fmi2SetReal)(c, &v, 1, &x); break;
        case 5: case 6: status = SYM(fmi2GetReal)(c, &v, 1, out); break;
        case 7: case 8: status = SYM(fmi2DoStep)(c, VALUE(), x, next(2)); break;
        case 9: status = SYM(fmi2Terminate)(c); break;
        case 10: status = SYM(fmi2Reset)(c); break;
        case 11: status = SYM(fmi2GetFMUstate)(c, &state); break;
        case 12: status = state ? SYM(fmi2SetFMUstate)(c, state) : 0; break;
        case 13: { size_t n = 0; status = state ? SYM(fmi2SerializedFMUstateSize)(c, state, &n) : 0; break; }
        case 14: for (int i = 0; i < 64; i++) garbage[i] = (char)next(256);
                 status = SYM(fmi2DeSerializeFMUstate)(c, garbage, next(64), &state); break;
        default: { fmi2Real t; status = SYM(fmi2GetRealStatus)(c, next(4), &t); break; }
        }
#else
        fmi3Boolean flags[3];
        switch (op) {
        case 0: case 1: status = SYM(fmi3EnterInitializationMode)(c, next(2), x, 0.0, next(2), VALUE()); break;
        case 2: status = SYM(fmi3ExitInitializationMode)(c); break;
        case 3: case 4: status = SYM(fmi3SetFloat64)(c, &v, 1, &x, 1); break;
        case 5: case 6: status = SYM(fmi3GetFloat64)(c, &v, 1, out, 1); break;
        case 7: case 8: status = SYM(fmi3DoStep)(c, VALUE(), x, next(2), flags, flags + 1, flags + 2, out); break;
        case 9: status = SYM(fmi3Terminate)(c); break;
        case 10: status = SYM(fmi3Reset)(c); break;
        case 11: status = SYM(fmi3GetFMUState)(c, &state); break;
        case 12: status = state ? SYM(fmi3SetFMUState)(c, state) : 0; break;
        case 13: { size_t n = 0; status = state ? SYM(fmi3SerializedFMUStateSize)(c, state, &n) : 0; break; }
        case 14: for (int i = 0; i < 64; i++) garbage[i] = (char)next(256);
                 status = SYM(fmi3DeserializeFMUState)(c, (fmi3Byte *)garbage, next(64), &state); break;
        default: status = SYM(fmi3EnterEventMode)(c); break;
        }
#endif
        if (status < 0 || status > 4) { printf("status %d from call %u\n", status, op); return 5; }
        statuses[status]++;
        if (status >= 3 && errors_logged == before) { printf("silent error from call %u\n", op); return 6; }
        if (next(200) == 0) {  /* free everything and start again */
#if FMI == 2
            if (state) SYM(fmi2FreeFMUstate)(c, &state);
#else
            if (state) SYM(fmi3FreeFMUState)(c, &state);
#endif
            state = NULL;
            FREE(c);
            c = NEW();
            if (!c) { printf("instantiation failed again\n"); return 4; }
        }
    }
    FREE(c);
    printf("ok %ld warning %ld discard %ld error %ld fatal %ld\n", statuses[0], statuses[1], statuses[2], statuses[3],
           statuses[4]);
    return 0;
}
"""


@pytest.fixture(scope="module")
def drivers(tmp_path_factory):
    return compile_hosts(DRIVER, tmp_path_factory.mktemp("fuzz"))


@pytest.mark.parametrize("name", ["CranePlant", "LqrController"])
@pytest.mark.parametrize("version", [2, 3])
def test_random_calls_from_a_c_host_never_crash_and_every_error_says_why(drivers, fmu_dir, name, version, tmp_path):
    fmu = (fmu_dir if version == 2 else fmi3_dir(fmu_dir)) / f"{name}.fmu"
    md, library, token, resources = unpack_fmu(fmu, tmp_path)
    refs = [str(v.valueReference) for v in md.modelVariables if v.type in ("Real", "Float64")]
    proc = subprocess.run([str(drivers[version]), library, token, resources, "12345", "6000", *refs],
                          capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert proc.returncode == 0, f"status {proc.returncode}: {proc.stdout[-2000:]} {proc.stderr[-2000:]}"
    counts = dict(zip(proc.stdout.split()[::2], map(int, proc.stdout.split()[1::2])))
    assert counts["ok"] > 500 and counts["error"] > 500, counts  # both kinds of path were taken
