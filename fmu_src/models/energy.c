/*
 * The EnergyController component in C: the native twin of crane_fmu/model/energy.py (its variables, configure(),
 * control(): eqs (E2)-(E4) with limits.limited()), registered as a component (component.h). Its variables and
 * parameter rules come from EnergyController_variables.h, generated from energy.VARIABLES. No state: the output u
 * follows the inputs of the same instant (direct feedthrough).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "EnergyController_variables.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

/* energy.Config */
typedef struct {
    double mu, m2, l1, l2, k_c, k_p, k_d, x_d, u_max, v_max, h;
} Config;

#define V(name) (values[VR_##name])

/* energy.configure(), after its RULES (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double u_max = unlimited(V(u_max)), v_max = unlimited(V(v_max));
    *c = (Config){V(m1) + V(m2), V(m2), V(l1), V(l2), V(k_c), V(k_p), V(k_d), V(x_d), u_max, v_max, V(h)};
    return MODEL_OK;
}

/* energy.control(): eq (E4) with the speed guard, the same arithmetic in the same order. */
static double control(const Config *c, const double s[6]) {
    double x = s[0], v = s[1], theta1 = s[2], dtheta1 = s[3], theta2 = s[4], dtheta2 = s[5];
    double xi = (c->mu * c->l1 * SIN(theta1) + c->m2 * c->l2 * SIN(theta2)) / c->mu; /* (E2) / mu */
    double dxi = (c->mu * c->l1 * COS(theta1) * dtheta1 + c->m2 * c->l2 * COS(theta2) * dtheta2) / c->mu;
    double chi = x - c->x_d - xi / c->k_c, sv = c->k_c * v - dxi; /* (E3) */
    double a = 0.5 * c->u_max;
    double u = -a * TANH(c->k_p * chi / a) - a * TANH(c->k_d * sv / a); /* (E4) */
    return limited(u, v, c->u_max, c->v_max, c->h);
}

static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    if (0.5 * c->u_max == 0) return ZERO_DIVISION(r); /* u_max below 1e-323: (E4) divides by a = 0 */
    out[0] = control(c, &values[VR_x]);
    return MODEL_OK;
}

STATELESS_COMPONENT;
