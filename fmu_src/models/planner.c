/*
 * The TrajectoryPlanner component in C: the native twin of crane_fmu/model/planner.py (its variables, configure(),
 * the shapers, modes() on plant_equations.linearisation(), the bang-coast-bang base, the shortest move of
 * shortest_steps() by mpc_axis.c's plan and reference()), registered
 * as a component (component.h). Its variables and parameter rules come from TrajectoryPlanner_variables.h,
 * generated from planner.VARIABLES. Its state is the time of its outputs: 0 at first, then the end of the last
 * step (time + step, the component's update()), and with plan_from measured the swing read at the first step and the
 * plan from it (planner.initial_state(), update(), plan()).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "TrajectoryPlanner_variables.h"
#include "linalg.h"
#include "lqr_design.h"
#include "mpc_axis.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

#define EI_TOLERANCE 0.05
#define PI 3.141592653589793 /* math.pi */
#define MAX_IMPULSES 9               /* a shaper of at most 3 impulses per mode, convolved */
#define MAX_SHAPED (4 * MAX_IMPULSES) /* four jumps of the base acceleration per impulse */
#define PLAN_INTERVAL 0.05           /* planner.PLAN_INTERVAL */

typedef struct {
    double t, value; /* an impulse (time, amplitude) or a jump of the acceleration (time, jump) */
} Pair;

/* planner.Config */
typedef struct {
    double x0, distance, t0, end, omegas[2], shapes[2][2], gains[2];
    int measured;       /* plan_from measured: the plan from the inputs read at the first step (planner.Measured) */
    int free;           /* a shortest move from a swing: */
    double free_[2][2]; /* its modal swing (eta, deta) at t0, planner.Config.free */
    Pair steps[MAX_PLAN + 1], impulses[MAX_IMPULSES]; /* the shortest move's: a jump per interval */
    int n_steps, n_impulses;
} Config;

/* planner.initial_state(): the time of the outputs; with plan_from measured whether the swing has been read at the
   first step, and the plan from it (Python keeps the swing read, its plan looked up by it) */
typedef struct {
    double time;
    int planned;
    Config plan;
} State;

#define V(name) (values[VR_##name])

/* Python's sorted() of (time, value) tuples: by time, then value (insertion sort: at most 36 pairs). */
static void sort_pairs(Pair p[], int n) {
    for (int i = 1; i < n; i++) {
        Pair key = p[i];
        int j = i - 1;
        for (; j >= 0 && (p[j].t > key.t || (p[j].t == key.t && p[j].value > key.value)); j--) p[j + 1] = p[j];
        p[j + 1] = key;
    }
}

/* planner.shaper(): one mode's impulses; returns their number. */
static int shaper(const char *kind, double period, Pair out[3]) {
    if (strcmp(kind, "zv") == 0) {
        out[0] = (Pair){0.0, 0.5}, out[1] = (Pair){period / 2, 0.5};
        return 2;
    }
    if (strcmp(kind, "zvd") == 0) {
        out[0] = (Pair){0.0, 0.25}, out[1] = (Pair){period / 2, 0.5}, out[2] = (Pair){period, 0.25};
        return 3;
    }
    if (strcmp(kind, "ei") == 0) {
        double v = EI_TOLERANCE;
        out[0] = (Pair){0.0, (1 + v) / 4}, out[1] = (Pair){period / 2, (1 - v) / 2};
        out[2] = (Pair){period, (1 + v) / 4};
        return 3;
    }
    out[0] = (Pair){0.0, 1.0};
    return 1;
}

