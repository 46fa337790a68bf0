/*
 * The MpcController3D component in C: the native twin of crane_fmu/model/mpc3d.py, registered as a component
 * (component.h). Its variables, value references, start values and parameter rules come from
 * MpcController3D_variables.h, generated from mpc3d.VARIABLES. Each axis runs the planar MPC of mpc_axis.c (the
 * MpcController's, mpc.c) on its own states, with its drive's limits as the constraints of its QPs: linearised at
 * rest the spatial crane is the planar crane per axis (plant3d.linearised()).
 *
 * A path (corridor > 0): path.plan() with the planner's unshaped move (planner.configure() and reference() with
 * shaper "none": one impulse, the bang-coast-bang base at the shrunk limits) gives each axis its move and the
 * later leg's start t0, found by bisection as path.py does; before t0 an axis' MPC holds its start position (the
 * same configuration with x_d the start: mpc3d.configure()'s `before`), and at t0 it starts afresh. Each axis
 * takes its estimated forces (F2x_hat, F1x_hat; F2y_hat, F1y_hat) and offset_free, as the planar MPC's.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "MpcController3D_variables.h"
#include "mpc_axis.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

enum { N_AXES = 2, N_POINTS = 3 }; /* mpc3d.AXES: x, y; a path's start, waypoint and end */
#define RESOLUTION 1e-3            /* path.RESOLUTION */
#define SAMPLE 1e-2                /* path.SAMPLE */
#define TIME_ROUNDING 1e-9         /* planner.TIME_ROUNDING */

/* mpc3d.Config: each axis' MPC, the target after its move's start t0 and the position it holds before. */
typedef struct {
    MpcConfig mpc[N_AXES];
    double after[N_AXES], before[N_AXES], t0[N_AXES];
} Config;

/* mpc3d's state: its time, then each axis' planar MPC state. */
typedef struct {
    double time;
    MpcState axes[N_AXES];
} State;

#define V(name) (values[VR_##name])

/* Each axis' states in the planar order (mpc3d.axis_states()). */
static const unsigned MEASURED[N_AXES][N_STATE] = {
    {VR_x, VR_dx, VR_theta1x, VR_dtheta1x, VR_theta2x, VR_dtheta2x},
    {VR_y, VR_dy, VR_theta1y, VR_dtheta1y, VR_theta2y, VR_dtheta2y}};
/* Each axis' estimated forces (mpc3d.axis_forces()): on the load, then on the hook. */
static const unsigned FORCES[N_AXES][2] = {{VR_F2x_hat, VR_F1x_hat}, {VR_F2y_hat, VR_F1y_hat}};
static const char *const PREFIX[N_AXES] = {"x axis: ", "y axis: "};

/* planner.configure() with shaper "none" (one impulse (0, 1): the bisection's acceleration is u_max) and the
   position of planner.reference(): the unshaped move from x0 to x_d starting at t0. */
typedef struct {
    double x0, distance, end, steps[4][2];
    int n_steps;
} Move;

static Move unshaped(double x0, double x_d, double t0, double u_max, double v_max) {
    Move m = {x0, x_d - x0, t0, {{0}}, 0};
    double sign = m.distance >= 0 ? 1.0 : -1.0, distance = fabs(m.distance), t_a = 0.0, t_c = 0.0;
    if (distance > 0) {
        t_a = v_max / u_max; /* planner._base() */
        if (distance < v_max * t_a) t_a = sqrt(distance / u_max), t_c = 0.0;
        else t_c = distance / v_max - t_a;
        double t = 0.0, steps[4][2] = {{t, u_max}, {t + t_a, -u_max}, {t + t_a + t_c, -u_max},
                                       {t + 2 * t_a + t_c, u_max}}; /* planner._accel_steps(): sorted already */
        for (int i = 0; i < 4; i++) m.steps[i][0] = t0 + steps[i][0], m.steps[i][1] = sign * steps[i][1];
        m.n_steps = 4;
        m.end = t0 + 0.0 + 2 * t_a + t_c;
    }
    return m;
}

static double position(const Move *m, double t) {
    double x = m->x0, rounding = TIME_ROUNDING * py_max(1.0, fabs(t));
    for (int i = 0; i < m->n_steps; i++) {
        double dt = t - m->steps[i][0];
        if (dt <= rounding) break;
        x += 0.5 * m->steps[i][1] * dt * dt;
    }
    if (!(t < m->end) && m->n_steps) x = m->x0 + m->distance; /* rest at the target */
    return x;
}

