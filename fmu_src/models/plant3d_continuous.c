/*
 * The CranePlant3D for Model Exchange: derivatives and their exact directional derivatives, event indicators and
 * event updates, the C of crane_fmu/model/plant3d_continuous.py (the specification), operation for operation.
 */
#include "plant3d_continuous.h"

#include <math.h>
#include <stddef.h>

#include "plant_limits.h"

/* One axis' drive: its output, its rate, and their derivatives (plant3d_continuous._drive). */
static void drive(const Axis *a, double u, double d, double t_u, double t_d, double out[4]) {
    double demand = u, t_demand = t_u;
    if (u > a->u_max) demand = a->u_max, t_demand = 0.0;
    else if (u < -a->u_max) demand = -a->u_max, t_demand = 0.0;
    if (a->tau > 0) { /* first-order lag: drive' = (demand - drive) / tau */
        out[0] = d, out[1] = t_d, out[2] = (demand - d) / a->tau, out[3] = (t_demand - t_d) / a->tau;
    } else {
        out[0] = demand, out[1] = t_demand, out[2] = 0.0, out[3] = 0.0;
    }
}

static void drives(const ContinuousPlant3 *c, const double s[], const double in[], const double *ds,
                   const double *din, double x[4], double y[4]) {
    drive(&c->x, in[IN_UX], s[DRIVE_X3], din ? din[IN_UX] : 0.0, ds ? ds[DRIVE_X3] : 0.0, x);
    drive(&c->y, in[IN_UY], s[DRIVE_Y3], din ? din[IN_UY] : 0.0, ds ? ds[DRIVE_Y3] : 0.0, y);
}

int plant3_derivatives(const ContinuousPlant3 *c, const double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                       PlantMode3 mode, const double *ds, const double *din, double f[N_CONTINUOUS3], double *df) {
    static const double none[N_CONTINUOUS3] = {0};
    if (c->p.m2 == 0 && (in[IN_F2X] != 0 || in[IN_F2Y] != 0)) return PLANT3_F2_WITHOUT_MASS;
    const double *sd = ds ? ds : none, *si = din ? din : none;
    double tx[4], ty[4];
    drives(c, s, in, sd, si, tx, ty);
    double ax = tx[0], t_ax = tx[1], ay = ty[0], t_ay = ty[1];
    if (mode.speed_x) ax = 0.0, t_ax = 0.0;
    if (mode.speed_y) ay = 0.0, t_ay = 0.0;
    double rate = 0.0, t_rate = 0.0, lift = 0.0, t_lift = 0.0;
    if (!mode.cable) {
        rate = s[DL13], t_rate = sd[DL13];
        if (!mode.hoist) lift = in[IN_HOIST], t_lift = si[IN_HOIST];
    }
    Load3 load = {lift, in[IN_F1X], in[IN_F1Y], in[IN_F2X], in[IN_F2Y], c->c1, c->c2};
    double seed[17] = {sd[A1], sd[DA1], sd[B1], sd[DB1], sd[A2], sd[DA2], sd[B2], sd[DB2], t_ax, t_ay, sd[L13],
                       t_rate, t_lift, si[IN_F1X], si[IN_F1Y], si[IN_F2X], si[IN_F2Y]};
    double dd[4], tdd[4];
    spatial_accelerations_tangent(&s[A1], ax, ay, &c->p, s[L13], rate, &load, seed, dd, tdd);
    double values[N_CONTINUOUS3] = {s[DX3], ax, s[DY3], ay, s[DA1], dd[0], s[DB1], dd[1], s[DA2], dd[2], s[DB2], dd[3],
                                    rate, lift, tx[2], ty[2]};
    for (int i = 0; i < N_CONTINUOUS3; i++) {
        if (!isfinite(values[i])) return PLANT3_NOT_FINITE;
        f[i] = values[i];
    }
    if (df) {
        double t[N_CONTINUOUS3] = {sd[DX3], t_ax, sd[DY3], t_ay, sd[DA1], tdd[0], sd[DB1], tdd[1], sd[DA2], tdd[2],
                                   sd[DB2], tdd[3], t_rate, t_lift, tx[3], ty[3]};
        for (int i = 0; i < N_CONTINUOUS3; i++) df[i] = t[i];
    }
    return PLANT3_OK;
}

