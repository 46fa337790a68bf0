/*
 * The Wind component in C: the native twin of crane_fmu/model/wind.py (its variables, _configure(),
 * turbulence_step(), drag() and _output()), registered as a component (component.h). Its variables and parameter
 * rules come from Wind_variables.h, generated from wind.COMPONENT. Its state is (k, w): the sample count and the
 * Dryden turbulence at sample k, drawn at first from the stationary distribution; the noise is noise.h's, the
 * Python wind's sequence for the same seed.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "Wind_variables.h"
#include "noise.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

#define CHANNEL 16 /* wind.CHANNEL */

/* wind.WindConfig */
typedef struct {
    double mean, sigma, time_constant, drag1, drag2, l1, l2;
    uint64_t seed;
} Config;

typedef struct {
    uint64_t k; /* the sample count, */
    double w;   /* and the turbulence at sample k */
} State;

#define V(name) (values[VR_##name])

/* wind._configure(), after its RULES (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double half = 0.5 * V(rho) * V(Cd);
    *c = (Config){V(U_mean), V(sigma), V(U_mean) != 0 ? V(L) / fabs(V(U_mean)) : INFINITY, half * V(A1),
                  half * V(A2), V(l1), V(l2), (uint64_t)V(seed)};
    return MODEL_OK;
}

/* wind.drag(): the drag force on a body moving at `velocity` in `wind` (both along x). */
static double drag(double half_rho_cd_area, double wind, double velocity) {
    double relative = wind - velocity;
    return half_rho_cd_area * relative * fabs(relative);
}

/* wind._initial_state(): (0, sigma n_0), stationary from the first sample. */
static void initial_state(const double values[], const Config *c, State *s) {
    s->k = 0, s->w = c->sigma * noise(c->seed, 0, CHANNEL);
}

/* wind._output(): the drag on hook and payload at their velocities (eqs (4)-(5) differentiated), and the wind. */
static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    double speed = c->mean + s->w;
    double v1 = V(dx) + c->l1 * COS(V(theta1)) * V(dtheta1);
    double v2 = v1 + c->l2 * COS(V(theta2)) * V(dtheta2);
    out[0] = drag(c->drag1, speed, v1), out[1] = drag(c->drag2, speed, v2), out[2] = speed;
    return MODEL_OK;
}

/* wind.turbulence_step(): the exact AR(1) of the Dryden shaping filter over the step, w_(k+1) from w_k. */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    double a = EXP(-step / c->time_constant);
    s->w = a * s->w + c->sigma * sqrt(1.0 - a * a) * noise(c->seed, s->k + 1, CHANNEL);
    s->k++;
    return MODEL_OK;
}

STATEFUL_COMPONENT;
