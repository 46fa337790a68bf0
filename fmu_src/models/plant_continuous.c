/*
 * The CranePlant for Model Exchange: derivatives and their exact directional derivatives, event indicators and
 * event updates, the C of crane_fmu/model/plant_continuous.py (the specification), operation for operation.
 */
#include "plant_continuous.h"

#include <math.h>
#include <stddef.h>

#include "plant_limits.h"

/* The demand within u_max, and its derivative by u (1 within the limit, 0 beyond it). */
static double demand_of(const ContinuousPlant *c, double u, double *gain) {
    *gain = 0.0;
    if (u > c->u_max) return c->u_max;
    if (u < -c->u_max) return -c->u_max;
    *gain = 1.0;
    return u;
}

/* The drive's output (the trolley's acceleration before the speed limit) and its rate, with their derivatives. */
static void trolley(const ContinuousPlant *c, const double s[], const double in[], const double *ds,
                    const double *din, double out[4]) {
    double gain, demand = demand_of(c, in[0], &gain);
    double t_demand = gain * (din ? din[0] : 0.0);
    if (c->tau > 0) { /* first-order lag: drive' = (demand - drive) / tau */
        double drive = s[DRIVE_STATE], t_drive = ds ? ds[DRIVE_STATE] : 0.0;
        out[0] = drive, out[1] = t_drive, out[2] = (demand - drive) / c->tau, out[3] = (t_demand - t_drive) / c->tau;
    } else {
        out[0] = demand, out[1] = t_demand, out[2] = 0.0, out[3] = 0.0;
    }
}

int plant_derivatives(const ContinuousPlant *c, const double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                      PlantMode mode, const double *ds, const double *din, double f[N_CONTINUOUS], double *df) {
    static const double none[N_CONTINUOUS] = {0};
    double f1 = in[2], f2 = in[3];
    if (c->p.m2 == 0 && f2 != 0) return PLANT_F2_WITHOUT_MASS;
    const double *sd = ds ? ds : none, *sin_ = din ? din : none;
    double tr[4];
    trolley(c, s, in, sd, sin_, tr);
    double accel = tr[0], t_accel = tr[1];
    if (mode.speed) accel = 0.0, t_accel = 0.0;
    double rate = 0.0, t_rate = 0.0, lift = 0.0, t_lift = 0.0;
    if (!mode.cable) {
        rate = s[DL1], t_rate = sd[DL1];
        if (!mode.hoist) lift = in[1], t_lift = sin_[1];
    }
    Load load = {lift, f1, f2, c->c1, c->c2};
    double seed[10] = {sd[THETA1], sd[DTHETA1], sd[THETA2], sd[DTHETA2], t_accel, sd[L1], t_rate, t_lift, sin_[2],
                       sin_[3]};
    double dd[2], tdd[2];
    accelerations_tangent(s[THETA1], s[DTHETA1], s[THETA2], s[DTHETA2], accel, &c->p, s[L1], rate, &load, seed, dd,
                          tdd);
    double values[N_CONTINUOUS] = {s[DX], accel, s[DTHETA1], dd[0], s[DTHETA2], dd[1], rate, lift, tr[2]};
    for (int i = 0; i < N_CONTINUOUS; i++) {
        if (!isfinite(values[i])) return PLANT_NOT_FINITE;
        f[i] = values[i];
    }
    if (df) {
        double t[N_CONTINUOUS] = {sd[DX], t_accel, sd[DTHETA1], tdd[0], sd[DTHETA2], tdd[1], t_rate, t_lift, tr[3]};
        for (int i = 0; i < N_CONTINUOUS; i++) df[i] = t[i];
    }
    return PLANT_OK;
}

void plant_continuous_outputs(const ContinuousPlant *c, const double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                              PlantMode mode, const double *ds, const double *din, double out[N_PLANT_OUTPUTS],
                              double *dout) {
    static const double none[N_CONTINUOUS] = {0};
    double tr[4];
    trolley(c, s, in, ds ? ds : none, din ? din : none, tr);
    plant_outputs(s, &c->p, out);
    out[11] = s[L1], out[12] = s[DL1], out[13] = mode.speed ? 0.0 : tr[0];
    if (dout) {
        outputs_tangent(s, &c->p, ds, dout);
        dout[11] = ds[L1], dout[12] = ds[DL1], dout[13] = mode.speed ? 0.0 : tr[1];
    }
}

void plant_event_indicators(const ContinuousPlant *c, const double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                            PlantMode mode, double z[N_INDICATORS]) {
    double tr[4];
    trolley(c, s, in, NULL, NULL, tr);
    pair(s[X], c->x_min, c->x_max, 0, 0.0, z);
    pair(s[DX], -c->v_max, c->v_max, mode.speed, tr[0], z + 2);
    pair(s[L1], c->l1_min, c->l1_max, mode.cable, in[1], z + 4);
    pair(s[DL1], -c->dl1_max, c->dl1_max, mode.hoist, in[1], z + 6);
}

void plant_event_update(const ContinuousPlant *c, double s[N_CONTINUOUS], const double in[N_PLANT_INPUTS],
                        PlantMode *mode, PlantEvent *event) {
    double tr[4];
    trolley(c, s, in, NULL, NULL, tr);
    double push = tr[0], lift = in[1];
    double outward = s[DX] != 0 ? s[DX] : (mode->speed ? 0.0 : push);
    *event = (PlantEvent){0, 0, 0.0, 0.0};
    if (s[X] > c->x_max || (s[X] == c->x_max && outward > 0)) {
        event->rail_end = 1;
        return;
    }
    if (s[X] < c->x_min || (s[X] == c->x_min && outward < 0)) {
        event->rail_end = -1;
        return;
    }
    hold(&s[DX], push, push, &mode->speed, -c->v_max, c->v_max);
    double dl1 = s[DL1];
    int reached = hold(&s[L1], dl1, lift, &mode->cable, c->l1_min, c->l1_max);
    if (mode->cable || reached) {
        if (reached && dl1 != 0.0) event->cable_reached = 1, event->cable_at = s[L1], event->cable_rate = dl1;
        s[DL1] = 0.0, mode->hoist = 0;
    } else {
        hold(&s[DL1], lift, lift, &mode->hoist, -c->dl1_max, c->dl1_max);
    }
}
