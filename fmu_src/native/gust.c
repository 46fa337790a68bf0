/*
 * The Gust component in C: the native twin of Gust in crane_fmu/model/disturbances.py (its variables,
 * _gust_configure() rules and messages, gust()) behind the model interface of model.h. Its variables
 * come from Gust_variables.h, generated from disturbances.GUST. Its state is the time of its outputs:
 * 0 at first, then the end of the last step (time + step, the component's update()).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "Gust_variables.h"
#include "model.h"
#include "plant_math.h"
#include "py_repr.h"
#include "model_values.h"

#define PI 3.141592653589793 /* math.pi */

/* disturbances.GustConfig */
typedef struct {
    double F1, F2, start, duration;
} Config;

struct Model {
    double values[N_VARIABLES]; /* parameters by value reference */
    int initialised;
    Config config; /* set when initialisation ends */
    double time;   /* the state: the time the outputs are for */
};

MODEL_EXPORTS(0)
MODEL_WITHOUT_STRINGS

#define V(name) (values[VR_##name])

void model_defaults(Model *m) {
    memset(m, 0, sizeof *m);
    for (unsigned i = 0; i < N_VARIABLES; i++) m->values[i] = VARIABLE_TABLE[i].start;
}

/* The rules of _gust_configure() in its order and words. */
static ModelStatus setup(const double values[], Config *c, const Reporter *r) {
    static const unsigned finite[] = {VR_F1_peak, VR_F2_peak, VR_start};
    for (unsigned i = 0; i < 3; i++)
        if (!isfinite(values[finite[i]])) return rule(r, VARIABLE_TABLE[finite[i]].name, "finite", values[finite[i]]);
    if (!(V(duration) > 0 && isfinite(V(duration)))) return rule(r, "duration", "> 0 and finite", V(duration));
    *c = (Config){V(F1_peak), V(F2_peak), V(start), V(duration)};
    return MODEL_OK;
}

/* disturbances.gust(): (F1, F2) at time t, a half-sine pulse while it lasts. */
static void gust(const Config *c, double t, double out[N_OUTPUTS]) {
    if (!(c->start <= t && t <= c->start + c->duration)) {
        out[0] = out[1] = 0.0;
        return;
    }
    double shape = SIN(PI * (t - c->start) / c->duration);
    out[0] = c->F1 * shape, out[1] = c->F2 * shape;
}

ModelStatus model_initialize(Model *m, const Reporter *r) {
    ModelStatus status = setup(m->values, &m->config, r);
    if (status != MODEL_OK) return status;
    m->time = 0.0; /* initial_state() */
    m->initialised = 1;
    return MODEL_OK;
}

ModelStatus model_get_reals(Model *m, const unsigned vr[], size_t n, double values[], const Reporter *r) {
    double out[N_OUTPUTS];
    int have_outputs = 0;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VARIABLES) return no_variable(r, vr[i]);
        if (VARIABLE_TABLE[vr[i]].causality != OUTPUT) {
            values[i] = m->values[vr[i]];
            continue;
        }
        if (!have_outputs && m->initialised) {
            gust(&m->config, m->time, out);
        } else if (!have_outputs) { /* before initialisation ends the outputs follow the parameters, at time 0 */
            Config c;
            if (setup(m->values, &c, r) != MODEL_OK) return MODEL_ERROR;
            gust(&c, 0.0, out);
        }
        have_outputs = 1;
        values[i] = out[vr[i] - FIRST_OUTPUT];
    }
    return MODEL_OK;
}

ModelStatus model_do_step(Model *m, double time, double step, const Reporter *r) {
    m->time = time + step; /* update(): the outputs are for the end of the step */
    return MODEL_OK;
}