/* planner.modes() on plant_equations.linearisation(): the swing modes of q'' = -W q - w u. */
static ModelStatus modes(double m1, double m2, double l1, double l2, double g, Config *c, const Reporter *r) {
    double m12 = m1 + m2;
    double na = m12 * l1, nb = m2 * l2, nc = l1, nd = l2; /* N of linearisation() */
    double ndet = na * nd - nb * nc;
    if (ndet == 0) return ZERO_DIVISION(r);
    double inv[2][2] = {{nd / ndet, -nb / ndet}, {-nc / ndet, na / ndet}};
    double a = inv[0][0] * m12 * g, b = inv[0][1] * g, cc = inv[1][0] * m12 * g, d = inv[1][1] * g; /* W */
    double w[2] = {inv[0][0] * m12 + inv[0][1], inv[1][0] * m12 + inv[1][1]};
    double half_trace = (a + d) / 2, det = a * d - b * cc;
    double discriminant = half_trace * half_trace - det;
    if (discriminant < 0) return DOMAIN_ERROR(r);
    double root = sqrt(discriminant);
    double lambdas[2] = {half_trace - root, half_trace + root};
    for (int k = 0; k < 2; k++) { /* (W - lam I) v = 0 */
        if (b != 0) c->shapes[k][0] = b, c->shapes[k][1] = lambdas[k] - a;
        else c->shapes[k][0] = lambdas[k] - d, c->shapes[k][1] = cc;
    }
    double v11 = c->shapes[0][0], v21 = c->shapes[0][1], v12 = c->shapes[1][0], v22 = c->shapes[1][1];
    double det_v = v11 * v22 - v12 * v21;
    if (det_v == 0) return ZERO_DIVISION(r); /* the modes coincide (m2 = 0, l1 = l2) */
    c->gains[0] = (v22 * w[0] - v12 * w[1]) / det_v, c->gains[1] = (-v21 * w[0] + v11 * w[1]) / det_v;
    if (lambdas[0] < 0 || lambdas[1] < 0) return DOMAIN_ERROR(r);
    c->omegas[0] = sqrt(lambdas[0]), c->omegas[1] = sqrt(lambdas[1]);
    if (c->omegas[0] == 0 || c->omegas[1] == 0) return ZERO_DIVISION(r); /* the shapers' periods 2 pi / omega */
    return MODEL_OK;
}

/* planner._base(): the accelerating and cruising times of the bang-coast-bang move. */
static void base(double distance, double accel, double speed, double *t_a, double *t_c) {
    *t_a = speed / accel;
    if (distance < speed * *t_a) { /* no cruise: a triangle */
        *t_a = sqrt(distance / accel), *t_c = 0.0;
        return;
    }
    *t_c = distance / speed - *t_a;
}

/* planner._accel_steps(): the shaped acceleration as sorted jumps; returns their number. */
static int accel_steps(const Config *c, double accel, double t_a, double t_c, Pair steps[MAX_SHAPED]) {
    int n = 0;
    for (int i = 0; i < c->n_impulses; i++) {
        double t = c->impulses[i].t, amp = c->impulses[i].value;
        steps[n++] = (Pair){t, amp * accel}, steps[n++] = (Pair){t + t_a, -amp * accel};
        steps[n++] = (Pair){t + t_a + t_c, -amp * accel}, steps[n++] = (Pair){t + 2 * t_a + t_c, amp * accel};
    }
    sort_pairs(steps, n);
    return n;
}

/* planner._peak(): the largest |shaped acceleration|. */
static double peak(const Pair steps[], int n) {
    double level = 0.0, top = 0.0;
    for (int i = 0; i < n; i++) level += steps[i].value, top = py_max(top, fabs(level));
    return top;
}

/* planner.shortest_steps(), in configure(): the jumps of the shortest move's held inputs (mpc.plan_move on the
   zero-order hold of lqr.continuous_model over PLAN_INTERVAL), from t0, and its end. */
