/*
 * The seeded measurement noise of the sensors: disturbances._mix() and disturbances.noise() in C. A sample is a
 * pure function of (seed, k, channel), so a native sensor gives the Python sensor's noise bit for bit where its
 * log and cos are glibc's.
 */
#ifndef NOISE_H
#define NOISE_H

#include <math.h>
#include <stdint.h>

#include "plant_math.h"

#define NOISE_PI 3.141592653589793 /* math.pi */
#define TWO_53 9007199254740992.0

/* disturbances._mix(): splitmix64 (Python's & 0xFFFFFFFFFFFFFFFF is C's unsigned wrap-around). */
static inline uint64_t mix(uint64_t z) {
    z += 0x9E3779B97F4A7C15u;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
    return z ^ (z >> 31);
}

/* disturbances.noise(): a standard normal sample of (seed, k, channel), Box-Muller on splitmix64. */
static inline double noise(uint64_t seed, uint64_t k, uint64_t channel) {
    uint64_t a = mix((seed << 40) ^ (k << 4) ^ channel), b = mix(a); /* _mix keeps the low 64 bits alike */
    double u1 = ((double)(a >> 11) + 0.5) / TWO_53, u2 = (double)(b >> 11) / TWO_53;
    return sqrt(-2.0 * LOG(u1)) * COS(2.0 * NOISE_PI * u2);
}

/* disturbances.SensorConfig and CraneSensorConfig: the noise's standard deviation on each channel (one a measured
   value, at most the plant state's six), its seed, and the delay in communication steps. */
typedef struct {
    double sigmas[6];
    uint64_t seed;
    int delay;
} SensorConfig;

/* disturbances.measure() and crane_measure(): n true values plus independent normal noise at sample k, on the
   channels first, first + 1, ... (none where a sigma is 0). */
static inline void measure(const SensorConfig *c, uint64_t k, unsigned first, unsigned n, const double true_values[],
                           double out[]) {
    for (unsigned i = 0; i < n; i++)
        out[i] = c->sigmas[i] != 0 ? true_values[i] + c->sigmas[i] * noise(c->seed, k, first + i) : true_values[i];
}

#endif
