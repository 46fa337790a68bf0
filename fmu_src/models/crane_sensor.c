/*
 * The CraneSensor component in C: the native twin of CraneSensor in crane_fmu/model/disturbances.py (its
 * variables, _crane_sensor_configure(), crane_measure() with noise.h's noise() on channels 8-10, and the delay of
 * whole steps), registered as a component (component.h). Its variables and parameter rules come from
 * CraneSensor_variables.h, generated from disturbances.CRANE_SENSOR. Its state is (k, history): the sample count
 * and the last `delay` samples, oldest first, none at first.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "CraneSensor_variables.h"
#include "noise.h"
#include "py_repr.h"
#include "rules.h"

enum { MAX_DELAY = 100 }; /* the rule on delay */

typedef SensorConfig Config; /* disturbances.CraneSensorConfig */

typedef struct {
    uint64_t k;                               /* samples taken, */
    int held;                                 /* how many of the last ones are kept (at most delay), */
    double history[MAX_DELAY][N_OUTPUTS];     /* and they, oldest first */
} State;

#define V(name) (values[VR_##name])

/* _crane_sensor_configure(), after its rules (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    c->sigmas[0] = V(sigma_x), c->sigmas[1] = V(sigma_theta1), c->sigmas[2] = V(sigma_theta2);
    c->seed = (uint64_t)V(seed), c->delay = (int)V(delay);
    return MODEL_OK;
}

/* disturbances.crane_measure(): (x, theta1, theta2) plus noise on channels 8-10 at sample k. */
static void crane_measure(const Config *c, uint64_t k, const double true_values[N_OUTPUTS], double out[N_OUTPUTS]) {
    measure(c, k, 8, N_OUTPUTS, true_values, out);
}

static void initial_state(const double values[], const Config *c, State *s) { s->k = 0, s->held = 0; } /* (0, []) */

/* _crane_sensor_output(): the sample delay steps ago (the oldest kept until there is one that old); without a
   delay, and at first, a sample of the inputs now. */
static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    if (c->delay == 0 || s->held == 0) crane_measure(c, s->k, &values[VR_x], out);
    else memcpy(out, s->history[0], sizeof s->history[0]);
    return MODEL_OK;
}

/* _crane_sensor_update(): (k + 1, (history + [crane_measure(k)])[-delay:]) */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    if (c->delay > 0) {
        if (s->held == c->delay) memmove(s->history[0], s->history[1], (size_t)--s->held * sizeof s->history[0]);
        crane_measure(c, s->k, &values[VR_x], s->history[s->held++]);
    }
    s->k++;
    return MODEL_OK;
}

STATEFUL_COMPONENT;