static ModelStatus shortest_steps(const double values[], const double start[4], double distance, double u_max,
                                  double v_max, Config *c, const Reporter *r) {
    PlantParameters p = {V(m1), V(m2), V(l1), V(l2), V(g)};
    Matrix a, b, ad, bd;
    const char *error = continuous_model(&p, &a, &b);
    if (error || (error = la_zoh(a, b, PLAN_INTERVAL, &ad, &bd))) return report(r, MODEL_ERROR, "%s", error);
    double ad_[N_STATE][N_STATE], bd_[N_STATE], inputs[MAX_PLAN];
    for (int i = 0; i < N_STATE; i++) {
        for (int j = 0; j < N_STATE; j++) ad_[i][j] = ad.v[i][j];
        bd_[i] = bd.v[i][0];
    }
    int n = 0;
    error = mpc_axis_plan_rest_to_rest((const double (*)[N_STATE])ad_, bd_, distance, start, u_max, v_max,
                                       PLAN_INTERVAL, V(stretch), inputs, &n); /* the cast: C99 takes no implicit const */
    if (error) return report(r, MODEL_ERROR, "%s", error);
    double far = fabs(distance);
    for (int i = 0; i < 4; i++) far = py_max(far, fabs(start[i]));
    if (n == 0 && far > REACHED) {
        char text[REPR_SIZE];
        return report(r, MODEL_ERROR, "shaper shortest: no move of x_d - x0 = %s m to rest within %g s",
                      py_repr(distance, text), MAX_PLAN * PLAN_INTERVAL);
    }
    double level = 0.0;
    for (int k = 0; k <= n; k++) {
        double u = k < n ? inputs[k] : 0.0;
        if (u != level) c->steps[c->n_steps++] = (Pair){V(t0) + k * PLAN_INTERVAL, u - level}, level = u;
    }
    c->end = c->n_steps ? V(t0) + n * PLAN_INTERVAL : V(t0);
    if (start[0] != 0 || start[1] != 0 || start[2] != 0 || start[3] != 0) { /* q = S eta: eta = S^-1 q */
        double s11 = c->shapes[0][0], s21 = c->shapes[0][1], s12 = c->shapes[1][0], s22 = c->shapes[1][1];
        double det = s11 * s22 - s12 * s21;
        c->free = 1;
        for (int i = 0; i < 2; i++) { /* the angles (theta1_0, theta2_0), then their rates */
            double q1 = start[i], q2 = start[2 + i];
            c->free_[i][0] = (s22 * q1 - s12 * q2) / det, c->free_[i][1] = (s11 * q2 - s21 * q1) / det;
        }
    }
    return MODEL_OK;
}

/* planner.configure(), after its RULES (the generated parameter_rules()): its plan. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    const char *kind = strings[STRING_shaper];
    double u_max = unlimited(V(u_max)), v_max = unlimited(V(v_max));
    memset(c, 0, sizeof *c);
    ModelStatus status = modes(V(m1), V(m2), V(l1), V(l2), V(g), c, r);
    if (status != MODEL_OK) return status;
    Pair a[3], b[3];
    int na = shaper(kind, 2 * PI / c->omegas[0], a), nb = shaper(kind, 2 * PI / c->omegas[1], b);
    for (int i = 0; i < na; i++) /* planner.convolve() */
        for (int j = 0; j < nb; j++) c->impulses[c->n_impulses++] = (Pair){a[i].t + b[j].t, a[i].value * b[j].value};
    sort_pairs(c->impulses, c->n_impulses);
    double distance = V(x_d) - V(x0);
    double sign = distance >= 0 ? 1.0 : -1.0, distance_abs = fabs(distance);
    double t_a = 0.0, t_c = 0.0;
    Pair steps[MAX_SHAPED];
    c->x0 = V(x0), c->distance = distance, c->t0 = V(t0);
    c->measured = strcmp(strings[STRING_plan_from], "measured") == 0;
    if (strcmp(kind, "shortest") == 0) {
        double start[4] = {V(theta1_0), V(dtheta1_0), V(theta2_0), V(dtheta2_0)};
        return shortest_steps(values, start, distance, u_max, v_max, c, r);
    }
    if (distance_abs > 0) {
        /* the largest base acceleration whose shaped acceleration stays within u_max (bisection) */
        double smallest = c->impulses[0].value;
        for (int i = 1; i < c->n_impulses; i++) smallest = py_min(smallest, c->impulses[i].value);
        double low = u_max, high = u_max / smallest;
        for (int i = 0; i < 60; i++) {
            double mid = 0.5 * (low + high);
            base(distance_abs, mid, v_max, &t_a, &t_c);
            if (peak(steps, accel_steps(c, mid, t_a, t_c, steps)) <= u_max * (1 + 1e-12)) low = mid;
            else high = mid;
        }
        base(distance_abs, low, v_max, &t_a, &t_c);
        c->n_steps = accel_steps(c, low, t_a, t_c, c->steps);
        for (int i = 0; i < c->n_steps; i++) c->steps[i].t = V(t0) + c->steps[i].t, c->steps[i].value *= sign;
    }
    c->end = c->n_steps ? V(t0) + c->impulses[c->n_impulses - 1].t + 2 * t_a + t_c : V(t0);
    return MODEL_OK;
}

