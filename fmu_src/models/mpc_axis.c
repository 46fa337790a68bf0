/*
 * The planar MPC of one axis in C: mpc_axis.h says what it is.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpc_axis.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

#define Config MpcConfig
#define State MpcState

#define R(value) py_repr(value, (char[REPR_SIZE]){0})
#define NOT_POSITIVE_DEFINITE "ArithmeticError: the matrix is not positive definite"

static const double ROBUST_WEIGHTS[N_ROBUST_WEIGHTS] = {1e6, 3e5, 1e5, 3e4, 1e4}; /* mpc.ROBUST_WEIGHTS */
static const double PEAK_STRETCHES[N_PEAK_STRETCHES] = {1.1, 1.2, 1.3, 1.5, 1.7, 2.0}; /* mpc.PEAK_STRETCHES */

/* mpc.constraint_rows(): one row per input (1.0 at k) and per speed (interval over the inputs up to k). */
static void constraint_rows(int steps, double interval, int first[], int length[], int offset[], double values[]) {
    values[0] = 1.0;
    for (int k = 0; k < steps; k++) {
        values[1 + k] = interval;
        first[k] = k, length[k] = 1, offset[k] = 0;
        first[steps + k] = 0, length[steps + k] = k + 1, offset[steps + k] = 1;
    }
}

static QpPrepared prepared(const Config *c, Design *d) {
    return (QpPrepared){c->steps, 2 * c->steps, c->first, c->length, c->offset, c->values,
                        d->hinv, d->g, d->norms, d->chain_end};
}

/* mpc.predict_rows(): b_k = Ad^k Bd for k < steps. */
static void predict_rows_of(const double ad[N_STATE][N_STATE], const double bd[N_STATE], int steps, double *b) {
    memcpy(b, bd, N_STATE * sizeof *b);
    for (int k = 1; k < steps; k++)
        for (int i = 0; i < N_STATE; i++) b[k * N_STATE + i] = la_dot(ad[i], &b[(k - 1) * N_STATE], N_STATE);
}

static void predict_rows(const Design *d, int steps, double *b) {
    predict_rows_of(d->ad, d->bd, steps, b);
}

/* planner.modes(): the swing modes' angular frequencies and shapes of q'' = -W q - w u (as planner.c's). */
static const char *modes_of(const PlantParameters *p, double omegas[2], double shapes[2][2]) {
    double m12 = p->m1 + p->m2, g = p->g;
    double na = m12 * p->l1, nb = p->m2 * p->l2, nc = p->l1, nd = p->l2; /* N of linearisation() */
    double ndet = na * nd - nb * nc;
    if (ndet == 0) return DIVISION_BY_ZERO;
    double inv[2][2] = {{nd / ndet, -nb / ndet}, {-nc / ndet, na / ndet}};
    double a = inv[0][0] * m12 * g, b = inv[0][1] * g, cc = inv[1][0] * m12 * g, dd = inv[1][1] * g; /* W */
    double half_trace = (a + dd) / 2, det = a * dd - b * cc, discriminant = half_trace * half_trace - det;
    if (discriminant < 0) return "ValueError: math domain error";
    double root = sqrt(discriminant), lambdas[2] = {half_trace - root, half_trace + root};
    for (int k = 0; k < 2; k++) { /* (W - lam I) v = 0 */
        if (b != 0) shapes[k][0] = b, shapes[k][1] = lambdas[k] - a;
        else shapes[k][0] = lambdas[k] - dd, shapes[k][1] = cc;
    }
    if (shapes[0][0] * shapes[1][1] - shapes[1][0] * shapes[0][1] == 0) return DIVISION_BY_ZERO;
    if (lambdas[0] < 0 || lambdas[1] < 0) return "ValueError: math domain error";
    omegas[0] = sqrt(lambdas[0]), omegas[1] = sqrt(lambdas[1]);
    return NULL;
}

static const char *modes(const PlantParameters *p, Design *d) {
    return modes_of(p, d->omegas, d->shapes);
}

/* mpc.design(): the tracking QP for the crane p: H_ij = r delta_ij + sum_{k>=max(i,j)} b_{k-i}' Q_k b_{k-j},
   F_i = sum_{k>=i} b_{k-i}' Q_k Ad^{k+1} (Q_k = Q, P from the Riccati equation at k = N - 1), prepared. */
static const char *design(Config *c, const PlantParameters *p, Design *d) {
    int n = c->steps;
    Matrix a, b, ad, bd, terminal, q = la_zeros(N_STATE, N_STATE), rr = la_zeros(1, 1);
    const char *error = continuous_model(p, &a, &b);
    if (error || (error = la_zoh(a, b, c->interval, &ad, &bd))) return error;
    for (int i = 0; i < N_STATE; i++) q.v[i][i] = c->weights[i];
    rr.v[0][0] = c->r;
    if ((error = la_dare(ad, bd, q, rr, &terminal))) return error;
    d->l1 = p->l1;
    for (int i = 0; i < N_STATE; i++) {
        memcpy(d->ad[i], ad.v[i], sizeof d->ad[i]);
        d->bd[i] = bd.v[i][0];
    }
    double *hessian = c->scratch, *inverse_scratch = hessian + n * n, *rows = inverse_scratch + 2 * n * n;
    double *powers = rows + n * N_STATE; /* Ad^(k+1) for state k + 1, 36 each */
    predict_rows(d, n, rows);
    Matrix power = ad;
    for (int k = 0; k < n; k++) {
        for (int i = 0; i < N_STATE; i++) memcpy(powers + k * 36 + i * N_STATE, power.v[i], N_STATE * sizeof(double));
        power = la_matmul(ad, power);
    }
    memset(hessian, 0, (size_t)n * n * sizeof *hessian);
    for (int i = 0; i < n; i++) {
        double row_f[N_STATE] = {0};
        for (int k = i; k < n; k++) {
            const Matrix *weight = k == n - 1 ? &terminal : &q;
            double wb[N_STATE], column[N_STATE];
            for (int s = 0; s < N_STATE; s++) wb[s] = la_dot(weight->v[s], rows + (k - i) * N_STATE, N_STATE);
            for (int col = 0; col < N_STATE; col++) {
                for (int s = 0; s < N_STATE; s++) column[s] = powers[k * 36 + s * N_STATE + col];
                row_f[col] += la_dot(wb, column, N_STATE);
            }
            for (int j = i; j <= k; j++) hessian[i * n + j] += la_dot(wb, rows + (k - j) * N_STATE, N_STATE);
        }
        memcpy(d->gain[i], row_f, sizeof row_f);
    }
    for (int i = 0; i < n; i++) {
        hessian[i * n + i] += c->r;
        for (int j = i + 1; j < n; j++) hessian[j * n + i] = hessian[i * n + j];
    }
    QpPrepared qp = prepared(c, d);
    if (qp_prepare(&qp, hessian, inverse_scratch)) return NOT_POSITIVE_DEFINITE;
    return modes(p, d);
}

