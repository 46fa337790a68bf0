/*
 * The StateEstimator component in C: the native twin of crane_fmu/model/estimator.py (its variables, configure(),
 * noise_model() and design(): the steady Kalman filter of the crane linearised about rest, and update(): correct,
 * then predict over the delay), registered as a component (component.h). Its variables and parameter rules come
 * from StateEstimator_variables.h, generated from estimator.VARIABLES. The filter is designed when initialisation
 * ends (lqr_design.c's continuous model, linalg.c's ZOH and Riccati doubling, in estimator.py's order of
 * operations). Its state is (started, s, the last delay inputs u, the estimate); the outputs are the estimate,
 * zero until the first step (no direct feedthrough).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "StateEstimator_variables.h"
#include "lqr_design.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

enum { MAX_DELAY = 100, MAX_MEASURED = 3 }; /* the rule on delay; x, theta1 and (a camera's) theta2 */
enum { MAX_FILTER = N_STATE + 2 }; /* the state and, with sigma_force > 0, the forces F2 (payload), F1 (hook) */

/* estimator.Config: Ad, Bd, the gain M (6 x measurements), the measured state positions and the delay. */
typedef struct {
    double ad[MAX_FILTER][MAX_FILTER], bd[MAX_FILTER], gain[MAX_FILTER][MAX_MEASURED];
    int rows[MAX_MEASURED], n_rows, delay, n; /* n: 6, or with the forces 7 (F2) or 8 (F2, F1) */
} Config;

typedef struct {
    int started;
    double s[MAX_FILTER];        /* the prediction for the measurement's time, */
    double history[MAX_DELAY];   /* the last delay inputs u, oldest first, */
    double estimate[MAX_FILTER]; /* and the output */
} State;

#define V(name) (values[VR_##name])

/* estimator.force_columns(): N^-1 (1, 1/m2) and N^-1 (1, 0), the swing accelerations per newton of a force on the
   payload and on the hook. */
static const char *force_columns(const PlantParameters *p, double e[2][2]) {
    double m12 = p->m1 + p->m2;
    double na = m12 * p->l1, nb = p->m2 * p->l2, nc = p->l1, nd = p->l2;
    double det = na * nd - nb * nc;
    if (det == 0.0 || p->m2 == 0.0) return DIVISION_BY_ZERO;
    double inv[2][2] = {{nd / det, -nb / det}, {-nc / det, na / det}}; /* N^-1 */
    for (int i = 0; i < 2; i++) e[0][i] = inv[i][0] + inv[i][1] / p->m2, e[1][i] = inv[i][0];
    return NULL;
}

/* estimator.noise_model(): (Ad, Bd, Qd), the crane held over h and the process noise covariance
   Qd = Gd diag(sigma_u^2, sigma_swing^2, sigma_swing^2) Gd'; with sigma_force > 0 the forces' states, F2 on the
   payload and (forces = 2) F1 on the hook (random walks, their rates' variance sigma_force^2). */
static const char *noise_model(const PlantParameters *p, double h, double sigma_u, double sigma_swing,
                               double sigma_force, int forces, Matrix *ad, Matrix *bd, Matrix *qd) {
    Matrix a, b, gd;
    const char *error = continuous_model(p, &a, &b);
    if (error) return error;
    if (!(sigma_force > 0)) forces = 0;
    int n = N_STATE + forces, m = 3 + forces;
    Matrix g = la_zeros(n, m);
    for (int i = 0; i < N_STATE; i++) /* the unknown accelerations: the trolley's as u, each angle's on its rate */
        g.v[i][0] = b.v[i][0], g.v[i][1] = i == 3 ? 1.0 : 0.0, g.v[i][2] = i == 5 ? 1.0 : 0.0;
    double variances[5] = {square(sigma_u), square(sigma_swing), square(sigma_swing), square(sigma_force),
                           square(sigma_force)};
    if (forces) {
        double e[2][2];
        if ((error = force_columns(p, e))) return error;
        a.rows = a.cols = n; /* la_zeros left the new rows and columns 0 */
        for (int k = 0; k < forces; k++) {
            a.v[3][N_STATE + k] = e[k][0], a.v[5][N_STATE + k] = e[k][1];
            g.v[N_STATE + k][3 + k] = 1.0;
        }
        if (isinf(variances[3])) return SQUARE_OVERFLOW;
    }
    if ((error = la_zoh(a, g, h, ad, &gd))) return error;
    *bd = la_zeros(n, 1);
    for (int i = 0; i < n; i++) bd->v[i][0] = gd.v[i][0];
    if (isinf(variances[0]) || isinf(variances[1])) return SQUARE_OVERFLOW; /* the sigmas are finite */
    *qd = la_zeros(n, n);
    for (int i = 0; i < n; i++) {
        double weighted[5];
        for (int k = 0; k < m; k++) weighted[k] = gd.v[i][k] * variances[k];
        for (int j = 0; j < n; j++) qd->v[i][j] = la_dot(weighted, gd.v[j], m);
    }
    return NULL;
}

