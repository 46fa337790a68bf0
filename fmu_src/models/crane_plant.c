/*
 * The CranePlant component in C: the native twin of crane_fmu/model/plant.py (its configure(), initial_state(),
 * output() and update()), registered as a component (component.h) that a host can also integrate (Model
 * Exchange: plant_continuous.c's derivatives, event indicators and event updates). Its variables, value
 * references, start values and parameter rules come from CranePlant_variables.h, which `crane-fmu build`
 * generates from the same table and rules (plant.VARIABLES, plant.RULES) as the Python FMU is built from.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "CranePlant_variables.h"
#include "plant_continuous.h"
#include "plant_equations.h"
#include "plant_limits.h"
#include "plant_math.h"
#include "py_repr.h"
#include "rules.h"

enum { DRIVE = N_SWING, ACCEL, N_STATE }; /* after the swing and hoist state: the drive's and the trolley's acceleration */
#define MAX_SUBSTEPS 10000000            /* per communication step: a host must never hang in doStep */
#define N_MESSAGES 4                     /* hoist messages kept per step */
#define AT_REST 0.01                     /* m/s: plant_limits.AT_REST (slower at a hoist limit: a move's end) */

typedef struct {
    PlantParameters p;
    Load damping; /* c1, c2 (hoist and forces are the inputs) */
    double max_substep, u_max, v_max, tau, x_min, x_max, l1_min, l1_max, dl1_max;
    ContinuousPlant continuous; /* the same parameters, for Model Exchange */
} Config;

typedef struct {
    double s[N_STATE]; /* the continuous state is its first N_CONTINUOUS values */
    PlantMode mode;    /* Model Exchange: the limits that hold */
} State;

#define V(name) (values[VR_##name])
#define R(value) py_repr(value, (char[REPR_SIZE]){0})

/* plant.configure(), after its RULES (the generated parameter_rules()). */
static ModelStatus configure(const double values[], const StringValue strings[], Config *c, const Reporter *r) {
    *c = (Config){{V(m1), V(m2), V(l1), V(l2), V(g)}, {0.0, 0.0, 0.0, V(c1), V(c2)}, V(max_substep),
                  unlimited(V(u_max)), unlimited(V(v_max)), V(tau), unlimited(V(x_min)), unlimited(V(x_max)),
                  V(l1_min), unlimited(V(l1_max)), unlimited(V(dl1_max)), /* 1e60 and beyond: no limit */
                  .continuous = {.c1 = 0.0}};                                /* below */
    c->continuous = (ContinuousPlant){c->p, V(c1), V(c2), c->u_max, c->v_max, c->tau, c->x_min, c->x_max, c->l1_min,
                                      c->l1_max, c->dl1_max};
    return MODEL_OK;
}

static void initial_state(const double values[], const Config *c, State *state) {
    double s[N_STATE] = {V(x0), V(dx0), V(theta1_0), V(dtheta1_0), V(theta2_0), V(dtheta2_0), c->p.l1, 0.0, 0.0, 0.0};
    memcpy(state->s, s, sizeof s);
    state->mode = (PlantMode){0, 0, 0};
}

/* Every output in table order: plant_outputs(), then l1_now, dl1_now, ddx. */
static ModelStatus outputs(const double values[], const Config *c, const State *state, double out[],
                           const Reporter *r) {
    plant_outputs(state->s, &c->p, out);
    out[11] = state->s[L1], out[12] = state->s[DL1], out[13] = state->s[ACCEL];
    return MODEL_OK;
}