/* mpc.configure(), after its RULES (the generated parameter_rules()): the rules that need the interval and the
   horizon counted in steps, then the designs (one, or one per scheduled length). */
ModelStatus mpc_axis_configure(const MpcSettings *v, Config *c, const Reporter *r) {
    double u_max = unlimited(v->u_max), v_max = unlimited(v->v_max), cap = v->max_iterations;
    double h = v->h, every = py_max(1.0, rint(v->interval / h)), interval = every * h;
    double steps = py_max(1.0, rint(v->horizon / interval));
    if (steps > MAX_STEPS)
        return report(r, MODEL_ERROR, "horizon must be at most 200 intervals, got %s s = %.0f intervals of %s s",
                      R(v->horizon), steps, R(interval));
    if ((long long)(LONGEST_PLAN / interval) > MAX_PLAN)
        return report(r, MODEL_ERROR, "interval must be at least %s s (a plan of at most %d intervals), got %s s",
                      R(LONGEST_PLAN / MAX_PLAN), MAX_PLAN, R(interval));
    c->plant = (PlantParameters){v->m1, v->m2, v->l1, v->l2, v->g};
    memcpy(c->weights, v->q, sizeof c->weights);
    c->r = v->r, c->x_d = v->x_d, c->u_max = u_max, c->v_max = v_max, c->margin = v->margin, c->h = h;
    c->every = every, c->interval = interval, c->steps = (int)steps, c->max_iterations = (int)cap;
    c->replan_x = v->replan_x, c->replan_angle = v->replan_angle, c->offset_free = v->offset_free;
    c->estimated = v->estimated;
    double low = v->l1_low, high = v->l1_high;
    c->n_designs = 1;
    if (!(low == 0.0 && high == 0.0)) c->n_designs = SCHEDULE_POINTS;
    constraint_rows(c->steps, interval, c->first, c->length, c->offset, c->values);
    for (int i = 0; i < c->n_designs; i++) {
        PlantParameters p = c->plant;
        if (c->n_designs > 1) p.l1 = low + (high - low) * i / (SCHEDULE_POINTS - 1);
        const char *error = design(c, &p, &c->designs[i]);
        if (error) return report(r, MODEL_ERROR, "%s", error);
    }
    double identify = v->identify;
    c->samples = identify > 0 && c->n_designs == 1 ? (int)py_max(1.0, rint(identify / interval)) : 0;
    const char *error = lqr_design(&c->plant, c->weights, c->r, h, c->lqr_gains);
    for (int i = 0; !error && c->n_designs > 1 && i < SCHEDULE_POINTS; i++) {
        PlantParameters p = c->plant;
        p.l1 = c->designs[i].l1;
        error = lqr_design(&p, c->weights, c->r, h, c->lqr_table[i]);
    }
    if (error) return report(r, MODEL_ERROR, "%s", error);
    c->have_identified = c->memo_valid = c->have_corners = 0;
    return MODEL_OK;
}

/* mpc.nearest_design(): the design for the cable length nearest the measured l1 (the only one without a
   schedule). */
static Design *nearest_design(Config *c, double l1) {
    if (c->n_designs == 1 || !(l1 > 0)) return &c->designs[c->n_designs == 1 ? 0 : c->n_designs / 2];
    int best = 0;
    for (int i = 1; i < c->n_designs; i++)
        if (fabs(c->designs[i].l1 - l1) < fabs(c->designs[best].l1 - l1)) best = i;
    return &c->designs[best];
}

/* mpc.identified_design(): the design for the identified model (l1, l2, m2), m1 + m2 kept; made once. */
static const char *identified_design(Config *c, const double model[3], Design **out) {
    Design *d = &c->designs[SCHEDULE_POINTS];
    if (!(c->have_identified && c->identified[0] == model[0] && c->identified[1] == model[1] &&
          c->identified[2] == model[2])) {
        double mu = c->plant.m1 + c->plant.m2;
        PlantParameters p = {mu - model[2], model[2], model[0], model[1], c->plant.g};
        c->have_identified = 0;
        const char *error = design(c, &p, d);
        if (error) return error;
        memcpy(c->identified, model, sizeof c->identified);
        c->have_identified = 1;
    }
    *out = d;
    return NULL;
}

/* mpc.fast_mode_rows(): the rows that take a state to the fast swing mode's amplitude (eta, eta' / w) on the angle
   it moves most. */
static void fast_mode_rows(const double omegas[2], double shapes[2][2], double rows[2][N_STATE]) {
    double s11 = shapes[0][0], s21 = shapes[0][1], s12 = shapes[1][0], s22 = shapes[1][1];
    double det = s11 * s22 - s12 * s21, a = -s21 / det, b = s11 / det;
    double scale = py_max(fabs(shapes[1][0]), fabs(shapes[1][1])), w = omegas[1];
    memset(rows, 0, 2 * N_STATE * sizeof(double));
    rows[0][2] = a * scale, rows[0][4] = b * scale;
    rows[1][3] = a * scale / w, rows[1][5] = b * scale / w;
}

/* mpc.robust_ends(): the corners of SPREAD about the model `known` (l1, l2, m2; zeros: the configured crane),
   m1 + m2 kept, each with its Ad, Bd and fast_mode_rows(); made once. */
static const char *robust_ends(Config *c, const double known[3]) {
    if (c->have_corners && c->corners_for[0] == known[0] && c->corners_for[1] == known[1] &&
        c->corners_for[2] == known[2])
        return NULL;
    c->have_corners = 0;
    PlantParameters p = c->plant;
    if (known[0] > 0.0) {
        double mu = p.m1 + p.m2;
        p = (PlantParameters){mu - known[2], known[2], known[0], known[1], p.g};
    }
    const double spread[4] = {SPREAD_L1, SPREAD_L2, SPREAD_M1, SPREAD_M2};
    double factors[4][2];
    for (int i = 0; i < 4; i++) factors[i][0] = 1.0 - spread[i], factors[i][1] = 1.0 + spread[i];
    for (int k = 0; k < N_CORNERS; k++) { /* itertools.product's order: l1 outermost, m2 innermost */
        PlantParameters corner = p;
        corner.l1 = p.l1 * factors[0][(k >> 3) & 1], corner.l2 = p.l2 * factors[1][(k >> 2) & 1];
        corner.m1 = p.m1 * factors[2][(k >> 1) & 1], corner.m2 = p.m2 * factors[3][k & 1];
        Matrix a, b, ad, bd;
        double omegas[2], shapes[2][2];
        const char *error = continuous_model(&corner, &a, &b);
        if (error || (error = la_zoh(a, b, c->interval, &ad, &bd)) || (error = modes_of(&corner, omegas, shapes)))
            return error;
        for (int i = 0; i < N_STATE; i++) {
            memcpy(c->corner_ad[k][i], ad.v[i], sizeof c->corner_ad[k][i]);
            c->corner_bd[k][i] = bd.v[i][0];
        }
        fast_mode_rows(omegas, shapes, c->corner_rows[k]);
    }
    memcpy(c->corners_for, known, sizeof c->corners_for);
    c->have_corners = 1;
    return NULL;
}

