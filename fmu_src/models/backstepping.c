/*
 * The BacksteppingController component in C: the native twin of crane_fmu/model/backstepping.py (its
 * configure() rules and messages, law() and the output limiting of limits.limited()), registered as a
 * component (component.h). Its variables, value references and start values come from
 * BacksteppingController_variables.h, generated from backstepping.VARIABLES. No state: the output u
 * follows the inputs of the same instant (direct feedthrough).
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
#define R(value) py_repr(value, (char[REPR_SIZE]){0})

/* The rules of backstepping.configure() in its order and words: h, the limits, the plant model, the gains. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    const char *b3_form = strings[STRING_b3_form];
    if (!(isfinite(V(h)) && V(h) > 0)) return rule(r, "h", "> 0 and finite", V(h));
    if (!(V(u_max) > 0)) return rule(r, "u_max", "> 0 (inf: no limit)", V(u_max));
    if (!(V(v_max) > 0)) return rule(r, "v_max", "> 0 (inf: no limit)", V(v_max));
    ModelStatus plant = plant_rules(V(m1), V(m2), V(l1), V(l2), V(g), r);
    if (plant != MODEL_OK) return plant;
    static const unsigned finite[] = {VR_K1_x, VR_K1_theta1, VR_K1_theta2, VR_K2_x, VR_K2_theta1, VR_K2_theta2,
                                      VR_x_d, VR_theta1_d, VR_theta2_d};
    for (unsigned i = 0; i < 9; i++)
        if (!isfinite(values[finite[i]])) return rule(r, VARIABLE_TABLE[finite[i]].name, "finite", values[finite[i]]);
    static const unsigned weights[] = {VR_w_x, VR_w_theta1, VR_w_theta2};
    for (unsigned i = 0; i < 3; i++) {
        double value = values[weights[i]];
        if (!(isfinite(value) && value >= 0)) return rule(r, VARIABLE_TABLE[weights[i]].name, ">= 0 and finite", value);
    }
    if (V(w_x) == 0) return report(r, MODEL_ERROR, "w_x must be > 0 (b'Wb must not vanish), got %s", R(V(w_x)));
    int derived = strcmp(b3_form, "derived") == 0;
    if (!derived && strcmp(b3_form, "printed") != 0)
        return report(r, MODEL_ERROR, "b3_form must be one of derived, printed, got %s",
                      str_repr(b3_form, (char[STR_REPR_SIZE]){0}));
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