/* path.distance_to_path(). */
static double distance_to_path(const double point[N_AXES], const double points[N_POINTS][N_AXES]) {
    double best = INFINITY;
    for (int i = 0; i + 1 < N_POINTS; i++) {
        double ax = points[i][0], ay = points[i][1], dx = points[i + 1][0] - ax, dy = points[i + 1][1] - ay;
        double length2 = dx * dx + dy * dy;
        double f = length2 == 0 ? 0.0 : py_min(1.0, py_max(0.0, ((point[0] - ax) * dx + (point[1] - ay) * dy) / length2));
        best = py_min(best, hypot(point[0] - ax - f * dx, point[1] - ay - f * dy));
    }
    return best;
}

/* path.plan()'s within(t0): the moves planned so far (has[k]) and this leg's at t0 keep the reference within
   margin of the path's centre line from `start` to the last move's end. */
static int within(const double points[N_POINTS][N_AXES], int leg, const int moving[N_AXES], const Move planned[],
                  const int has[], double start, double t0, double margin, double u_max, double v_max) {
    Move trial[N_AXES];
    int in[N_AXES];
    double last = -INFINITY;
    for (int k = 0; k < N_AXES; k++) {
        in[k] = has[k] || moving[k];
        if (moving[k]) trial[k] = unshaped(points[leg][k], points[leg + 1][k], t0, u_max, v_max);
        else if (has[k]) trial[k] = planned[k];
        if (in[k]) last = py_max(last, trial[k].end);
    }
    if (last == -INFINITY) last = start; /* nothing moved yet: the reference at the start */
    for (double t = start; t <= last + SAMPLE; t += SAMPLE) {
        double where[N_AXES];
        for (int k = 0; k < N_AXES; k++) where[k] = in[k] ? position(&trial[k], t) : points[0][k];
        if (distance_to_path(where, points) > margin + 1e-12) return 0;
    }
    return 1;
}

/* Python's round(x, 6): the correctly rounded decimal (printf's), read back. */
static double round6(double x) {
    char text[512];
    snprintf(text, sizeof text, "%.6f", x);
    return strtod(text, NULL);
}

/* path.plan() for the path start, waypoint, end: each axis' move (x0, x_d, t0); an error names an axis that moves
   in two legs. */
static ModelStatus plan(const double points[N_POINTS][N_AXES], double margin, double u_max, double v_max,
                        double x0[N_AXES], double x_d[N_AXES], double t0[N_AXES], const Reporter *r) {
    Move planned[N_AXES];
    int has[N_AXES] = {0};
    double start = 0.0, end = 0.0;
    for (int k = 0; k < N_AXES; k++) x0[k] = x_d[k] = points[0][k], t0[k] = 0.0;
    for (int leg = 0; leg + 1 < N_POINTS; leg++) {
        int moving[N_AXES];
        for (int k = 0; k < N_AXES; k++) moving[k] = points[leg][k] != points[leg + 1][k];
        for (int k = 0; k < N_AXES; k++)
            if (moving[k] && has[k])
                return report(r, MODEL_ERROR, "waypoints: the %s axis moves in two legs (leg %d); a path moves each "
                              "axis once", k ? "y" : "x", leg + 1);
        double t = end;
        if (margin > 0 && leg > 0 && within(points, leg, moving, planned, has, start, start, margin, u_max, v_max)) {
            t = start;
        } else if (margin > 0 && leg > 0) {
            double low = start, high = end; /* low: leaves the corridor; high: the last leg's end, within */
            while (high - low > RESOLUTION) {
                double mid = 0.5 * (low + high);
                if (within(points, leg, moving, planned, has, start, mid, margin, u_max, v_max)) high = mid;
                else low = mid;
            }
            t = ceil(round6(high / RESOLUTION)) * RESOLUTION;
        }
        double new_end = end;
        for (int k = 0; k < N_AXES; k++)
            if (moving[k]) {
                x0[k] = points[leg][k], x_d[k] = points[leg + 1][k], t0[k] = t;
                planned[k] = unshaped(points[leg][k], points[leg + 1][k], t, u_max, v_max), has[k] = 1;
                new_end = py_max(new_end, planned[k].end);
            }
        start = t, end = new_end;
    }
    return MODEL_OK;
}

