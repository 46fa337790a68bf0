/*
 * The Gust component in C: the native twin of Gust in crane_fmu/model/disturbances.py (its variables,
 * _gust_configure(), gust()), registered as a component (component.h). Its variables and parameter rules come from
 * Gust_variables.h, generated from disturbances.GUST. Its state is the time of its outputs: 0 at first, then the
 * end of the last step (time + step, the component's update()).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "Gust_variables.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

#define PI 3.141592653589793 /* math.pi */

/* disturbances.GustConfig */
typedef struct {
    double F1, F2, start, duration;
} Config;

STATE_IS_TIME

#define V(name) (values[VR_##name])

/* _gust_configure(), after its rules (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
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

static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    gust(c, s->time, out);
    return MODEL_OK;
}

STATEFUL_COMPONENT;