void plant3_outputs(const ContinuousPlant3 *c, const double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                    PlantMode3 mode, const double *ds, const double *din, double out[N_OUTPUTS3], double *dout) {
    static const double none[N_CONTINUOUS3] = {0};
    double tx[4], ty[4];
    drives(c, s, in, ds ? ds : none, din ? din : none, tx, ty);
    for (int i = 0; i < L13; i++) out[i] = s[i];
    spatial_outputs(s, &c->p, out + L13);
    out[21] = s[L13], out[22] = s[DL13], out[23] = mode.speed_x ? 0.0 : tx[0], out[24] = mode.speed_y ? 0.0 : ty[0];
    if (dout) {
        for (int i = 0; i < L13; i++) dout[i] = ds[i];
        spatial_outputs_tangent(s, &c->p, ds, dout + L13);
        dout[21] = ds[L13], dout[22] = ds[DL13];
        dout[23] = mode.speed_x ? 0.0 : tx[1], dout[24] = mode.speed_y ? 0.0 : ty[1];
    }
}

void plant3_event_indicators(const ContinuousPlant3 *c, const double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                             PlantMode3 mode, double z[N_INDICATORS3]) {
    double tx[4], ty[4];
    drives(c, s, in, NULL, NULL, tx, ty);
    pair(s[X3], c->x.low, c->x.high, 0, 0.0, z);
    pair(s[DX3], -c->x.v_max, c->x.v_max, mode.speed_x, tx[0], z + 2);
    pair(s[Y3], c->y.low, c->y.high, 0, 0.0, z + 4);
    pair(s[DY3], -c->y.v_max, c->y.v_max, mode.speed_y, ty[0], z + 6);
    pair(s[L13], c->l1_min, c->l1_max, mode.cable, in[IN_HOIST], z + 8);
    pair(s[DL13], -c->dl1_max, c->dl1_max, mode.hoist, in[IN_HOIST], z + 10);
}

/* The rail end the trolley is at and moving past along one axis: +1 (high), -1 (low), 0 none. */
static int rail_end(const Axis *a, double position, double speed, double accel) {
    double outward = speed != 0 ? speed : accel;
    if (position > a->high || (position == a->high && outward > 0)) return 1;
    if (position < a->low || (position == a->low && outward < 0)) return -1;
    return 0;
}

void plant3_event_update(const ContinuousPlant3 *c, double s[N_CONTINUOUS3], const double in[N_INPUTS3],
                         PlantMode3 *mode, PlantEvent3 *event) {
    double tx[4], ty[4];
    drives(c, s, in, NULL, NULL, tx, ty);
    double push_x = tx[0], push_y = ty[0], lift = in[IN_HOIST];
    *event = (PlantEvent3){0, 0, 0, 0.0, 0.0};
    int end = rail_end(&c->x, s[X3], s[DX3], mode->speed_x ? 0.0 : push_x);
    if (!end) end = rail_end(&c->y, s[Y3], s[DY3], mode->speed_y ? 0.0 : push_y), event->rail_axis = end ? 1 : 0;
    if (end) {
        event->rail_end = end;
        return;
    }
    hold(&s[DX3], push_x, push_x, &mode->speed_x, -c->x.v_max, c->x.v_max);
    hold(&s[DY3], push_y, push_y, &mode->speed_y, -c->y.v_max, c->y.v_max);
    double dl1 = s[DL13];
    int reached = hold(&s[L13], dl1, lift, &mode->cable, c->l1_min, c->l1_max);
    if (mode->cable || reached) {
        if (reached && dl1 != 0.0) event->cable_reached = 1, event->cable_at = s[L13], event->cable_rate = dl1;
        s[DL13] = 0.0, mode->hoist = 0;
    } else {
        hold(&s[DL13], lift, lift, &mode->hoist, -c->dl1_max, c->dl1_max);
    }
}