/* mpc.speed_envelope(): the speed's bounds after k intervals, widened to braking at u_max from v0. */
static void speed_envelope(double v0, double v_max, double u_max, double interval, int k, double *low,
                           double *high) {
    *low = py_min(-v_max, v0 + u_max * interval * k);
    *high = py_max(v_max, v0 - u_max * interval * k);
}

/* mpc.feasible_start(): the guess moved, input by input, into the bounds and the speed envelope. */
static void feasible_start(const double *guess, int n, double v0, const double *lower_u, const double *upper_u,
                           double v_max, double u_max, double interval, double *u) {
    double v = v0;
    for (int k = 0; k < n; k++) {
        double low_v, high_v;
        speed_envelope(v0, v_max, u_max, interval, k + 1, &low_v, &high_v);
        double low = py_max(lower_u[k], (low_v - v) / interval), high = py_min(upper_u[k], (high_v - v) / interval);
        u[k] = py_min(py_max(guess[k], low), high);
        v += interval * u[k];
    }
}

/* mpc.rigid_move_time(): the trolley's own shortest rest-to-rest move. */
static double rigid_move_time(double distance, double u_max, double v_max) {
    distance = fabs(distance);
    if (distance <= v_max * v_max / u_max) return 2.0 * sqrt(distance / u_max);
    return distance / v_max + v_max / u_max;
}

/* The plan's memory: a QP of up to `most` intervals, the last attempt's solution and codes. */
typedef struct {
    int most, has_previous, previous_n;
    double *hinv, *g, *norms, *hessian, *scratch, *work, *columns, *f, *lower, *upper, *guess, *start, *x;
    double *previous, *previous_codes, *values, *found, *other, *projected;
    int *first, *length, *offset, *chain_end, *iwork, *hint_rows, *hint_sides, *active, *sides;
    void *block;
} PlanMemory;

static int plan_memory(PlanMemory *pm, int most) {
    size_t n = (size_t)most, m = 2 * n;
    size_t doubles = n * n + m * n + m + n * n + 2 * n * n + QP_WORK(n, m) + n * N_STATE + n + 2 * m + 5 * n + m +
                     (n + 1) + n + n * N_STATE + 2 * n;
    size_t ints = 4 * m + QP_IWORK(m) + 2 * m + 2 * m;
    pm->block = malloc(doubles * sizeof(double) + ints * sizeof(int));
    if (!pm->block) return -1;
    double *d = pm->block;
    pm->most = most, pm->has_previous = 0;
    pm->hinv = d, d += n * n;
    pm->g = d, d += m * n;
    pm->norms = d, d += m;
    pm->hessian = d, d += n * n;
    pm->scratch = d, d += 2 * n * n;
    pm->work = d, d += QP_WORK(n, m);
    pm->columns = d, d += n * N_STATE;
    pm->f = d, d += n;
    pm->lower = d, d += m;
    pm->upper = d, d += m;
    pm->guess = d, d += n;
    pm->start = d, d += n;
    pm->x = d, d += n;
    pm->previous = d, d += n;
    pm->found = d, d += n;
    pm->previous_codes = d, d += m;
    pm->values = d, d += n + 1;
    d += n;
    pm->other = d, d += n * N_STATE;
    pm->projected = d, d += 2 * n;
    int *i = (int *)d;
    pm->first = i, i += m;
    pm->length = i, i += m;
    pm->offset = i, i += m;
    pm->chain_end = i, i += m;
    pm->iwork = i, i += QP_IWORK(m);
    pm->hint_rows = i, i += m;
    pm->hint_sides = i, i += m;
    pm->active = i, i += m;
    pm->sides = i;
    return 0;
}

/* plan_move()'s ends(): b_k of (ad, bd) into b (input j's effect on the end state is b_{n-1-j}) and what the
   inputs must add to reach the target from s0 into miss. */
static void ends(const double ad[N_STATE][N_STATE], const double bd[N_STATE], const double s0[N_STATE],
                 const double target[N_STATE], int n, double *b, double miss[N_STATE]) {
    predict_rows_of(ad, bd, n, b);
    double free_[N_STATE];
    memcpy(free_, s0, sizeof free_);
    for (int k = 0; k < n; k++) {
        double next[N_STATE];
        for (int i = 0; i < N_STATE; i++) next[i] = la_dot(ad[i], free_, N_STATE);
        memcpy(free_, next, sizeof next);
    }
    for (int i = 0; i < N_STATE; i++) miss[i] = target[i] - free_[i];
}

/* plan_move()'s attempt(n): the solution of min RHO |s_n - target|^2 + |U|^2 (+ weight times each corner's fast
   mode at the end, with `robust`: the Config's corners, mpc.robust_ends) within the limits from the last
   attempt's (resampled, mpc._resampled), into pm->x; 1 when it reaches the target, -1 when H is not definite. */
