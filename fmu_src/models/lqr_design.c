/*
 * lqr.continuous_model() and lqr.design() in C; see lqr_design.h.
 */
#include <stddef.h>

#include "lqr_design.h"

/* q'' = -W q - w u with W = N^-1 diag((m1+m2) g, g), w = N^-1 (m1+m2, 1), N = [[(m1+m2) l1, m2 l2], [l1, l2]]
   (plant.linearisation()). */
const char *continuous_model(const PlantParameters *p, Matrix *a, Matrix *b) {
    double m12 = p->m1 + p->m2, g = p->g;
    double na = m12 * p->l1, nb = p->m2 * p->l2, nc = p->l1, nd = p->l2;
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

/* K = (r + Bd' P Bd)^-1 Bd' P Ad for the ZOH discretisation (Ad, Bd) at step h, Q = diag(weights), P from the
   discrete algebraic Riccati equation. */
const char *lqr_design(const PlantParameters *p, const double weights[N_STATE], double r, double h,
                       double gains[N_STATE]) {
    Matrix a, b;
    const char *error = continuous_model(p, &a, &b);
    return error ? error : lqr_design_of(a, b, weights, r, h, gains);
}

/* lqr.design_of(): the same for one axis' s' = A s + B u given (6 states, one input). */
const char *lqr_design_of(Matrix a, Matrix b, const double weights[N_STATE], double r, double h,
                          double gains[N_STATE]) {
    Matrix ad, bd, big_p, q = la_zeros(N_STATE, N_STATE), rr = la_zeros(1, 1);
    for (int i = 0; i < N_STATE; i++) q.v[i][i] = weights[i];
    rr.v[0][0] = r;
    const char *error = la_zoh(a, b, h, &ad, &bd);
    if (error || (error = la_dare(ad, bd, q, rr, &big_p))) return error;
    Matrix pb = la_matmul(big_p, bd), bd_t = la_transpose(bd), pb_t = la_transpose(pb);
    double bt_p_b = la_dot(bd_t.v[0], pb_t.v[0], N_STATE);
    Matrix bt_p_a = la_matmul(pb_t, ad);
    if (r + bt_p_b == 0.0) return DIVISION_BY_ZERO;
    for (int j = 0; j < N_STATE; j++) gains[j] = bt_p_a.v[0][j] / (r + bt_p_b);
    return NULL;
}
