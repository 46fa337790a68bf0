/*
 * The cost of the native plant's derivatives through its FMI 2.0 Model Exchange interface (crane-fmu bench
 * --derivatives), beside derivative_bench.c's cost of the model's C functions: microseconds per
 * fmi2SetContinuousStates with fmi2GetDerivatives, with one fmi2GetDirectionalDerivative (every derivative and
 * output along one state), and with the whole Jacobian (one call per state and input), at Section V's plant
 * swinging, the state moved a little at each call.
 * Usage: fmi_derivative_bench LIB N NX NU NY KNOWN... UNKNOWN...   (NX states then NU inputs; NX derivatives
 *        then NY outputs, by value reference; the first input is the trolley's demand u) prints three numbers
 */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi2Functions.h"

enum { MOST = 64 };

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define SYMBOL(name) name##TYPE *name = (name##TYPE *)dlsym(lib, #name)

int main(int argc, char **argv) {
    if (argc < 6) return fprintf(stderr, "usage: fmi_derivative_bench LIB N NX NU NY KNOWN... UNKNOWN...\n"), 2;
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) return fprintf(stderr, "cannot load %s\n", argv[1]), 3;
    long n = atol(argv[2]);
    int nx = atoi(argv[3]), nu = atoi(argv[4]), ny = atoi(argv[5]), nk = nx + nu, nz = nx + ny;
    if (nx < 3 || nk > MOST || nz > MOST || argc != 6 + nk + nz) return fprintf(stderr, "bad arguments\n"), 2;
    fmi2ValueReference known[MOST], unknown[MOST];
    for (int i = 0; i < nk; i++) known[i] = (fmi2ValueReference)atol(argv[6 + i]);
    for (int i = 0; i < nz; i++) unknown[i] = (fmi2ValueReference)atol(argv[6 + nk + i]);
    SYMBOL(fmi2Instantiate);
    SYMBOL(fmi2SetupExperiment);
    SYMBOL(fmi2EnterInitializationMode);
    SYMBOL(fmi2ExitInitializationMode);
    SYMBOL(fmi2NewDiscreteStates);
    SYMBOL(fmi2EnterContinuousTimeMode);
    SYMBOL(fmi2SetReal);
    SYMBOL(fmi2GetContinuousStates);
    SYMBOL(fmi2SetContinuousStates);
    SYMBOL(fmi2GetDerivatives);
    SYMBOL(fmi2GetDirectionalDerivative);
    SYMBOL(fmi2FreeInstance);
    fmi2CallbackFunctions callbacks = {NULL, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("plant", fmi2ModelExchange, NULL, NULL, &callbacks, fmi2False, fmi2False);
    fmi2EventInfo info;
    double u = 0.5, x[MOST], dx[MOST], dz[MOST], one = 1.0;
    if (!c || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) || fmi2EnterInitializationMode(c) ||
        fmi2ExitInitializationMode(c) || fmi2NewDiscreteStates(c, &info) || fmi2EnterContinuousTimeMode(c) ||
        fmi2SetReal(c, &known[nx], 1, &u) || fmi2GetContinuousStates(c, x, (size_t)nx))
        return fprintf(stderr, "the FMU did not start\n"), 3;
    double theta1 = x[2], sink = 0.0;
    int failed = 0;
    double t0 = now();
    for (long i = 0; i < n; i++) {
        x[2] = theta1 + 1e-9 * (double)(i & 1023);
        failed |= fmi2SetContinuousStates(c, x, (size_t)nx) | fmi2GetDerivatives(c, dx, (size_t)nx);
        sink += dx[3];
    }
    double t1 = now();
    for (long i = 0; i < n; i++) {
        x[2] = theta1 + 1e-9 * (double)(i & 1023);
        failed |= fmi2SetContinuousStates(c, x, (size_t)nx) |
                  fmi2GetDirectionalDerivative(c, unknown, (size_t)nz, &known[2], 1, &one, dz);
        sink += dz[3];
    }
    double t2 = now();
    long m = n / nk + 1;
    for (long i = 0; i < m; i++) {
        x[2] = theta1 + 1e-9 * (double)(i & 1023);
        failed |= fmi2SetContinuousStates(c, x, (size_t)nx);
        for (int k = 0; k < nk; k++) {
            failed |= fmi2GetDirectionalDerivative(c, unknown, (size_t)nz, &known[k], 1, &one, dz);
            sink += dz[3];
        }
    }
    double t3 = now();
    fmi2FreeInstance(c);
    if (failed) return fprintf(stderr, "an FMI call failed\n"), 3;
    printf("%.6f %.6f %.6f\n", 1e6 * (t1 - t0) / (double)n, 1e6 * (t2 - t1) / (double)n, 1e6 * (t3 - t2) / (double)m);
    return sink == 12345.0; /* never: keeps the loops */
}