static int attempt(const Design *d, const double s0[N_STATE], const double target[N_STATE], double u_max,
                   double v_max, double interval, int n, const Config *robust, double weight, PlanMemory *pm) {
    int m = 2 * n;
    double *b = pm->columns; /* b_k; input j's effect on the end state is b_{n-1-j} */
    double miss[N_STATE];
    ends(d->ad, d->bd, s0, target, n, b, miss); /* what the inputs must add */
    for (int i = 0; i < n; i++) {
        const double *ci = b + (n - 1 - i) * N_STATE;
        for (int j = 0; j < n; j++)
            pm->hessian[i * n + j] = RHO * la_dot(ci, b + (n - 1 - j) * N_STATE, N_STATE) + (i == j ? 1.0 : 0.0);
        pm->f[i] = -RHO * la_dot(ci, miss, N_STATE);
    }
    for (int k = 0; robust && k < N_CORNERS; k++) { /* another crane's end: its fast mode's amplitude at the target */
        double other_miss[N_STATE], projected_miss[2], *o = pm->projected;
        ends(robust->corner_ad[k], robust->corner_bd[k], s0, target, n, pm->other, other_miss);
        for (int i = 0; i < n; i++)
            for (int r = 0; r < 2; r++)
                o[2 * i + r] = la_dot(robust->corner_rows[k][r], pm->other + (n - 1 - i) * N_STATE, N_STATE);
        for (int r = 0; r < 2; r++) projected_miss[r] = la_dot(robust->corner_rows[k][r], other_miss, N_STATE);
        for (int i = 0; i < n; i++) {
            for (int j = 0; j < n; j++) pm->hessian[i * n + j] += weight * la_dot(o + 2 * i, o + 2 * j, 2);
            pm->f[i] -= weight * la_dot(o + 2 * i, projected_miss, 2);
        }
    }
    constraint_rows(n, interval, pm->first, pm->length, pm->offset, pm->values);
    QpPrepared qp = {n, m, pm->first, pm->length, pm->offset, pm->values, pm->hinv, pm->g, pm->norms, pm->chain_end};
    if (qp_prepare(&qp, pm->hessian, pm->scratch)) return -1;
    for (int k = 0; k < n; k++) {
        double low_v, high_v;
        pm->lower[k] = -u_max, pm->upper[k] = u_max;
        speed_envelope(s0[1], v_max, u_max, interval, k + 1, &low_v, &high_v);
        pm->lower[n + k] = low_v - s0[1], pm->upper[n + k] = high_v - s0[1];
    }
    int n_hint = 0;
    if (pm->has_previous) { /* mpc._resampled(): pick min(old - 1, k old // n) for input k */
        int old = pm->previous_n;
        for (int block = 0; block < 2; block++)
            for (int k = 0; k < n; k++) {
                int pick = k * old / n < old - 1 ? k * old / n : old - 1;
                double code = pm->previous_codes[pick + block * old];
                if (code != 0) pm->hint_rows[n_hint] = k + block * n, pm->hint_sides[n_hint++] = (int)code;
                if (block == 0) pm->guess[k] = pm->previous[pick];
            }
    } else {
        memset(pm->guess, 0, (size_t)n * sizeof *pm->guess);
    }
    feasible_start(pm->guess, n, s0[1], pm->lower, pm->upper, v_max, u_max, interval, pm->start);
    QpSolution solution = {pm->x, pm->active, pm->sides, 0, 0, 0};
    qp_solve(&qp, pm->f, pm->lower, pm->upper, pm->start, pm->hint_rows, pm->hint_sides, n_hint, 20 * n, pm->work,
             pm->iwork, &solution);
    memset(pm->previous_codes, 0, (size_t)m * sizeof *pm->previous_codes);
    for (int i = 0; i < solution.n_active; i++) pm->previous_codes[solution.active[i]] = solution.sides[i];
    memcpy(pm->previous, pm->x, (size_t)n * sizeof *pm->x);
    pm->previous_n = n, pm->has_previous = 1;
    for (int i = 0; i < N_STATE; i++) {
        double reach = 0.0;
        for (int j = 0; j < n; j++) reach += b[(n - 1 - j) * N_STATE + i] * pm->x[j];
        if (!(fabs(reach - miss[i]) <= REACHED)) return 0;
    }
    return 1;
}

/* mpc.plan_move(): the shortest move (u*, s*) from s0 to rest at target within the limits, by bisection on its
   number of intervals; *n_plan = 0 when none is needed or found within max_intervals. With stretch > 1 the move of
   ceil(stretch n) intervals (at most max_intervals) instead, when it reaches the target (the cautious plan). */
static const char *plan_move(const Design *d, const double s0[N_STATE], const double target[N_STATE], double u_max,
                             double v_max, double interval, int max_intervals, double stretch, const Config *robust,
                             double *plan_u, double *plan_s, int *n_plan) {
    *n_plan = 0;
    double far = 0.0;
    for (int i = 0; i < N_STATE; i++) far = py_max(far, fabs(s0[i] - target[i]));
    if (far <= REACHED) return NULL;
    if (max_intervals < 1) return NULL; /* attempt(0) is not ok, and none longer may be tried */
    int at_rest = fabs(s0[1]) <= REACHED;
    double shortest = at_rest ? rigid_move_time(target[0] - s0[0], u_max, v_max) : 0.0;
    int low = at_rest ? (int)(shortest / interval) - 1 : 0; /* too few (rounding aside) */
    PlanMemory pm;
    if (plan_memory(&pm, max_intervals)) return "MemoryError: the plan's QP";
    int high = (int)py_min(py_max(8, low + 1 + (int)(0.15 * low) + 4), max_intervals), ok;
    const char *error = NULL;
#define ATTEMPT_WITH(n, corners, weight) if ((n) < 1) { /* no move of no interval */       \
        ok = 0;                                                                             \
    } else if ((ok = attempt(d, s0, target, u_max, v_max, interval, n, corners, weight, &pm)) < 0) { \
        error = NOT_POSITIVE_DEFINITE;                                                      \
        goto done;                                                                          \
    }
#define ATTEMPT(n) ATTEMPT_WITH(n, NULL, 0.0)
    ATTEMPT(high)
    memcpy(pm.found, pm.x, (size_t)high * sizeof *pm.x);
    while (!ok) {
        if (high >= max_intervals) goto done;
        low = high, high = (int)py_min(2 * high, max_intervals);
        ATTEMPT(high)
        memcpy(pm.found, pm.x, (size_t)high * sizeof *pm.x);
    }
    while (high - low > 1) {
        int mid = (low + high) / 2; /* low >= -1, high >= low + 2: no negative sum to floor */
        ATTEMPT(mid)
        if (ok) {
            high = mid;
            memcpy(pm.found, pm.x, (size_t)mid * sizeof *pm.x);
        } else {
            low = mid;
        }
    }
    if (stretch > 1.0) { /* the cautious plan: the least-effort move of more intervals (no longer bang-bang) */
        int longer = (int)py_min(ceil(high * stretch), max_intervals);
        if (longer > high) { /* robust to the corners with the first weight that reaches the target, else not */
            ok = 0;
            for (int w = 0; robust && !ok && w < N_ROBUST_WEIGHTS; w++) {
                ATTEMPT_WITH(longer, robust, ROBUST_WEIGHTS[w])
            }
            if (!ok) {
                ATTEMPT(longer)
            }
            if (ok) {
                high = longer;
                memcpy(pm.found, pm.x, (size_t)longer * sizeof *pm.x);
            }
        }
    }
#undef ATTEMPT
#undef ATTEMPT_WITH
    *n_plan = high;
    memcpy(plan_u, pm.found, (size_t)high * sizeof *plan_u);
    double s[N_STATE];
    memcpy(s, s0, sizeof s);
    memcpy(plan_s, s, sizeof s);
    for (int k = 0; k < high; k++) {
        double next[N_STATE];
        for (int i = 0; i < N_STATE; i++) next[i] = la_dot(d->ad[i], s, N_STATE) + d->bd[i] * plan_u[k];
        memcpy(s, next, sizeof s);
        memcpy(plan_s + (k + 1) * N_STATE, s, sizeof s);
    }
done:
    free(pm.block);
    return error;
}


/* planner.shortest_steps()'s plan: mpc.plan_move on the discrete model (ad, bd), from the swing start (theta1, dtheta1,
   theta2, dtheta2) at 0 to rest at distance, at most MAX_PLAN intervals; its inputs into plan_u (MAX_PLAN of room), their number into
   *n_plan (0: none needed or found). */
