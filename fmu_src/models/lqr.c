/*
 * The LqrController component in C: the native twin of crane_fmu/model/lqr.py (its variables, configure(), the
 * gain schedule, control() with limits.limited()), registered as a component (component.h). Its variables, value
 * references, start values and parameter rules come from LqrController_variables.h, generated from lqr.VARIABLES.
 * The designs (ZOH discretisation, Riccati doubling, gains: lqr_design.c over linalg.c) are done when
 * initialisation ends; before that the output follows the parameters. No state: u follows the inputs of the same
 * instant (direct feedthrough).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "LqrController_variables.h"
#include "lqr_design.h"
#include "py_repr.h"
#include "rules.h"

enum { SCHEDULE_POINTS = 21 }; /* lqr.SCHEDULE_POINTS */

/* lqr.Config: the gains for l1, the limits and the schedule (designs over [l1_low, l1_high]), fixed-size so that
   an FMU state is a plain copy of the model. */
typedef struct {
    double gains[N_STATE], x_d, u_max, v_max, h;
    double offset_free;   /* lqr.Config.offset_free, and its crane model (lqr.force_target()) */
    PlantParameters plant;
    int scheduled;
    double lengths[SCHEDULE_POINTS], table[SCHEDULE_POINTS][N_STATE];
} Config;

#define V(name) (values[VR_##name])

/* lqr.design() for the controller's crane model with the cable length l1 (lqr_design.c). */
static const char *design(const double values[], double l1, double gains[N_STATE]) {
    PlantParameters p = {V(m1), V(m2), l1, V(l2), V(g)};
    return lqr_design(&p, &values[VR_q_x], V(r), V(h), gains);
}

/* lqr.configure(), after its RULES (the generated parameter_rules()): the schedule's designs and the design for
   l1. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double low = V(l1_low), high = V(l1_high);
    const char *error;
    c->scheduled = !(low == 0.0 && high == 0.0);
    if (c->scheduled) {
        for (int i = 0; i < SCHEDULE_POINTS; i++) {
            c->lengths[i] = low + (high - low) * i / (SCHEDULE_POINTS - 1);
            if ((error = design(values, c->lengths[i], c->table[i]))) return report(r, MODEL_ERROR, "%s", error);
        }
    }
    if ((error = design(values, V(l1), c->gains))) return report(r, MODEL_ERROR, "%s", error);
    c->x_d = V(x_d), c->u_max = unlimited(V(u_max)), c->v_max = unlimited(V(v_max)), c->h = V(h);
    c->offset_free = V(offset_free);
    PlantParameters p = {V(m1), V(m2), V(l1), V(l2), V(g)};
    c->plant = p;
    return MODEL_OK;
}

/* lqr.scheduled_gains(): linear between the schedule's designs for the measured l1 (clamped to its range); the
   gains for the parameter l1 without a schedule or a measurement (l1 <= 0). */
static const char *scheduled_gains(const Config *c, double l1, double gains[N_STATE]) {
    memcpy(gains, c->gains, sizeof c->gains);
    if (!c->scheduled || !(l1 > 0)) return NULL;
    const double *lengths = c->lengths;
    double spacing = lengths[1] - lengths[0];
    if (spacing == 0.0) return DIVISION_BY_ZERO; /* l1_high within a rounding of l1_low */
    double position = (py_min(py_max(l1, lengths[0]), lengths[SCHEDULE_POINTS - 1]) - lengths[0]) / spacing;
    int i = position >= SCHEDULE_POINTS - 2 ? SCHEDULE_POINTS - 2 : (int)position; /* min(int(position), 19) */
    double f = position - i;
    for (int j = 0; j < N_STATE; j++) gains[j] = c->table[i][j] + f * (c->table[i + 1][j] - c->table[i][j]);
    return NULL;
}

/* lqr.control(): u = ddx_ref - K (s - s_ref), s_ref = (x_ref + x_d, dx_ref, ...) moved by F2_hat, F1_hat
   (offset-free), within limits.limited(). */
static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    double gains[N_STATE], error[N_STATE];
    const char *failure = scheduled_gains(c, V(l1_now), gains);
    if (failure) return report(r, MODEL_ERROR, "%s", failure);
    for (int i = 0; i < N_STATE; i++) error[i] = values[VR_x + i] - values[VR_x_ref + i];
    error[0] -= c->x_d;
    double f2 = V(F2_hat), f1 = V(F1_hat);
    if (c->offset_free != 0.0 && (f2 != 0.0 || f1 != 0.0)) { /* the offset-free target: lqr.force_target(), the rest
                                                                 the estimated forces hold (eqs (8)-(9) at rest) */
        const PlantParameters *p = &c->plant;
        double theta1 = (f1 + f2) / ((p->m1 + p->m2) * p->g), theta2 = f2 / (p->m2 * p->g);
        if (c->offset_free == 1.0) error[0] -= -(p->l1 * theta1 + p->l2 * theta2); /* the load at x_d */
        error[2] -= theta1, error[4] -= theta2;
    }
    out[0] = limited(V(ddx_ref) - la_dot(gains, error, N_STATE), V(dx), c->u_max, c->v_max, c->h);
    return MODEL_OK;
}

STATELESS_COMPONENT;
