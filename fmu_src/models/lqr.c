/*
 * The LqrController component in C: the native twin of crane_fmu/model/lqr.py (its variables, configure()
 * rules and messages in their order, design(), the gain schedule, control() with limits.limited()), registered
 * as a component (component.h). Its variables, value references and start values come from
 * LqrController_variables.h, generated from lqr.VARIABLES. The design (ZOH discretisation, Riccati doubling,
 * gains; linalg.c) is done when initialisation ends; before that the output follows the parameters. No state:
 * u follows the inputs of the same instant (direct feedthrough).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "LqrController_variables.h"
#include "linalg.h"
#include "py_repr.h"
#include "rules.h"

enum { N_STATE = 6, SCHEDULE_POINTS = 21 }; /* s = (x, dx, theta1, dtheta1, theta2, dtheta2); lqr.SCHEDULE_POINTS */

/* lqr.Config: the gains for l1, the limits and the schedule (designs over [l1_low, l1_high]), fixed-size so that
   an FMU state is a plain copy of the model. */
typedef struct {
    double gains[N_STATE], x_d, u_max, v_max, h;
    int scheduled;
    double lengths[SCHEDULE_POINTS], table[SCHEDULE_POINTS][N_STATE];
} Config;

#define V(name) (values[VR_##name])
#define R(value) py_repr(value, (char[REPR_SIZE]){0})
#define DIVISION_BY_ZERO "ZeroDivisionError: float division by zero" /* Python's, where C would give inf */

/* lqr.continuous_model(): s' = A s + B u with x'' = u (eq 12) and plant.linearisation() of eqs (8)-(9),
   q'' = -W q - w u with W = N^-1 diag((m1+m2) g, g), w = N^-1 (m1+m2, 1), N = [[(m1+m2) l1, m2 l2], [l1, l2]]. */
static const char *continuous_model(const double values[], double l1, Matrix *a, Matrix *b) {
    double m12 = V(m1) + V(m2), g = V(g);
    double na = m12 * l1, nb = V(m2) * V(l2), nc = l1, nd = V(l2);
    double det = na * nd - nb * nc;
    if (det == 0.0) return DIVISION_BY_ZERO;
    double inv[2][2] = {{nd / det, -nb / det}, {-nc / det, na / det}}; /* N^-1 */
    *a = la_zeros(N_STATE, N_STATE), *b = la_zeros(N_STATE, 1);
    a->v[0][1] = a->v[2][3] = a->v[4][5] = 1.0;
    b->v[1][0] = 1.0;
    for (int i = 0; i < 2; i++) { /* rows dtheta1 (3) and dtheta2 (5) */
        a->v[3 + 2 * i][2] = -(inv[i][0] * m12 * g), a->v[3 + 2 * i][4] = -(inv[i][1] * g);
        b->v[3 + 2 * i][0] = -(inv[i][0] * m12 + inv[i][1]);
    }
    return NULL;
}

/* lqr.design(): K = (r + Bd' P Bd)^-1 Bd' P Ad for the ZOH discretisation (Ad, Bd) at step h, Q = diag(q_*),
   P from the discrete algebraic Riccati equation. NULL, or the Python exception's text. */
static const char *design(const double values[], double l1, double gains[N_STATE]) {
    Matrix a, b, ad, bd, p, q = la_zeros(N_STATE, N_STATE), r = la_zeros(1, 1);
    for (int i = 0; i < N_STATE; i++) q.v[i][i] = values[VR_q_x + i];
    r.v[0][0] = V(r);
    const char *error = continuous_model(values, l1, &a, &b);
    if (error || (error = la_zoh(a, b, V(h), &ad, &bd)) || (error = la_dare(ad, bd, q, r, &p))) return error;
    Matrix pb = la_matmul(p, bd), bd_t = la_transpose(bd), pb_t = la_transpose(pb);
    double bt_p_b = la_dot(bd_t.v[0], pb_t.v[0], N_STATE);
    Matrix bt_p_a = la_matmul(pb_t, ad);
    if (V(r) + bt_p_b == 0.0) return DIVISION_BY_ZERO;
    for (int j = 0; j < N_STATE; j++) gains[j] = bt_p_a.v[0][j] / (V(r) + bt_p_b);
    return NULL;
}

/* lqr.configure(): the rules of parameters.plant_parameters, the weights, r, h, x_d, limits.check and the
   schedule, in that order and in their words; then the schedule's designs and the design for l1. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    ModelStatus plant = plant_rules(V(m1), V(m2), V(l1), V(l2), V(g), r);
    if (plant != MODEL_OK) return plant;
    for (int i = 0; i < N_STATE; i++) {
        double value = values[VR_q_x + i];
        if (!(value >= 0 && value < INFINITY)) return rule(r, VARIABLE_TABLE[VR_q_x + i].name, ">= 0 and finite", value);
    }
    if (!(isfinite(V(r)) && V(r) > 0)) return rule(r, "r", "> 0 and finite", V(r));
    if (!(isfinite(V(h)) && V(h) > 0)) return rule(r, "h", "> 0 and finite", V(h));
    if (!isfinite(V(x_d))) return rule(r, "x_d", "finite", V(x_d));
    if (!(V(u_max) > 0)) return rule(r, "u_max", "> 0 (inf: no limit)", V(u_max));
    if (!(V(v_max) > 0)) return rule(r, "v_max", "> 0 (inf: no limit)", V(v_max));
    double low = V(l1_low), high = V(l1_high);
    const char *error;
    c->scheduled = !(low == 0.0 && high == 0.0);
    if (c->scheduled) {
        if (!(isfinite(low) && low > 0)) return rule(r, "l1_low", "> 0 and finite", low);
        if (!(high > low) || !isfinite(high))
            return report(r, MODEL_ERROR, "l1_high must be finite and > l1_low = %s, got %s", R(low), R(high));
        for (int i = 0; i < SCHEDULE_POINTS; i++) {
            c->lengths[i] = low + (high - low) * i / (SCHEDULE_POINTS - 1);
            if ((error = design(values, c->lengths[i], c->table[i]))) return report(r, MODEL_ERROR, "%s", error);
        }
    }
    if ((error = design(values, V(l1), c->gains))) return report(r, MODEL_ERROR, "%s", error);
    c->x_d = V(x_d), c->u_max = unlimited(V(u_max)), c->v_max = unlimited(V(v_max)), c->h = V(h);
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

/* lqr.control(): u = ddx_ref - K (s - s_ref), s_ref = (x_ref + x_d, dx_ref, ...), within limits.limited(). */
static ModelStatus outputs(const double values[], const Config *c, double out[], const Reporter *r) {
    double gains[N_STATE], error[N_STATE];
    const char *failure = scheduled_gains(c, V(l1_now), gains);
    if (failure) return report(r, MODEL_ERROR, "%s", failure);
    for (int i = 0; i < N_STATE; i++) error[i] = values[VR_x + i] - values[VR_x_ref + i];
    error[0] -= c->x_d;
    out[0] = limited(V(ddx_ref) - la_dot(gains, error, N_STATE), V(dx), c->u_max, c->v_max, c->h);
    return MODEL_OK;
}

STATELESS_COMPONENT;
