/*
 * The Sensor component in C: the native twin of Sensor in crane_fmu/model/disturbances.py (its variables,
 * _sensor_configure(), noise.h's measure() and the one-step delay), registered as a component (component.h). Its
 * variables and parameter rules come from Sensor_variables.h, generated from disturbances.SENSOR. Its state is (k,
 * held): the sample count and the last sample, none at first.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "Sensor_variables.h"
#include "noise.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

typedef SensorConfig Config; /* disturbances.SensorConfig */

typedef struct {
    uint64_t k;             /* samples taken, */
    int have_held;          /* whether there is one, */
    double held[N_OUTPUTS]; /* and the last */
} State;

#define V(name) (values[VR_##name])

/* _sensor_configure(), after its rules (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double s[6] = {V(sigma_x), V(sigma_dx), V(sigma_theta), V(sigma_dtheta), V(sigma_theta), V(sigma_dtheta)};
    memcpy(c->sigmas, s, sizeof s);
    c->seed = (uint64_t)V(seed), c->delay = V(delay) == 1.0;
    return MODEL_OK;
}

static void initial_state(const double values[], const Config *c, State *s) { s->k = 0, s->have_held = 0; } /* (0, None) */

/* _sensor_output(): the held sample when delayed, else (and at first) a sample of the inputs now. */
static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    if (!c->delay || !s->have_held) measure(c, s->k, 0, N_OUTPUTS, &values[VR_x], out);
    else memcpy(out, s->held, sizeof s->held);
    return MODEL_OK;
}

/* _sensor_update(): (k + 1, measure(k)) */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    measure(c, s->k, 0, N_OUTPUTS, &values[VR_x], s->held);
    s->k++, s->have_held = 1;
    return MODEL_OK;
}

STATEFUL_COMPONENT;
