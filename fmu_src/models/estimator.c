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

/* estimator.Config: Ad, Bd, the gain M (6 x measurements), the measured state positions and the delay. */
typedef struct {
    double ad[N_STATE][N_STATE], bd[N_STATE], gain[N_STATE][MAX_MEASURED];
    int rows[MAX_MEASURED], n_rows, delay;
} Config;

typedef struct {
    int started;
    double s[N_STATE];          /* the prediction for the measurement's time, */
    double history[MAX_DELAY];  /* the last delay inputs u, oldest first, */
    double estimate[N_STATE];   /* and the output */
} State;

#define V(name) (values[VR_##name])

/* estimator.noise_model(): (Ad, Bd, Qd), the crane held over h and the process noise covariance
   Qd = Gd diag(sigma_u^2, sigma_swing^2, sigma_swing^2) Gd'. */
static const char *noise_model(const PlantParameters *p, double h, double sigma_u, double sigma_swing, Matrix *ad,
                               Matrix *bd, Matrix *qd) {
    Matrix a, b, gd;
    const char *error = continuous_model(p, &a, &b);
    if (error) return error;
    Matrix g = la_zeros(N_STATE, 3);
    for (int i = 0; i < N_STATE; i++) /* the unknown accelerations: the trolley's as u, each angle's on its rate */
        g.v[i][0] = b.v[i][0], g.v[i][1] = i == 3 ? 1.0 : 0.0, g.v[i][2] = i == 5 ? 1.0 : 0.0;
    if ((error = la_zoh(a, g, h, ad, &gd))) return error;
    *bd = la_zeros(N_STATE, 1);
    for (int i = 0; i < N_STATE; i++) bd->v[i][0] = gd.v[i][0];
    double variances[3] = {square(sigma_u), square(sigma_swing), square(sigma_swing)};
    if (isinf(variances[0]) || isinf(variances[1])) return SQUARE_OVERFLOW; /* the sigmas are finite */
    *qd = la_zeros(N_STATE, N_STATE);
    for (int i = 0; i < N_STATE; i++) {
        double weighted[3];
        for (int k = 0; k < 3; k++) weighted[k] = gd.v[i][k] * variances[k];
        for (int j = 0; j < N_STATE; j++) qd->v[i][j] = la_dot(weighted, gd.v[j], 3);
    }
    return NULL;
}

/* estimator.design(): the gain M = P C' (C P C' + R)^-1 of the steady filter, P from the filter Riccati equation
   (linalg.dare of Ad', C'). */
static const char *design(const Matrix *ad, const Matrix *qd, const double sigmas[MAX_MEASURED], Config *c) {
    int n = c->n_rows;
    Matrix cc = la_zeros(n, N_STATE), r = la_zeros(n, n), big_p, gain_t;
    for (int i = 0; i < n; i++) {
        cc.v[i][c->rows[i]] = 1.0, r.v[i][i] = square(sigmas[i]);
        if (isinf(r.v[i][i])) return SQUARE_OVERFLOW; /* the sigmas are finite */
    }
    const char *error = la_dare(la_transpose(*ad), la_transpose(cc), *qd, r, &big_p);
    if (error) return error;
    Matrix pct = la_zeros(N_STATE, n), innovation = la_zeros(n, n); /* P C', C P C' + R */
    for (int i = 0; i < N_STATE; i++)
        for (int j = 0; j < n; j++) pct.v[i][j] = big_p.v[i][c->rows[j]];
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) innovation.v[a][b] = big_p.v[c->rows[a]][c->rows[b]] + r.v[a][b];
    if ((error = la_solve(innovation, la_transpose(pct), &gain_t))) return error; /* innovation symmetric */
    for (int i = 0; i < N_STATE; i++)
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
    const char *error = noise_model(&p, V(h), V(sigma_u), V(sigma_swing), &ad, &bd, &qd);
    if (error || (error = design(&ad, &qd, sigmas, c))) return report(r, MODEL_ERROR, "%s", error);
    for (int i = 0; i < N_STATE; i++) {
        memcpy(c->ad[i], ad.v[i], sizeof c->ad[i]);
        c->bd[i] = bd.v[i][0];
    }
    return MODEL_OK;
}

/* (started, zeros, delay zeros, zeros) */
static void initial_state(const double values[], const Config *c, State *s) { memset(s, 0, sizeof *s); }

static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    memcpy(out, s->estimate, sizeof s->estimate);
    return MODEL_OK;
}

/* estimator._predict(): Ad s + Bd u, in place. */
static void predict(const Config *c, double s[N_STATE], double u) {
    double next[N_STATE];
    for (int i = 0; i < N_STATE; i++) next[i] = la_dot(c->ad[i], s, N_STATE) + c->bd[i] * u;
    memcpy(s, next, sizeof next);
}

/* estimator.update(): correct with the measurement held over the step (the first one is the state), predict with
   the oldest input held (u_{k-d}), and the estimate forward with the inputs applied since. */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    const double y[MAX_MEASURED] = {V(x_meas), V(theta1_meas), V(theta2_meas)};
    if (!s->started) {
        double first[N_STATE] = {y[0], 0.0, y[1], 0.0, c->n_rows == 3 ? y[2] : 0.0, 0.0};
        memcpy(s->s, first, sizeof first);
    } else {
        double innovation[MAX_MEASURED];
        for (int i = 0; i < c->n_rows; i++) innovation[i] = y[i] - s->s[c->rows[i]];
        for (int i = 0; i < N_STATE; i++) s->s[i] = s->s[i] + la_dot(c->gain[i], innovation, c->n_rows);
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