/* planner.reference(): x_ref, dx_ref, ddx_ref and the induced swing at time t, the same arithmetic in its order. */
static void reference(const Config *c, double t, double out[N_OUTPUTS]) {
    double x = c->x0, v = 0.0, a = 0.0, eta[2] = {0.0, 0.0}, deta[2] = {0.0, 0.0};
    double rounding = 1e-9 * (t > 1.0 ? t : t < -1.0 ? -t : 1.0); /* TIME_ROUNDING * max(1.0, abs(t)) */
    int moving = t < c->end - rounding; /* a summed time just short of the end is at it, at rest */
    if (moving && c->free) { /* the swing the move starts from, left to itself: eta_k'' = -w_k^2 eta_k */
        double since = t - c->t0;
        for (int k = 0; k < 2; k++) {
            double w = c->omegas[k], e0 = c->free_[0][k], d0 = c->free_[1][k];
            eta[k] = e0 * COS(w * since) + d0 * SIN(w * since) / w;
            deta[k] = -e0 * w * SIN(w * since) + d0 * COS(w * since);
        }
    }
    for (int i = 0; i < c->n_steps; i++) {
        double dt = t - c->steps[i].t, jump = c->steps[i].value;
        if (dt <= rounding) break;
        a += jump;
        v += jump * dt;
        x += 0.5 * jump * dt * dt;
        if (moving)
            for (int k = 0; k < 2; k++) { /* eta_k'' = -w_k^2 eta_k - g_k u, answering a step */
                double w = c->omegas[k];
                eta[k] -= c->gains[k] * jump * (1.0 - COS(w * dt)) / (w * w);
                deta[k] -= c->gains[k] * jump * SIN(w * dt) / w;
            }
    }
    if (!moving && c->n_steps) x = c->x0 + c->distance, v = 0.0, a = 0.0; /* rest at the target */
    double s11 = c->shapes[0][0], s21 = c->shapes[0][1], s12 = c->shapes[1][0], s22 = c->shapes[1][1];
    double result[N_OUTPUTS] = {x, v, a, s11 * eta[0] + s12 * eta[1], s11 * deta[0] + s12 * deta[1],
                                s21 * eta[0] + s22 * eta[1], s21 * deta[0] + s22 * deta[1]};
    memcpy(out, result, sizeof result);
}

/* planner.Measured.plan(): the plan of the parameters with the swing start as theta1_0 ... (plan_from measured). */
static ModelStatus measured_plan(const double values[], const Config *c, const double start[4], Config *plan,
                                 const Reporter *r) {
    static const char *const names[4] = {"theta1_now", "dtheta1_now", "theta2_now", "dtheta2_now"};
    for (int i = 0; i < 4; i++)
        if (!isfinite(start[i])) {
            char text[REPR_SIZE];
            return report(r, MODEL_ERROR, "%s must be finite (the measured swing the plan starts from), got %s",
                          names[i], py_repr(start[i], text));
        }
    *plan = *c; /* the parameters' modes and impulses; the shortest move anew */
    plan->n_steps = 0, plan->free = 0, plan->measured = 0;
    memset(plan->free_, 0, sizeof plan->free_);
    return shortest_steps(values, start, c->distance, unlimited(V(u_max)), unlimited(V(v_max)), plan, r);
}

static void initial_state(const double values[], const Config *c, State *s) {
    s->time = 0.0, s->planned = 0;
}

/* planner.update(): the time after the step; with plan_from measured the swing read at the first step, planned. */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    if (c->measured && !s->planned) {
        double start[4] = {V(theta1_now), V(dtheta1_now), V(theta2_now), V(dtheta2_now)};
        ModelStatus status = measured_plan(values, c, start, &s->plan, r);
        if (status != MODEL_OK) return status;
        s->planned = 1;
    }
    s->time = time + step;
    return MODEL_OK;
}

/* planner._output() on planner.plan(): the parameters' plan, the one from the swing read at the first step, or before
   it from the inputs now. */
static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    if (!c->measured) {
        reference(c, s->time, out);
        return MODEL_OK;
    }
    if (s->planned) {
        reference(&s->plan, s->time, out);
        return MODEL_OK;
    }
    Config *plan = malloc(sizeof *plan);
    if (!plan) return report(r, MODEL_ERROR, "MemoryError: the planner's plan");
    double start[4] = {V(theta1_now), V(dtheta1_now), V(theta2_now), V(dtheta2_now)};
    ModelStatus status = measured_plan(values, c, start, plan, r);
    if (status == MODEL_OK) reference(plan, s->time, out);
    free(plan);
    return status;
}

STATEFUL_COMPONENT;