const char *mpc_axis_plan_rest_to_rest(const double ad[N_STATE][N_STATE], const double bd[N_STATE], double distance,
                                       const double start[4], double u_max, double v_max, double interval,
                                       double stretch, double *plan_u, int *n_plan) {
    Design *d = malloc(sizeof *d);
    double *plan_s = malloc((size_t)(MAX_PLAN + 1) * N_STATE * sizeof *plan_s);
    const char *error = "MemoryError: the shortest move's plan";
    *n_plan = 0;
    if (d && plan_s) {
        double s0[N_STATE] = {0.0, 0.0, start[0], start[1], start[2], start[3]}, target[N_STATE] = {distance, 0.0, 0.0, 0.0, 0.0, 0.0};
        memcpy(d->ad, ad, sizeof d->ad);
        memcpy(d->bd, bd, sizeof d->bd);
        error = plan_move(d, s0, target, u_max, v_max, interval, MAX_PLAN, stretch, NULL, plan_u, plan_s, n_plan);
    }
    free(d);
    free(plan_s);
    return error;
}

/* mpc._sample(): what the identification keeps of a measured state. */
static void sample(const double measured[N_STATE], double out[8]) {
    double theta1 = measured[2], theta2 = measured[4], d = theta1 - theta2;
    out[0] = measured[3], out[1] = measured[5], out[2] = COS(d), out[3] = SIN(d);
    out[4] = COS(theta1), out[5] = SIN(theta1), out[6] = COS(theta2), out[7] = SIN(theta2);
}

/* mpc.integrate(): the identification's integrals one communication step further (trapezoidal rule). */
static void integrate(double h, const double in[8], const double before[8], const double now[8], double out[8]) {
    double w1a = before[0], w2a = before[1], cda = before[2], sda = before[3], c1a = before[4], s1a = before[5];
    double c2a = before[6], s2a = before[7];
    double w1b = now[0], w2b = now[1], cdb = now[2], sdb = now[3], c1b = now[4], s1b = now[5], c2b = now[6];
    double s2b = now[7];
    double half = 0.5 * h, cd = 0.5 * (cda + cdb);
    out[0] = in[0] + (w1b - w1a), out[1] = in[1] + (w2b - w2a);
    out[2] = in[2] + (cd * (w1b - w1a) - half * (w1a * w1a * sda + w1b * w1b * sdb));
    out[3] = in[3] + (cd * (w2b - w2a) + half * (w2a * w2a * sda + w2b * w2b * sdb));
    out[4] = in[4] + half * (c1a + c1b), out[5] = in[5] + half * (c2a + c2b);
    out[6] = in[6] + half * (s1a + s1b), out[7] = in[7] + half * (s2a + s2b);
}

/* mpc.precise(): whether each least-squares value's standard error, sqrt(residual / (rows - 3) (N^-1)_ii), is
   within STANDARD_ERROR of itself (packed: the normal equations' Cholesky factor). */
static int precise(const double packed[6], const double values[3], double residual, double rows) {
    double variance = residual / py_max(rows - 3.0, 1.0);
    for (int i = 0; i < 3; i++) {
        double unit[3] = {0.0, 0.0, 0.0}, column[3], scratch[3];
        unit[i] = 1.0;
        qp_cholesky_solve(packed, 3, unit, scratch, column);
        double bound = STANDARD_ERROR * values[i];
        if (variance * column[i] > bound * bound) return 0;
    }
    return 1;
}

static int identifying(const Config *c, const double *s) { return c->samples > 0 && s[H_L1] == 0.0; }

/* mpc.identify(): the normal equations with the interval that ends now (sums), the model they give (*found), and
   whether the data are beyond any crane's equations (*unexplained). */
static const char *identify(const Config *c, const double *s, const double measured[N_STATE], double sums[11],
                            double model[3], int *found, int *unexplained) {
    memcpy(sums, s + H_N11, 11 * sizeof *sums);
    *found = 0, *unexplained = 0;
    if (!identifying(c, s)) return NULL;
    if (s[H_COUNT] > 0) {
        double now[8], in[8];
        sample(measured, now);
        integrate(c->h, s + H_D1, s + H_W1, now, in);
        double d1 = in[0], d2 = in[1], a1 = in[2], a2 = in[3], c1 = in[4], c2 = in[5], s1 = in[6], s2 = in[7];
        double u = s[H_U], g = c->plant.g, y1 = -u * c1 - g * s1, y2 = -u * c2 - g * s2;
        sums[0] += d1 * d1 + a1 * a1;
        sums[1] += a1 * d2;
        sums[2] += d1 * a2;
        sums[3] += d2 * d2;
        sums[5] += a2 * a2;
        sums[6] += d1 * y1 + a1 * y2;
        sums[7] += d2 * y2;
        sums[8] += a2 * y1;
        sums[9] += y1 * y1 + y2 * y2;
        sums[10] += 1.0;
    }
    if (!(sums[10] >= py_min(c->samples, SUSPECT_AFTER))) return NULL; /* the misfit judged from SUSPECT_AFTER */
    double normal[9] = {sums[0], sums[1], sums[2], sums[1], sums[3], sums[4], sums[2], sums[4], sums[5]};
    double factor[9], packed[6], lam[3], scratch[3];
    if (qp_cholesky(normal, 3, factor)) return NULL;
    double pivot = factor[0] * factor[0] / normal[0];
    for (int i = 1; i < 3; i++) pivot = py_min(pivot, factor[4 * i] * factor[4 * i] / normal[4 * i]);
    if (!(pivot >= WELL_POSED)) return NULL;
    packed[0] = factor[0], packed[1] = factor[3], packed[2] = factor[4], packed[3] = factor[6];
    packed[4] = factor[7], packed[5] = factor[8];
    qp_cholesky_solve(packed, 3, sums + 6, scratch, lam);
    double l1 = lam[0], l2 = lam[1], k = lam[2], yy = sums[9];
    if (yy == 0.0) return DIVISION_BY_ZERO;
    double misfit = (yy - (l1 * sums[6] + l2 * sums[7] + k * sums[8])) / yy; /* the residual's share */
    *unexplained = misfit > (c->estimated != 0.0 ? MISFIT : UNEXPLAINED); /* with estimated: no model's data */
    const PlantParameters *p = &c->plant;
    int plausible = p->l1 / PLAUSIBLE <= l1 && l1 <= p->l1 * PLAUSIBLE && p->l2 / PLAUSIBLE <= l2 &&
                    l2 <= p->l2 * PLAUSIBLE;
    if (sums[10] >= c->samples && misfit <= MISFIT && plausible && 0.0 < k && k < l2) {
        double m2 = (p->m1 + p->m2) * k / l2, residual = yy - (l1 * sums[6] + l2 * sums[7] + k * sums[8]);
        if (p->m2 / PLAUSIBLE_PAYLOAD <= m2 && m2 <= p->m2 * PLAUSIBLE_PAYLOAD &&
            precise(packed, lam, residual, 2.0 * sums[10])) {
            model[0] = l1, model[1] = l2, model[2] = m2;
            *found = 1;
        }
    }
    return NULL;
}

