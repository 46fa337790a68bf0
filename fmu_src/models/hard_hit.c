/*
 * The HardHitController component in C: the native twin of crane_fmu/model/hard_hit.py (its variables,
 * configure(), the two LQR designs of lqr_design.c, the swing energy of eq (E1), the blend and control() with
 * limits.limited()), registered as a component (component.h). Its variables and parameter rules come from
 * HardHitController_variables.h, generated from hard_hit.VARIABLES. The designs are done when initialisation ends;
 * before that the output follows the parameters. No state: u follows the inputs of the same instant (direct
 * feedthrough).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "HardHitController_variables.h"
#include "lqr_design.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

/* hard_hit.Config */
typedef struct {
    double near[N_STATE], far[N_STATE], e_near, e_far, mu, m2, l1, l2, g, x_d, u_max, v_max, h;
} Config;

#define V(name) (values[VR_##name])

/* hard_hit.configure(), after its RULES (the generated parameter_rules()): the near and the far design. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double near = V(theta_near), far = V(theta_far);
    PlantParameters p = {V(m1), V(m2), V(l1), V(l2), V(g)};
    double far_weights[N_STATE];
    memcpy(far_weights, &values[VR_q_x], sizeof far_weights);
    far_weights[0] = V(q_x_far);
    const char *error;
    if ((error = lqr_design(&p, &values[VR_q_x], V(r), V(h), c->near)) ||
        (error = lqr_design(&p, far_weights, V(r_far), V(h), c->far)))
        return report(r, MODEL_ERROR, "%s", error);
    c->mu = p.m1 + p.m2, c->m2 = p.m2, c->l1 = p.l1, c->l2 = p.l2, c->g = p.g;
    /* the energy of both angles held at theta_near, theta_far */
    c->e_near = p.g * (c->mu * p.l1 + p.m2 * p.l2) * (1.0 - COS(near));
    c->e_far = p.g * (c->mu * p.l1 + p.m2 * p.l2) * (1.0 - COS(far));
    c->x_d = V(x_d), c->u_max = unlimited(V(u_max)), c->v_max = unlimited(V(v_max)), c->h = V(h);
    return MODEL_OK;
}

/* hard_hit.swing_energy(), eq (E1): kinetic energy of hook and payload relative to the trolley plus their
   potential energy [J]. */
static double swing_energy(const Config *c, const double s[N_STATE]) {
    double a = s[2], da = s[3], b = s[4], db = s[5];
    double kinetic = 0.5 * c->mu * square(c->l1 * da) +
                     0.5 * c->m2 * (square(c->l2 * db) + 2.0 * c->l1 * c->l2 * da * db * COS(a - b));
    return kinetic + c->g * (c->mu * c->l1 * (1.0 - COS(a)) + c->m2 * c->l2 * (1.0 - COS(b)));
}

/* hard_hit.control(): u = ddx_ref - K(w) (s - s_ref), K(w) = (1 - w) K_near + w K_far, within the limits. */
static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    const double *s = &values[VR_x];
    if (c->e_far - c->e_near == 0.0) return ZERO_DIVISION(r); /* theta_far within a rounding of theta_near */
    double w = py_min(1.0, py_max(0.0, (swing_energy(c, s) - c->e_near) / (c->e_far - c->e_near))); /* blend() */
    double gains[N_STATE], error[N_STATE];
    for (int i = 0; i < N_STATE; i++) gains[i] = w == 0.0 ? c->near[i] : (1.0 - w) * c->near[i] + w * c->far[i];
    for (int i = 0; i < N_STATE; i++) error[i] = s[i] - values[VR_x_ref + i];
    error[0] -= c->x_d;
    out[0] = limited(V(ddx_ref) - la_dot(gains, error, N_STATE), V(dx), c->u_max, c->v_max, c->h);
    return MODEL_OK;
}

STATELESS_COMPONENT;
