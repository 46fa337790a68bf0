/*
 * The BacksteppingController component in C: the native twin of crane_fmu/model/backstepping.py (its configure(),
 * law() and the output limiting of limits.limited()), registered as a component (component.h). Its variables,
 * value references, start values and parameter rules come from BacksteppingController_variables.h, generated from
 * backstepping.VARIABLES. No state: the output u follows the inputs of the same instant (direct feedthrough).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "BacksteppingController_variables.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

/* What law() computes once from the parameters, named as there. */
typedef struct {
    double a, m2, l1, l2, ga, gm2, two_m2, m12, l2m2, m12g, two_m12;
    int derived;
    double k1x, k2x, k11, k21, k12, k22, nk1x, nk11, nk12, x_d, theta1_d, theta2_d, w_x, w_1, w_2;
    double u_max, v_max, h;
} Config;

#define V(name) (values[VR_##name])

/* backstepping.configure(), after its RULES (the generated parameter_rules()): law()'s constants. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    int derived = strcmp(strings[STRING_b3_form], "derived") == 0;
    double m1 = V(m1), m2 = V(m2), l2 = V(l2), g = V(g);
    c->a = 2.0 * m1 + m2;
    c->m2 = m2, c->l1 = V(l1), c->l2 = l2;
    c->ga = -g * c->a, c->gm2 = g * m2, c->two_m2 = 2.0 * m2;
    c->m12 = m1 + m2;
    c->l2m2 = l2 * m2, c->m12g = c->m12 * g, c->two_m12 = 2.0 * c->m12;
    c->derived = derived;
    c->k1x = V(K1_x), c->k2x = V(K2_x), c->k11 = V(K1_theta1), c->k21 = V(K2_theta1), c->k12 = V(K1_theta2);
    c->k22 = V(K2_theta2);
    c->nk1x = -c->k1x, c->nk11 = -c->k11, c->nk12 = -c->k12;
    c->x_d = V(x_d), c->theta1_d = V(theta1_d), c->theta2_d = V(theta2_d);
    c->w_x = V(w_x), c->w_1 = V(w_theta1), c->w_2 = V(w_theta2);
    c->u_max = unlimited(V(u_max)), c->v_max = unlimited(V(v_max)), c->h = V(h);
    return MODEL_OK;
}

/* backstepping.law(): the same arithmetic in the same order. */
static double law(const Config *c, const double s[6]) {
    double x = s[0], dx = s[1], theta1 = s[2], dtheta1 = s[3], theta2 = s[4], dtheta2 = s[5];
    double d = theta1 - theta2;
    double sd = SIN(d), cd = COS(d);
    double den = c->a - c->m2 * COS(2.0 * d);
    double w1s = dtheta1 * dtheta1, w2s = dtheta2 * dtheta2;
    double f2 = (c->ga * SIN(theta1) - c->gm2 * SIN(theta1 - 2.0 * theta2) -
                 c->two_m2 * (c->l1 * w1s * cd + c->l2 * w2s) * sd) / (c->l1 * den);
    double b2 = (-c->a * COS(theta1) + c->m2 * COS(theta1 - 2.0 * theta2)) / (c->l1 * den);
    double f3 = 2.0 * (c->l1 * w1s * c->m12 + c->l2m2 * w2s * cd + c->m12g * COS(theta1)) * sd / (c->l2 * den);
    double b3 = c->two_m12 * sd * SIN(theta1) / (c->l2 * den);
    if (c->derived) b3 = -b3;
    double e3x = c->nk1x * dx - c->k2x * (dx + c->k1x * (x - c->x_d));
    double e31 = c->nk11 * dtheta1 - c->k21 * (dtheta1 + c->k11 * (theta1 - c->theta1_d));
    double e32 = c->nk12 * dtheta2 - c->k22 * (dtheta2 + c->k12 * (theta2 - c->theta2_d));
    double num = c->w_x * e3x + c->w_1 * b2 * (e31 - f2) + c->w_2 * b3 * (e32 - f3);
    return num / (c->w_x + c->w_1 * b2 * b2 + c->w_2 * b3 * b3);
}

static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    const double *in = &values[VR_x];
    double u = law(c, in);
    out[0] = c->u_max == INFINITY && c->v_max == INFINITY ? u : limited(u, in[1], c->u_max, c->v_max, c->h);
    return MODEL_OK;
}

STATELESS_COMPONENT;