/* mpc.deviation(): how far the measured state is from the plan's, (trolley [m], swing [rad]). */
static void deviation(const Design *d, const double measured[N_STATE], const double ref[N_STATE], double *trolley,
                      double *swing) {
    double e[N_STATE];
    for (int i = 0; i < N_STATE; i++) e[i] = measured[i] - ref[i];
    double w = d->omegas[0];
    *trolley = sqrt(e[0] * e[0] + (e[1] / w) * (e[1] / w));
    double s11 = d->shapes[0][0], s21 = d->shapes[0][1], s12 = d->shapes[1][0], s22 = d->shapes[1][1];
    double det = s11 * s22 - s12 * s21, rows[2][2] = {{s22, -s12}, {-s21, s11}};
    *swing = 0.0;
    for (int k = 0; k < 2; k++) { /* rows of the shapes' inverse */
        double a = rows[k][0], b = rows[k][1];
        double eta = (a * e[2] + b * e[4]) / det, rate = (a * e[3] + b * e[5]) / det;
        double largest = py_max(fabs(d->shapes[k][0]), fabs(d->shapes[k][1]));
        *swing += sqrt(eta * eta + (rate / d->omegas[k]) * (rate / d->omegas[k])) * largest;
    }
}

/* The plan stored in a state: its length, its inputs and its states (len: n + 1, or 0 without a plan). */
static int plan_states(const double *s) { return s[H_PLAN_STEPS] > 0 ? (int)s[H_PLAN_STEPS] + 1 : 0; }

/* How many of a state's values are in use: its length as mpc.py's tuple. */
static size_t used(const Config *c, const double *s) {
    int n = (int)s[H_PLAN_STEPS];
    return H_N_HEADER + 3 * (size_t)c->steps + (size_t)n + N_STATE * (size_t)plan_states(s);
}

/* The steps per interval as a whole number (beyond any count a run reaches: as good as infinite). */
static long long whole(double every) { return every < 1e15 ? (long long)every : (long long)1e15; }

/* mpc.force_shift(): the rest the estimated forces f2 (payload), f1 (hook) hold, lqr.force_target() on the configured
   model (eqs (8)-(9) at rest), the trolley's shift for the load at x_d (offset_free 1) or none (2); 0 when
   offset_free is 0 or there is no force. */
static int force_shift(const Config *c, double f2, double f1, double shift[N_STATE]) {
    if (c->offset_free == 0.0 || (f2 == 0.0 && f1 == 0.0)) return 0;
    const PlantParameters *p = &c->plant;
    double theta1 = (f1 + f2) / ((p->m1 + p->m2) * p->g), theta2 = f2 / (p->m2 * p->g);
    double dx = -(p->l1 * theta1 + p->l2 * theta2);
    for (int i = 0; i < N_STATE; i++) shift[i] = 0.0;
    shift[0] = c->offset_free == 1.0 ? dx : 0.0, shift[2] = theta1, shift[4] = theta2;
    return 1;
}

/* lqr.scheduled_gains() over the MPC's own LQR designs (the schedule's lengths, or none) and lqr.control() for the
   target x_d moved by the forces (offset-free): the LQR the MPC hands over to. */
static double lqr_input(const Config *c, const double measured[N_STATE], double l1, double f2, double f1) {
    double gains[N_STATE], error[N_STATE];
    memcpy(gains, c->lqr_gains, sizeof gains);
    if (c->n_designs > 1 && l1 > 0) {
        double low = c->designs[0].l1, high = c->designs[SCHEDULE_POINTS - 1].l1;
        double position = (py_min(py_max(l1, low), high) - low) / (c->designs[1].l1 - low);
        int i = position >= SCHEDULE_POINTS - 2 ? SCHEDULE_POINTS - 2 : (int)position; /* min(int(position), 9) */
        double f = position - i;
        for (int j = 0; j < N_STATE; j++)
            gains[j] = c->lqr_table[i][j] + f * (c->lqr_table[i + 1][j] - c->lqr_table[i][j]);
    }
    for (int i = 0; i < N_STATE; i++) error[i] = measured[i] - 0.0;
    error[0] -= c->x_d;
    double shift[N_STATE];
    if (force_shift(c, f2, f1, shift)) { /* lqr.control()'s order: x, then theta1, theta2 */
        if (c->offset_free == 1.0) error[0] -= shift[0];
        error[2] -= shift[2], error[4] -= shift[4];
    }
    return limited(0.0 - la_dot(gains, error, N_STATE), measured[1], c->u_max, c->v_max, c->h);
}

/* mpc._largest(): a plan's largest swing [rad], the largest of its angles over its n_plan + 1 states (0: none). */
static double largest(const double *states, int n_plan) {
    double out = 0.0;
    for (int k = 0; n_plan > 0 && k <= n_plan; k++)
        out = py_max(out, py_max(fabs(states[k * N_STATE + 2]), fabs(states[k * N_STATE + 4])));
    return out;
}

/* mpc.handover(): the solve that hands over to the LQR: its input, the state kept but marked. */
static const char *handover(const Config *c, const double *state, const double measured[N_STATE], double l1_now,
                            const double forces[2], double replans, double cautious, double *next) {
    memcpy(next, state, used(c, state) * sizeof(double));
    next[H_U] = lqr_input(c, measured, l1_now, forces[0], forces[1]), next[H_ITERATIONS] = 0.0;
    next[H_HANDED] = 1.0, next[H_REPLANS] = replans, next[H_CAUTIOUS] = cautious;
    return NULL;
}

/* mpc.solve(): one solve, from the state and the measured state, into `next` (the new state with the count as it
   was); *warns when its message is due. */