/* estimator.design(): the gain M = P C' (C P C' + R)^-1 of the steady filter, P from the filter Riccati equation
   (linalg.dare of Ad', C'). */
static const char *design(const Matrix *ad, const Matrix *qd, const double sigmas[MAX_MEASURED], Config *c) {
    int n = c->n_rows;
    Matrix cc = la_zeros(n, c->n), r = la_zeros(n, n), big_p, gain_t;
    for (int i = 0; i < n; i++) {
        cc.v[i][c->rows[i]] = 1.0, r.v[i][i] = square(sigmas[i]);
        if (isinf(r.v[i][i])) return SQUARE_OVERFLOW; /* the sigmas are finite */
    }
    const char *error = la_dare(la_transpose(*ad), la_transpose(cc), *qd, r, &big_p);
    if (error) return error;
    Matrix pct = la_zeros(c->n, n), innovation = la_zeros(n, n); /* P C', C P C' + R */
    for (int i = 0; i < c->n; i++)
        for (int j = 0; j < n; j++) pct.v[i][j] = big_p.v[i][c->rows[j]];
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) innovation.v[a][b] = big_p.v[c->rows[a]][c->rows[b]] + r.v[a][b];
    if ((error = la_solve(innovation, la_transpose(pct), &gain_t))) return error; /* innovation symmetric */
    for (int i = 0; i < c->n; i++)
        for (int j = 0; j < n; j++) c->gain[i][j] = gain_t.v[j][i];
    return NULL;
}

/* estimator.configure(), after its RULES (the generated parameter_rules()): the filter. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double delay = V(delay);
    PlantParameters p = {V(m1), V(m2), V(l1), V(l2), V(g)};
    Matrix ad, bd, qd;
    c->n_rows = V(camera) == 1.0 ? 3 : 2, c->rows[0] = 0, c->rows[1] = 2, c->rows[2] = 4; /* measured_rows() */
    c->delay = (int)delay;
    double sigmas[MAX_MEASURED] = {V(sigma_x), V(sigma_theta), V(sigma_theta)};
    int forces = c->n_rows == 3 ? 2 : 1; /* estimator.force_states(): one per measured angle */
    c->n = V(sigma_force) > 0 ? N_STATE + forces : N_STATE;
    const char *error = noise_model(&p, V(h), V(sigma_u), V(sigma_swing), V(sigma_force), forces, &ad, &bd, &qd);
    if (error || (error = design(&ad, &qd, sigmas, c))) return report(r, MODEL_ERROR, "%s", error);
    for (int i = 0; i < c->n; i++) {
        for (int j = 0; j < c->n; j++) c->ad[i][j] = ad.v[i][j];
        c->bd[i] = bd.v[i][0];
    }
    return MODEL_OK;
}

/* (started, zeros, delay zeros, zeros) */
static void initial_state(const double values[], const Config *c, State *s) { memset(s, 0, sizeof *s); }

static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    memcpy(out, s->estimate, N_STATE * sizeof s->estimate[0]);
    out[N_STATE] = c->n > N_STATE ? s->estimate[N_STATE] : 0.0;             /* F2_hat */
    out[N_STATE + 1] = c->n > N_STATE + 1 ? s->estimate[N_STATE + 1] : 0.0; /* F1_hat */
    return MODEL_OK;
}

/* estimator._predict(): Ad s + Bd u, in place. */
static void predict(const Config *c, double s[MAX_FILTER], double u) {
    double next[MAX_FILTER];
    for (int i = 0; i < c->n; i++) next[i] = la_dot(c->ad[i], s, c->n) + c->bd[i] * u;
    memcpy(s, next, (size_t)c->n * sizeof next[0]);
}

/* estimator.update(): correct with the measurement held over the step (the first one is the state), predict with
   the oldest input held (u_{k-d}), and the estimate forward with the inputs applied since. */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    const double y[MAX_MEASURED] = {V(x_meas), V(theta1_meas), V(theta2_meas)};
    if (!s->started) {
        double first[MAX_FILTER] = {y[0], 0.0, y[1], 0.0, c->n_rows == 3 ? y[2] : 0.0, 0.0, 0.0, 0.0}; /* forces 0 */
        memcpy(s->s, first, sizeof first);
    } else {
        double innovation[MAX_MEASURED];
        for (int i = 0; i < c->n_rows; i++) innovation[i] = y[i] - s->s[c->rows[i]];
        for (int i = 0; i < c->n; i++) s->s[i] = s->s[i] + la_dot(c->gain[i], innovation, c->n_rows);
    }
    double applied[MAX_DELAY + 1]; /* u_{k-d} .. u_k */
    memcpy(applied, s->history, (size_t)c->delay * sizeof applied[0]);
    applied[c->delay] = V(u);
    predict(c, s->s, applied[0]);
    memcpy(s->estimate, s->s, sizeof s->s);
    for (int i = 1; i <= c->delay; i++) predict(c, s->estimate, applied[i]);
    memcpy(s->history, applied + 1, (size_t)c->delay * sizeof applied[0]);
    s->started = 1;
    return MODEL_OK;
}

STATEFUL_COMPONENT;