/* mpc3d.configure(), after its RULES (the generated parameter_rules()): each axis' moves and planar MPC. */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    double x0[N_AXES] = {V(x0), V(y0)}, x_d[N_AXES] = {V(x_d), V(y_d)}, t0[N_AXES] = {0.0, 0.0};
    if (V(corridor) > 0) {
        double shrink = 1.0 - V(margin);
        const double points[N_POINTS][N_AXES] = {{V(x0), V(y0)}, {V(x_via), V(y_via)}, {V(x_d), V(y_d)}};
        ModelStatus status = plan(points, V(corridor) / 2, unlimited(V(u_max) * shrink), unlimited(V(v_max) * shrink),
                                  x0, x_d, t0, r);
        if (status != MODEL_OK) return status;
    }
    MpcSettings s = {V(m1), V(m2), V(l1), V(l2), V(g), {0}, V(r), 0.0, V(u_max), V(v_max), V(margin), V(h),
                     V(interval), V(horizon), V(max_iterations), V(replan_x), V(replan_angle), 0.0, 0.0,
                     V(identify), V(offset_free), V(estimated)};
    for (int i = 0; i < N_STATE; i++) s.q[i] = values[VR_q_x + i];
    for (int k = 0; k < N_AXES; k++) {
        s.x_d = x_d[k];
        ModelStatus status = mpc_axis_configure(&s, &c->mpc[k], r);
        if (status != MODEL_OK) return status;
        c->after[k] = x_d[k], c->before[k] = t0[k] <= 0 ? x_d[k] : x0[k], c->t0[k] = t0[k];
    }
    return MODEL_OK;
}

/* mpc3d._started(): a time within the planner's rounding margin short of the axis' move's start t0 is at it. */
static int started(const Config *config, int k, double time) {
    return time >= config->t0[k] - TIME_ROUNDING * py_max(1.0, fabs(time));
}

/* mpc3d._config(): the axis' MPC for its move after t0, for holding its start before (only x_d differs: the
   target the plans, the tracking and the LQR it hands over to are for); a change forgets the last solve. */
static const MpcConfig *axis_config(const Config *config, int k, double time) {
    MpcConfig *c = (MpcConfig *)&config->mpc[k]; /* the target and the memo: as mpc3d.Config's two configs */
    double x_d = started(config, k, time) ? config->after[k] : config->before[k];
    if (c->x_d != x_d) c->x_d = x_d, c->memo_valid = 0;
    return c;
}

/* mpc3d._axis_inputs(): the axis' states, then l1_now (not measured: 0) and the axis' estimated forces. */
static void axis_inputs(const double values[], int k, double out[N_INPUTS]) {
    for (int i = 0; i < N_STATE; i++) out[i] = values[MEASURED[k][i]];
    out[N_STATE] = 0.0, out[N_STATE + 1] = values[FORCES[k][0]], out[N_STATE + 2] = values[FORCES[k][1]];
}

static void initial_state(const double values[], const Config *c, State *s) {
    s->time = 0.0;
    for (int k = 0; k < N_AXES; k++) mpc_axis_initial_state(&s->axes[k]);
}

/* mpc3d._output(): each axis' planar MPC's u. */
static ModelStatus outputs(const double values[], const Config *c, const State *s, double out[], const Reporter *r) {
    for (int k = 0; k < N_AXES; k++) {
        double inputs[N_INPUTS], axis_out[3];
        axis_inputs(values, k, inputs);
        ModelStatus status = mpc_axis_outputs(axis_config(c, k, s->time), &s->axes[k], inputs, axis_out, r);
        if (status != MODEL_OK) return status;
        out[k] = axis_out[0];
    }
    return MODEL_OK;
}

/* mpc3d.update(): each axis' planar MPC step; an axis whose move starts within the step starts afresh. */
static ModelStatus update(const double values[], const Config *c, State *s, double time, double step,
                          const Reporter *r) {
    for (int k = 0; k < N_AXES; k++) {
        double inputs[N_INPUTS];
        axis_inputs(values, k, inputs);
        ModelStatus status = mpc_axis_update(axis_config(c, k, s->time), &s->axes[k], inputs, PREFIX[k], r);
        if (status != MODEL_OK) return status;
        if (!started(c, k, s->time) && started(c, k, time + step)) mpc_axis_initial_state(&s->axes[k]);
    }
    s->time = time + step;
    return MODEL_OK;
}

STATEFUL_COMPONENT;