static const char *solve(Config *c, const double *state, const double measured[N_STATE], double l1_now,
                         const double forces[2], double *next, int *warns) {
    int n = c->steps;
    double count = state[H_COUNT];
    long long at = (long long)count / whole(c->every); /* this interval's number (count // every) */
    double sums[11], model[3], known[3] = {state[H_L1], state[H_L2], state[H_M2]};
    int found_model, unexplained;
    const char *error = identify(c, state, measured, sums, model, &found_model, &unexplained);
    if (error) return error;
    Design *d;
    if (known[0] > 0.0) {
        if ((error = identified_design(c, known, &d))) return error;
    } else {
        d = nearest_design(c, l1_now);
    }
    if (found_model) { /* identified: a new design and plan when a swing mode's frequency moved */
        double omegas[2] = {d->omegas[0], d->omegas[1]};
        Design *found;
        if ((error = identified_design(c, model, &found))) return error;
        memcpy(known, model, sizeof known);
        if (py_max(fabs(found->omegas[0] - omegas[0]) / omegas[0], fabs(found->omegas[1] - omegas[1]) / omegas[1]) <=
            TOLERANCE)
            found_model = 0;
        d = found;
    }
    const double target[N_STATE] = {c->x_d, 0.0, 0.0, 0.0, 0.0, 0.0};
    size_t plan_at = H_N_HEADER + 3 * (size_t)n;
    int n_plan = (int)state[H_PLAN_STEPS], n_states = plan_states(state);
    const double *plan_u = state + plan_at, *plan_s = plan_u + n_plan;
    long long plan_start = (long long)state[H_PLAN_START], plan_after = (long long)state[H_PLAN_AFTER];
    long long step = at - plan_start;
    const double *ref_s = count != 0 && step < n_states ? plan_s + step * N_STATE : target;
    double trolley, swing;
    deviation(d, measured, ref_s, &trolley, &swing);
    int rescheduled = c->n_designs > 1 && d->l1 != state[H_PLAN_L1]; /* the schedule's design changed */
    int moved = trolley > c->replan_x || swing > c->replan_angle || rescheduled;
    int replan = count == 0 || found_model || (moved && at >= plan_after);
    /* the safety envelope: data the crane's equations do not explain make every plan from now on cautious, the first
       at once (it is no plan for a deviation) */
    double cautious = state[H_CAUTIOUS];
    int warned_now = unexplained && !cautious;
    if (warned_now) cautious = 1.0, replan = 1;
    double *new_plan_u = next + plan_at, to_trolley, to_rest;
    deviation(d, measured, target, &to_trolley, &to_rest);
    int over = step >= n_plan;
    /* too far from rest for the linear model's plan; with none held after the first solve (the large swing's
       phase), planned again only below PLAN_BELOW; a plan held mid-move is not dropped for it (mpc.solve) */
    double hit = state[H_HIT]; /* after a hard hit's large swing, plans dropped past LARGEST_SWING as before */
    int large = !(count != 0 && n_plan > 0 && !over && hit == 0.0) &&
                to_rest > (count != 0 && n_plan == 0 ? PLAN_BELOW : LARGEST_SWING);
    /* the safety envelope: the LQR takes over, for good, when the plan is over and the identification's data are
       beyond the crane's equations or the plans for a deviation have run out (mid-move the LQR's kick would swing
       more than the plan's end), the swing grows past the plan's largest by SWING_MARGIN, or the crane is at rest on
       the target */
    double replans = state[H_REPLANS], bound = state[H_BOUND], first = state[H_FIRST];
    /* a plan for a deviation needs a plan to deviate from: the first after the large swing's phase is none */
    if (replan && count != 0 && !found_model && !warned_now && !large && n_plan > 0 &&
        (trolley > c->replan_x || swing > c->replan_angle))
        replans += 1.0;
    int swung = n_plan > 0 && to_rest > bound + SWING_MARGIN; /* past the plan's largest */
    int at_rest = over && to_trolley <= c->replan_x && to_rest <= c->replan_angle;
    int spent = replans > MOST_REPLANS;
    if (spent && !over && !swung) /* the plans for a deviation run out mid-move: the held plan tracked to its end */
        replan = found_model, replans = MOST_REPLANS + 1.0;
    else if (count != 0 && ((unexplained && over) || spent || swung || at_rest))
        return handover(c, state, measured, l1_now, forces, replans, cautious, next);
    if (replan && large) { /* none made: the tracking QP takes the swing down alone, a plan tried next interval */
        replan = n_plan > 0 || found_model; /* the last solve's warm start holds unless a plan or model changed */
        n_plan = 0, n_states = 0, plan_u = plan_s = new_plan_u;
        plan_start = at, step = 0, plan_after = at;
        bound = to_rest, hit = 1.0;
    } else if (replan) {
        double shrink = 1.0 - c->margin, far = 0.0, stretch = cautious != 0.0 ? CAUTIOUS_STRETCH : 1.0;
        const Config *corners = cautious != 0.0 ? c : NULL;
        int most = (int)(LONGEST_PLAN / c->interval);
        if (cautious != 0.0 && (error = robust_ends(c, known))) return error;
        error = plan_move(d, measured, target, c->u_max * shrink, c->v_max * shrink, c->interval, most, stretch,
                          corners, new_plan_u, new_plan_u + MAX_PLAN, &n_plan);
        if (error) return error;
        if (count == 0) { /* the first plan's largest swing: what the move asked for swings on the configured crane */
            first = largest(new_plan_u + MAX_PLAN, n_plan);
        } else if (first > 0.0 && largest(new_plan_u + MAX_PLAN, n_plan) > first + PEAK_ALLOWANCE) {
            int fits = 0; /* the first longer move within the first plan's swing, else the shortest move again */
            for (int j = 0; j < N_PEAK_STRETCHES && !fits; j++) {
                error = plan_move(d, measured, target, c->u_max * shrink, c->v_max * shrink, c->interval, most,
                                  stretch * PEAK_STRETCHES[j], corners, new_plan_u, new_plan_u + MAX_PLAN, &n_plan);
                if (error) return error;
                fits = n_plan > 0 && largest(new_plan_u + MAX_PLAN, n_plan) <= first + PEAK_ALLOWANCE;
            }
            if (!fits && (error = plan_move(d, measured, target, c->u_max * shrink, c->v_max * shrink, c->interval,
                                            most, stretch, corners, new_plan_u, new_plan_u + MAX_PLAN, &n_plan)))
                return error;
        }
        memmove(new_plan_u + n_plan, new_plan_u + MAX_PLAN, (n_plan ? n_plan + 1 : 0) * N_STATE * sizeof(double));
        plan_u = new_plan_u, plan_s = new_plan_u + n_plan, n_states = n_plan ? n_plan + 1 : 0;
        plan_start = at, step = 0;
        for (int i = 0; i < N_STATE; i++) far = py_max(far, fabs(measured[i] - target[i]));
        if (n_plan) plan_after = at + (long long)rint(REPLAN_GAP / c->interval); /* the next waits REPLAN_GAP */
        else if (far > REACHED) plan_after = at + (long long)rint(RETRY_GAP / c->interval); /* the QP alone */
        bound = py_max(to_rest, largest(plan_s, n_plan));
    }
    double *ref_u = c->scratch, *f = ref_u + n, *lower = f + n, *upper = lower + 2 * n, *guess = upper + 2 * n;
    double *absolute = guess + n, *start = absolute + n, *lower_u = start + n, *upper_u = lower_u + n;
    int *hint_rows = c->hint_rows, *hint_sides = c->hint_sides;
    for (int k = 0; k < n; k++) ref_u[k] = step + k < n_plan ? plan_u[step + k] : 0.0;
    ref_s = step < n_states ? plan_s + step * N_STATE : target;
    double e0[N_STATE];
    for (int i = 0; i < N_STATE; i++) e0[i] = measured[i] - ref_s[i];
    double shift[N_STATE]; /* offset-free: the error from the forces' rest (the disturbance in the prediction) */
    if (force_shift(c, forces[0], forces[1], shift))
        for (int i = 0; i < N_STATE; i++) e0[i] = e0[i] - shift[i];
    if (large && n_plan == 0) e0[0] = 0.0; /* the trolley left free while the swing is taken down */
    for (int k = 0; k < n; k++) f[k] = la_dot(d->gain[k], e0, N_STATE);
    double v0 = measured[1], planned = v0;
    for (int k = 0; k < n; k++) lower[k] = -c->u_max - ref_u[k], upper[k] = c->u_max - ref_u[k];
    for (int k = 0; k < n; k++) { /* the speed rows bound what du adds to the plan's speed change from v0 */
        double low_v, high_v;
        planned += c->interval * ref_u[k];
        speed_envelope(v0, c->v_max, c->u_max, c->interval, k + 1, &low_v, &high_v);
        lower[n + k] = low_v - planned, upper[n + k] = high_v - planned;
    }
    const double *previous = state + H_N_HEADER, *codes = previous + n;
    int shifted = count != 0 && !replan, n_hint = 0;
    for (int k = 0; k < n; k++) {
        guess[k] = shifted ? ref_u[k] + (k + 1 < n ? previous[k + 1] : 0.0) : ref_u[k];
        lower_u[k] = -c->u_max, upper_u[k] = c->u_max;
    }
    feasible_start(guess, n, v0, lower_u, upper_u, c->v_max, c->u_max, c->interval, absolute);
    for (int k = 0; k < n; k++) start[k] = absolute[k] - ref_u[k];
    if (shifted) /* each row one interval later: row k + 1 of the last solve is row k now */
        for (int row = 0; row < 2 * n; row++)
            if (codes[row] != 0 && row % n) hint_rows[n_hint] = row - 1, hint_sides[n_hint++] = (int)codes[row];
    /* the solution into the new state; the tracking QP's work after the solve's scratch */
    double *x = next + H_N_HEADER, *new_codes = x + n;
    int *active = c->active, *sides = c->sides;
    QpSolution solution = {x, active, sides, 0, 0, 0};
    QpPrepared qp = prepared(c, d);
    qp_solve(&qp, f, lower, upper, start, hint_rows, hint_sides, n_hint, c->max_iterations, c->work, c->iwork,
             &solution);
    for (int row = 0; row < 2 * n; row++) new_codes[row] = 0.0;
    for (int i = 0; i < solution.n_active; i++) new_codes[active[i]] = (double)sides[i];
    double warned = state[H_WARNED];
    *warns = 0;
    if (!solution.optimal && !warned) warned = 1.0, *warns = 1;
    if (!replan) memcpy(next + plan_at, state + plan_at, (n_plan + N_STATE * n_states) * sizeof(double));
    double header[H_N_HEADER] = {count, ref_u[0] + x[0], (double)solution.iterations, warned, (double)n_plan,
                               (double)plan_start, (double)plan_after, replan ? d->l1 : state[H_PLAN_L1],
                               known[0], known[1], known[2]};
    sample(measured, header + H_W1);
    memcpy(header + H_N11, sums, sizeof sums);
    header[H_HANDED] = 0.0, header[H_REPLANS] = replans, header[H_BOUND] = bound, header[H_CAUTIOUS] = cautious;
    header[H_HIT] = hit, header[H_FIRST] = first;
    memcpy(next, header, sizeof header);
    return NULL;
}

