/*
 * The CranePlant3D component in C: the native twin of crane_fmu/model/plant3d.py (its configure() after its
 * declared rules, initial_state(), output() and update()), registered as a component a host can also integrate
 * (Model Exchange: plant3d_continuous.c). Its variables, value references, start values and rules come from
 * CranePlant3D_variables.h, which `crane-fmu build` generates from the same table (plant3d.VARIABLES, RULES).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "CranePlant3D_variables.h"
#include "plant3d_continuous.h"
#include "plant_limits.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

enum { ACCEL_X = N_CONTINUOUS3, ACCEL_Y, N_STATE }; /* the trolley's mean accelerations over the last sub-step */
#define MAX_SUBSTEPS 10000000 /* per communication step: a host must never hang in doStep */
#define N_MESSAGES 4          /* hoist messages kept per step */
#define AT_REST 0.01          /* m/s: plant_limits.AT_REST (slower at a hoist limit: a move's end) */

typedef struct {
    ContinuousPlant3 c; /* every parameter of the model; the RK4's sub-step besides */
    double max_substep;
} Config;

typedef struct {
    double s[N_STATE]; /* the continuous state is its first N_CONTINUOUS3 values */
    PlantMode3 mode;   /* Model Exchange: the limits that hold */
} State;

#define V(name) (values[VR_##name])
#define R(value) py_repr(value, (char[REPR_SIZE]){0})

static const unsigned INITIAL[] = {VR_x0,        VR_dx0,        VR_y0,        VR_dy0,
                                   VR_theta1x_0, VR_dtheta1x_0, VR_theta1y_0, VR_dtheta1y_0,
                                   VR_theta2x_0, VR_dtheta2x_0, VR_theta2y_0, VR_dtheta2y_0};

/* plant3d.configure(), after its RULES (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    /* 1e60 and beyond: no limit */
    *c = (Config){{{V(m1), V(m2), V(l1), V(l2), V(g)},
                   V(c1),
                   V(c2),
                   {unlimited(V(ux_max)), unlimited(V(vx_max)), V(tau_x), unlimited(V(x_min)), unlimited(V(x_max))},
                   {unlimited(V(uy_max)), unlimited(V(vy_max)), V(tau_y), unlimited(V(y_min)), unlimited(V(y_max))},
                   V(l1_min),
                   unlimited(V(l1_max)),
                   unlimited(V(dl1_max))},
                  V(max_substep)};
    return MODEL_OK;
}

static void initial_state(const double values[], const Config *c, State *state) {
    for (unsigned i = 0; i < 12; i++) state->s[i] = values[INITIAL[i]];
    state->s[L13] = c->c.p.l1;
    for (unsigned i = DL13; i < N_STATE; i++) state->s[i] = 0.0;
    state->mode = (PlantMode3){0, 0, 0, 0};
}

/* Every output in table order: the swing state, spatial_outputs(), then l1_now, dl1_now, ddx, ddy. */
static ModelStatus outputs(const double values[], const Config *c, const State *state, double out[],
                           const Reporter *r) {
    for (int i = 0; i < L13; i++) out[i] = state->s[i];
    spatial_outputs(state->s, &c->c.p, out + L13);
    out[21] = state->s[L13], out[22] = state->s[DL13], out[23] = state->s[ACCEL_X], out[24] = state->s[ACCEL_Y];
    return MODEL_OK;
}