static ModelStatus update(const double values[], const Config *c, State *state, double time, double step,
                          const Reporter *r) {
    const double *in = &values[VR_u];
    double u = in[0], hoist = in[1], f1 = in[2], f2 = in[3];
    if (c->p.m2 == 0 && f2 != 0)
        return report(r, MODEL_DISCARD, "F2 = %s N acts on a payload of mass m2 = 0: the step is discarded", R(f2));
    /* plant_equations.substeps(): the 1e-9 slack keeps h = 1 ms with max_substep = 1 ms at one sub-step */
    double need = step / c->max_substep - 1e-9;
    if (!(need <= MAX_SUBSTEPS))
        return report(r, MODEL_ERROR,
                      "communication step %s s needs more than %d RK4 sub-steps of at most max_substep = %s s",
                      R(step), MAX_SUBSTEPS, R(c->max_substep));
    long n = (long)need; /* math.ceil, at least one */
    if ((double)n < need) n++;
    if (n < 1) n = 1;
    double dt = step / (double)n;
    Load load = {0.0, f1, f2, c->damping.c1, c->damping.c2};
    int forces = f1 != 0 || f2 != 0 || load.c1 != 0 || load.c2 != 0;
    double demand = clamp(u, -c->u_max, c->u_max);
    /* the drive's first-order lag over a sub-step, exactly: a(dt) = d + (a(0) - d) lag, its mean d + (a(0) - d) mean */
    double lag = 0.0, mean = 0.0;
    if (c->tau != 0) lag = EXP(-dt / c->tau), mean = c->tau / dt * (1.0 - lag);
    double swing[N_SWING], drive = state->s[DRIVE], accel = demand;
    memcpy(swing, state->s, sizeof swing);
    double reached[N_MESSAGES][3]; /* (l1, t, speed) where the cable reached a hoist limit */
    int n_reached = 0;
    for (long k = 0; k < n; k++) {
        accel = c->tau > 0 ? demand + (drive - demand) * mean : demand;
        drive = demand + (drive - demand) * lag;
        double cable_rate = swing[DL1];
        accel = within_speed(accel, swing[DX], c->v_max, dt);
        load.hoist = within_speed(hoist, cable_rate, c->dl1_max, dt);
        if (load.hoist == 0.0 && cable_rate == 0.0 && !forces) paper_step(swing, accel, dt, &c->p);
        else rk4_step(swing, accel, dt, &c->p, &load);
        double t = time + (double)(k + 1) * dt;
        for (int i = 0; i < N_SWING; i++) /* Python stops here on sin(inf); C computes on in NaN */
            if (!isfinite(swing[i]))
                return report(r, MODEL_DISCARD,
                              "plant state became non-finite in the step from t=%s s (u=%s m/s2); the step is discarded",
                              R(time), R(u));
        if (!(c->x_min <= swing[X] && swing[X] <= c->x_max)) {
            int high = swing[X] > c->x_max;
            return report(r, MODEL_DISCARD,
                          "the trolley would pass the rail end %s = %s m (x = %s m) at t = %s s: the step from t = %s s "
                          "is discarded", high ? "x_max" : "x_min", R(high ? c->x_max : c->x_min), R(swing[X]), R(t),
                          R(time));
        }
        if (!(c->l1_min <= swing[L1] && swing[L1] <= c->l1_max)) { /* the cable is held at the limit it reached */
            double held = swing[L1] > c->l1_max ? c->l1_max : c->l1_min;
            double speed = (swing[DL1] < 0 ? -swing[DL1] : swing[DL1]) + 0.0; /* Python's abs() */
            if (cable_rate != 0.0 && n_reached < N_MESSAGES)
                reached[n_reached][0] = held, reached[n_reached][1] = t, reached[n_reached++][2] = speed;
            swing[L1] = held, swing[DL1] = 0.0;
        }
    }
    memcpy(state->s, swing, sizeof swing);
    state->s[DRIVE] = drive, state->s[ACCEL] = accel;
    for (int i = 0; i < n_reached; i++) /* plant_limits.reached_limit(): at rest the end of a move, else a warning */
        if (reached[i][2] < AT_REST)
            report(r, MODEL_OK, "hoist: l1 reached %s m at t = %s s and is held there", R(reached[i][0]),
                   R(reached[i][1]));
        else
            report(r, MODEL_WARNING, "hoist: l1 hit the limit %s m at %s m/s at t = %s s and is held there",
                   R(reached[i][0]), R(reached[i][2]), R(reached[i][1]));
    return MODEL_OK;
}

/* ---- Model Exchange: plant_continuous.c on the state's first N_CONTINUOUS values ---- */

static double *continuous_states(State *state) { return state->s; }

static ModelStatus derivatives(const double values[], const Config *c, const State *state, const double *ds,
                               const double *din, double f[], double *df, const Reporter *r) {
    int why = plant_derivatives(&c->continuous, state->s, &values[VR_u], state->mode, ds, din, f, df);
    if (why == PLANT_F2_WITHOUT_MASS)
        return report(r, MODEL_DISCARD, "F2 = %s N acts on a payload of mass m2 = 0", R(values[VR_F2]));
    if (why == PLANT_NOT_FINITE) return report(r, MODEL_DISCARD, "the plant's derivatives are not finite at this state");
    return MODEL_OK;
}

static void continuous_outputs(const double values[], const Config *c, const State *state, int model_exchange,
                               const double *ds, const double *din, double out[], double *dout) {
    plant_continuous_outputs(&c->continuous, state->s, &values[VR_u], state->mode, ds, din, out, dout);
    if (!model_exchange) { /* co-simulation's ddx: the acceleration over the last step, kept (outputs() above) */
        out[13] = state->s[ACCEL];
        if (dout) dout[13] = 0.0;
    }
}

static void indicators(const double values[], const Config *c, const State *state, double z[]) {
    plant_event_indicators(&c->continuous, state->s, &values[VR_u], state->mode, z);
}

/* plant_continuous.event_update(): a rail end ends the simulation; a cable that reached a hoist limit is logged
   as the co-simulation logs it (plant_limits.reached_limit). */
static ModelStatus event_update(const double values[], const Config *c, State *state, double time, int *terminate,
                                const Reporter *r) {
    PlantEvent event;
    plant_event_update(&c->continuous, state->s, &values[VR_u], &state->mode, &event);
    if (event.rail_end) {
        *terminate = 1;
        int high = event.rail_end > 0;
        report(r, MODEL_WARNING, "the trolley reached the rail end %s = %s m (x = %s m) at t = %s s",
               high ? "x_max" : "x_min", R(high ? c->x_max : c->x_min), R(state->s[X]), R(time));
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