/* mpc.initial_state(): zeros. */
void mpc_axis_initial_state(State *s) { memset(s, 0, sizeof *s); }

/* mpc._solved(): the solve at this state and these inputs, shared by the outputs and the step (Config's memo). */
static const char *solved(const Config *config, const State *s, const double inputs[], const double **next,
                          int *warns) {
    Config *c = (Config *)config; /* the memo, as mpc.Config.memo: not the configuration */
    size_t n = used(c, s->v);
    if (!(c->memo_valid && memcmp(c->memo_inputs, inputs, sizeof c->memo_inputs) == 0 &&
          used(c, c->memo_state.v) == n && memcmp(c->memo_state.v, s->v, n * sizeof(double)) == 0)) {
        c->memo_valid = 0;
        const char *error = solve(c, s->v, inputs, inputs[N_STATE], inputs + N_STATE + 1, c->memo_next.v,
                                  &c->memo_warns);
        if (error) return error;
        memcpy(c->memo_inputs, inputs, sizeof c->memo_inputs);
        memcpy(c->memo_state.v, s->v, n * sizeof(double));
        c->memo_valid = 1;
    }
    *next = c->memo_next.v, *warns = c->memo_warns;
    return NULL;
}

static int due(const Config *c, const double *s) { return (long long)s[H_COUNT] % whole(c->every) == 0; }

/* mpc._output(): the held input, the QP's iterations and the plan's end; at a solve, the solve's. */
ModelStatus mpc_axis_outputs(const Config *c, const State *s, const double inputs[N_INPUTS], double out[3],
                             const Reporter *r) {
    const double *state = s->v;
    if (state[H_HANDED] != 0.0) { /* the LQR's, every step */
        out[0] = lqr_input(c, inputs, inputs[N_STATE], inputs[N_STATE + 1], inputs[N_STATE + 2]), out[1] = 0.0;
        out[2] = state[H_PLAN_STEPS] != 0 ? (state[H_PLAN_START] + state[H_PLAN_STEPS]) * c->interval : 0.0;
        return MODEL_OK;
    }
    if (due(c, state)) {
        int warns;
        const char *error = solved(c, s, inputs, &state, &warns);
        if (error) return report(r, MODEL_ERROR, "%s", error);
    }
    out[0] = state[H_U], out[1] = state[H_ITERATIONS];
    out[2] = state[H_PLAN_STEPS] != 0 ? (state[H_PLAN_START] + state[H_PLAN_STEPS]) * c->interval : 0.0;
    return MODEL_OK;
}

/* mpc.update(): count the step and add it to the identification's integrals; at a solve keep the solve's state
   (its input held until the next, its solution, the plan, the identification's sums); warn once at the cap. */
ModelStatus mpc_axis_update(const Config *c, State *s, const double inputs[N_INPUTS], const char *prefix,
                            const Reporter *r) {
    double *state = s->v, count = state[H_COUNT];
    if (!due(c, state) || state[H_HANDED] != 0.0) {
        if (state[H_HANDED] == 0.0 && identifying(c, state)) {
            double now[8], integrals[8];
            sample(inputs, now);
            integrate(c->h, state + H_D1, state + H_W1, now, integrals);
            memcpy(state + H_W1, now, sizeof now);
            memcpy(state + H_D1, integrals, sizeof integrals);
        }
        state[H_COUNT] = count + 1.0;
        return MODEL_OK;
    }
    const double *next;
    int warns;
    const char *error = solved(c, s, inputs, &next, &warns);
    if (error) return report(r, MODEL_ERROR, "%s", error);
    memcpy(state, next, used(c, next) * sizeof(double));
    state[H_COUNT] = count + 1.0;
    if (warns)
        report(r, MODEL_WARNING, "%sMpcController: the QP stopped at its iteration cap (%d) at t = %s s; u is its best "
               "feasible input (warned once)", prefix, c->max_iterations, R((double)(long long)count * c->h));
    return MODEL_OK;
}