static ModelStatus update(const double values[], const Config *config, State *state, double time, double step,
                          const Reporter *r) {
    const ContinuousPlant3 *c = &config->c;
    const double *in = &values[VR_ux];
    if (c->p.m2 == 0 && (in[IN_F2X] != 0 || in[IN_F2Y] != 0))
        return report(r, MODEL_DISCARD, "F2 = (%s, %s) N acts on a load of mass m2 = 0: the step is discarded",
                      R(in[IN_F2X]), R(in[IN_F2Y]));
    /* plant_equations.substeps(): the 1e-9 slack keeps h = 1 ms with max_substep = 1 ms at one sub-step */
    double need = step / config->max_substep - 1e-9;
    if (!(need <= MAX_SUBSTEPS))
        return report(r, MODEL_ERROR,
                      "communication step %s s needs more than %d RK4 sub-steps of at most max_substep = %s s",
                      R(step), MAX_SUBSTEPS, R(config->max_substep));
    long n = (long)need; /* math.ceil, at least one */
    if ((double)n < need) n++;
    if (n < 1) n = 1;
    double dt = step / (double)n;
    Load3 load = {0.0, in[IN_F1X], in[IN_F1Y], in[IN_F2X], in[IN_F2Y], c->c1, c->c2};
    const Axis *axes[2] = {&c->x, &c->y};
    static const int speeds[2] = {DX3, DY3}, places[2] = {X3, Y3};
    static const char *names[2] = {"x", "y"};
    double demand[2], lag[2] = {0.0, 0.0}, mean[2] = {0.0, 0.0}, drives[2], accels[2] = {0.0, 0.0};
    for (int i = 0; i < 2; i++) {
        demand[i] = clamp(in[i == 0 ? IN_UX : IN_UY], -axes[i]->u_max, axes[i]->u_max);
        /* the drive's first-order lag over a sub-step, exactly (plant_limits.drive_factors) */
        if (axes[i]->tau != 0) lag[i] = EXP(-dt / axes[i]->tau), mean[i] = axes[i]->tau / dt * (1.0 - lag[i]);
        drives[i] = state->s[DRIVE_X3 + i];
    }
    double swing[N_SPATIAL];
    memcpy(swing, state->s, sizeof swing);
    double reached[N_MESSAGES][3]; /* (l1, t, speed) where the cable reached a hoist limit */
    int n_reached = 0;
    for (long k = 0; k < n; k++) {
        for (int i = 0; i < 2; i++) {
            double accel = axes[i]->tau > 0 ? demand[i] + (drives[i] - demand[i]) * mean[i] : demand[i];
            drives[i] = demand[i] + (drives[i] - demand[i]) * lag[i];
            accels[i] = within_speed(accel, swing[speeds[i]], axes[i]->v_max, dt);
        }
        double cable_rate = swing[DL13];
        load.hoist = within_speed(in[IN_HOIST], cable_rate, c->dl1_max, dt);
        spatial_rk4_step(swing, accels[0], accels[1], dt, &c->p, &load);
        double t = time + (double)(k + 1) * dt;
        for (int i = 0; i < N_SPATIAL; i++) /* Python stops here on sin(inf); C computes on in NaN */
            if (!isfinite(swing[i]))
                return report(r, MODEL_DISCARD,
                              "plant state became non-finite in the step from t=%s s (ux=%s, uy=%s m/s2); the step "
                              "is discarded", R(time), R(in[IN_UX]), R(in[IN_UY]));
        for (int i = 0; i < 2; i++) {
            double at = swing[places[i]];
            if (!(axes[i]->low <= at && at <= axes[i]->high)) {
                int high = at > axes[i]->high;
                return report(r, MODEL_DISCARD,
                              "the trolley would pass the rail end %s_%s = %s m (%s = %s m) at t = %s s: the step "
                              "from t = %s s is discarded", names[i], high ? "max" : "min",
                              R(high ? axes[i]->high : axes[i]->low), names[i], R(at), R(t), R(time));
            }
        }
        if (!(c->l1_min <= swing[L13] && swing[L13] <= c->l1_max)) { /* the cable is held at the limit it reached */
            double held = swing[L13] > c->l1_max ? c->l1_max : c->l1_min;
            double speed = (swing[DL13] < 0 ? -swing[DL13] : swing[DL13]) + 0.0; /* Python's abs() */
            if (cable_rate != 0.0 && n_reached < N_MESSAGES)
                reached[n_reached][0] = held, reached[n_reached][1] = t, reached[n_reached++][2] = speed;
            swing[L13] = held, swing[DL13] = 0.0;
        }
    }
    memcpy(state->s, swing, sizeof swing);
    state->s[DRIVE_X3] = drives[0], state->s[DRIVE_Y3] = drives[1];
    state->s[ACCEL_X] = accels[0], state->s[ACCEL_Y] = accels[1];
    for (int i = 0; i < n_reached; i++) /* plant_limits.reached_limit(): at rest the end of a move, else a warning */
        if (reached[i][2] < AT_REST)
            report(r, MODEL_OK, "hoist: l1 reached %s m at t = %s s and is held there", R(reached[i][0]),
                   R(reached[i][1]));
        else
            report(r, MODEL_WARNING, "hoist: l1 hit the limit %s m at %s m/s at t = %s s and is held there",
                   R(reached[i][0]), R(reached[i][2]), R(reached[i][1]));
    return MODEL_OK;
}

