/*
 * The cost of the native plant's derivatives for Model Exchange (crane-fmu bench --derivatives): microseconds per
 * evaluation of the derivatives, of one directional derivative, and of the whole Jacobian (one directional
 * derivative per state and input), at Section V's plant swinging, the state moved a little at each call.
 * Usage: derivative_bench N   (prints three numbers, us per evaluation)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "plant_continuous.h"

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
    long n = argc > 1 ? atol(argv[1]) : 1000000;
    ContinuousPlant c = {{3.0, 7.0, 1.0, 0.5, 9.8}, 0.0, 0.0, INFINITY, INFINITY, 0.0, -INFINITY, INFINITY, 0.0,
                         INFINITY, INFINITY};
    double s[N_CONTINUOUS] = {0.0, 0.0, 0.17453292519943295, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0};
    double in[N_PLANT_INPUTS] = {0.5, 0.0, 0.0, 0.0}, f[N_CONTINUOUS], df[N_CONTINUOUS];
    PlantMode free_mode = {0, 0, 0};
    volatile double sink = 0.0;
    double seeds[N_CONTINUOUS + N_PLANT_INPUTS][N_CONTINUOUS + N_PLANT_INPUTS] = {{0}};
    for (int k = 0; k < N_CONTINUOUS + N_PLANT_INPUTS; k++) seeds[k][k] = 1.0;
    double t0 = now();
    for (long i = 0; i < n; i++) {
        s[THETA1] = 0.17453292519943295 + 1e-9 * (double)(i & 1023);
        plant_derivatives(&c, s, in, free_mode, NULL, NULL, f, NULL);
        sink += f[DTHETA1];
    }
    double t1 = now();
    for (long i = 0; i < n; i++) {
        s[THETA1] = 0.17453292519943295 + 1e-9 * (double)(i & 1023);
        plant_derivatives(&c, s, in, free_mode, seeds[THETA1], seeds[THETA1] + N_CONTINUOUS, f, df);
        sink += df[DTHETA1];
    }
    double t2 = now();
    long m = n / (N_CONTINUOUS + N_PLANT_INPUTS) + 1;
    for (long i = 0; i < m; i++) {
        s[THETA1] = 0.17453292519943295 + 1e-9 * (double)(i & 1023);
        for (int k = 0; k < N_CONTINUOUS + N_PLANT_INPUTS; k++) {
            plant_derivatives(&c, s, in, free_mode, seeds[k], seeds[k] + N_CONTINUOUS, f, df);
            sink += df[DTHETA1];
        }
    }
    double t3 = now();
    printf("%.6f %.6f %.6f\n", 1e6 * (t1 - t0) / (double)n, 1e6 * (t2 - t1) / (double)n, 1e6 * (t3 - t2) / (double)m);
    return sink == 12345.0; /* never: keeps the loops */
}