/* ---- Model Exchange: plant3d_continuous.c on the state's first N_CONTINUOUS3 values ---- */

static double *continuous_states(State *state) { return state->s; }

static ModelStatus derivatives(const double values[], const Config *c, const State *state, const double *ds,
                               const double *din, double f[], double *df, const Reporter *r) {
    int why = plant3_derivatives(&c->c, state->s, &values[VR_ux], state->mode, ds, din, f, df);
    if (why == PLANT3_F2_WITHOUT_MASS)
        return report(r, MODEL_DISCARD, "F2 = (%s, %s) N acts on a load of mass m2 = 0", R(values[VR_F2x]),
                      R(values[VR_F2y]));
    if (why == PLANT3_NOT_FINITE) return report(r, MODEL_DISCARD, "the plant's derivatives are not finite at this state");
    return MODEL_OK;
}

static void continuous_outputs(const double values[], const Config *c, const State *state, int model_exchange,
                               const double *ds, const double *din, double out[], double *dout) {
    plant3_outputs(&c->c, state->s, &values[VR_ux], state->mode, ds, din, out, dout);
    if (!model_exchange) { /* co-simulation's ddx, ddy: the accelerations over the last step, kept (outputs() above) */
        out[23] = state->s[ACCEL_X], out[24] = state->s[ACCEL_Y];
        if (dout) dout[23] = 0.0, dout[24] = 0.0;
    }
}

static void indicators(const double values[], const Config *c, const State *state, double z[]) {
    plant3_event_indicators(&c->c, state->s, &values[VR_ux], state->mode, z);
}

/* plant3d_continuous.event_update(): a rail end ends the simulation; a cable that reached a hoist limit is logged
   as the co-simulation logs it (plant_limits.reached_limit). */
static ModelStatus event_update(const double values[], const Config *c, State *state, double time, int *terminate,
                                const Reporter *r) {
    PlantEvent3 event;
    plant3_event_update(&c->c, state->s, &values[VR_ux], &state->mode, &event);
    if (event.rail_end) {
        *terminate = 1;
        int high = event.rail_end > 0, y = event.rail_axis;
        const Axis *axis = y ? &c->c.y : &c->c.x;
        report(r, MODEL_WARNING, "the trolley reached the rail end %s_%s = %s m (%s = %s m) at t = %s s", y ? "y" : "x",
               high ? "max" : "min", R(high ? axis->high : axis->low), y ? "y" : "x", R(state->s[y ? Y3 : X3]),
               R(time));
    } else if (event.cable_reached) {
        double speed = (event.cable_rate < 0 ? -event.cable_rate : event.cable_rate) + 0.0;
        if (speed < AT_REST)
            report(r, MODEL_OK, "hoist: l1 reached %s m at t = %s s and is held there", R(event.cable_at), R(time));
        else
            report(r, MODEL_WARNING, "hoist: l1 hit the limit %s m at %s m/s at t = %s s and is held there",
                   R(event.cable_at), R(speed), R(time));
    }
    return MODEL_OK;
}

CONTINUOUS_COMPONENT;
