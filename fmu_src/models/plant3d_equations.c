/*
 * The spatial crane's equations (S1)-(S6) and its RK4 step. Each expression keeps the order of operations of
 * crane_fmu/model/plant3d_equations.py, the specification: C and Python evaluate a + b + c and a * b * c from the
 * left alike, so the same IEEE operations give the same numbers (-ffp-contract=off).
 */
#include "plant3d_equations.h"

#include <math.h>

#include "plant_math.h"

static double dot(const double p[3], const double q[3]) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }

/* One cable's direction and its rates: (S1)-(S3) and w = e x e' (plant3d_equations._cable). */
typedef struct {
    double sb, cb, e[3], u[3], v[3], s, de[3], k[3], w[3];
} Cable;

static void cable(double a, double da, double b, double db, Cable *c) {
    double sa = SIN(a), ca = COS(a), sb = SIN(b), cb = COS(b);
    c->sb = sb, c->cb = cb;
    c->e[0] = sa * cb, c->e[1] = sb, c->e[2] = -ca * cb;
    c->u[0] = ca, c->u[1] = 0.0, c->u[2] = sa;
    c->v[0] = -sa * sb, c->v[1] = cb, c->v[2] = ca * sb;
    double s = cb * da;
    c->s = s;
    for (int i = 0; i < 3; i++) c->de[i] = s * c->u[i] + db * c->v[i];
    double aa = da * da * cb, ab = 2.0 * da * db * sb, bb = db * db;
    c->k[0] = -aa * sa - ab * c->u[0] - bb * c->e[0];
    c->k[1] = -ab * c->u[1] - bb * c->e[1];
    c->k[2] = aa * ca - ab * c->u[2] - bb * c->e[2];
    for (int i = 0; i < 3; i++) c->w[i] = -s * c->v[i] + db * c->u[i];
}

/* (q1, q2) of (S4) for C = [[c[0], c[1]], [c[2], c[3]]]: L S q1 = r1 - m2 C r2 with S = mu I - m2 C C^T by Cramer's rule, then q2 = (r2 - L C^T q1) / l2. */
static void solve(double mu, double m2, double big_l, double l2, const double c[4], const double r1[2],
                  const double r2[2], double q1[2], double q2[2]) {
    double c11 = c[0], c12 = c[1], c21 = c[2], c22 = c[3];
    double s11 = mu - m2 * (c11 * c11 + c12 * c12);
    double s12 = -m2 * (c11 * c21 + c12 * c22);
    double s22 = mu - m2 * (c21 * c21 + c22 * c22);
    double h1 = r1[0] - m2 * (c11 * r2[0] + c12 * r2[1]);
    double h2 = r1[1] - m2 * (c21 * r2[0] + c22 * r2[1]);
    double det = (s11 * s22 - s12 * s12) * big_l;
    double p1 = (s22 * h1 - s12 * h2) / det;
    double p2 = (s11 * h2 - s12 * h1) / det;
    q1[0] = p1, q1[1] = p2;
    q2[0] = (r2[0] - big_l * (c11 * p1 + c21 * p2)) / l2;
    q2[1] = (r2[1] - big_l * (c12 * p1 + c22 * p2)) / l2;
}

/* The cables' kinematics and the terms of (S4)-(S6) (plant3d_equations._system). */
typedef struct {
    Cable one, two;
    double c[4], r1[2], r2[2], g1[3], g2[3], d[3]; /* c: C's rows */
} System;

static void system_of(const double angles[8], double ux, double uy, const PlantParameters *p, double big_l, double dl1,
                      const Load3 *load, System *s) {
    double mu = p->m1 + p->m2, m2 = p->m2, l2 = p->l2, g = p->g;
    double ddl1 = load->hoist, f1x = load->f1x, f1y = load->f1y, f2x = load->f2x, f2y = load->f2y, c1 = load->c1,
           c2 = load->c2;
    cable(angles[0], angles[1], angles[2], angles[3], &s->one);
    cable(angles[4], angles[5], angles[6], angles[7], &s->two);
    const Cable *one = &s->one, *two = &s->two;
    const double *e1 = one->e, *u1 = one->u, *v1 = one->v, *de1 = one->de, *k1 = one->k, *u2 = two->u, *v2 = two->v,
                 *k2 = two->k;
    double acc[3] = {ux + ddl1 * e1[0] + 2.0 * dl1 * de1[0] + big_l * k1[0],
                     uy + ddl1 * e1[1] + 2.0 * dl1 * de1[1] + big_l * k1[1],
                     ddl1 * e1[2] + 2.0 * dl1 * de1[2] + big_l * k1[2]};
    double m2l2 = m2 * l2;
    s->g1[0] = f1x + f2x - mu * acc[0] - m2l2 * k2[0];
    s->g1[1] = f1y + f2y - mu * acc[1] - m2l2 * k2[1];
    s->g1[2] = -mu * g - mu * acc[2] - m2l2 * k2[2];
    s->g2[0] = -acc[0] - l2 * k2[0];
    s->g2[1] = -acc[1] - l2 * k2[1];
    s->g2[2] = -g - acc[2] - l2 * k2[2];
    for (int i = 0; i < 3; i++) s->d[i] = two->w[i] - one->w[i];
    const double *d = s->d;
    s->r1[0] = dot(u1, s->g1) + (-c1 * one->s - c2 * dot(d, v1)) / big_l;
    s->r1[1] = dot(v1, s->g1) + (-c1 * angles[3] + c2 * dot(d, u1)) / big_l;
    s->r2[0] = dot(u2, s->g2);
    s->r2[1] = dot(v2, s->g2);
    if (m2 > 0) {
        s->r2[0] += (u2[0] * f2x + c2 * dot(d, v2) / l2) / m2;
        s->r2[1] += (v2[0] * f2x + v2[1] * f2y - c2 * dot(d, u2) / l2) / m2;
    }
    s->c[0] = dot(u1, u2), s->c[1] = dot(u1, v2), s->c[2] = dot(v1, u2), s->c[3] = dot(v1, v2);
}

void spatial_accelerations(const double angles[8], double ux, double uy, const PlantParameters *p, double l1,
                           double dl1, const Load3 *load, double dd[4]) {
    System s;
    double q1[2], q2[2];
    system_of(angles, ux, uy, p, l1, dl1, load, &s);
    solve(p->m1 + p->m2, p->m2, l1, p->l2, s.c, s.r1, s.r2, q1, q2);
    dd[0] = q1[0] / s.one.cb, dd[1] = q1[1], dd[2] = q2[0] / s.two.cb, dd[3] = q2[1];
}

/* The change of cable()'s values along (ta, tda, tb, tdb) (plant3d_equations._cable_tangent). */
static void cable_tangent(const Cable *c, double da, double db, double ta, double tda, double tb, double tdb,
                          Cable *t) {
    double sb = c->sb, cb = c->cb, s = c->s, sa = c->u[2], ca = c->u[0];
    const double *e = c->e, *u = c->u, *v = c->v;
    double tsb = cb * tb, tcb = -sb * tb;
    t->sb = tsb, t->cb = tcb;
    for (int i = 0; i < 3; i++) t->e[i] = cb * u[i] * ta + v[i] * tb;
    t->u[0] = -sa * ta, t->u[1] = 0.0, t->u[2] = ca * ta;
    for (int i = 0; i < 3; i++) t->v[i] = -sb * u[i] * ta - e[i] * tb;
    double ts = tcb * da + cb * tda;
    t->s = ts;
    for (int i = 0; i < 3; i++) t->de[i] = ts * u[i] + s * t->u[i] + tdb * v[i] + db * t->v[i];
    double aa = da * da * cb, ab = 2.0 * da * db * sb, bb = db * db;
    double taa = 2.0 * da * tda * cb + da * da * tcb;
    double tab = 2.0 * (tda * db * sb + da * tdb * sb + da * db * tsb);
    double tbb = 2.0 * db * tdb;
    t->k[0] = -taa * sa - aa * ca * ta - tab * u[0] - ab * t->u[0] - tbb * e[0] - bb * t->e[0];
    t->k[1] = -tab * u[1] - ab * t->u[1] - tbb * e[1] - bb * t->e[1];
    t->k[2] = taa * ca - aa * sa * ta - tab * u[2] - ab * t->u[2] - tbb * e[2] - bb * t->e[2];
    for (int i = 0; i < 3; i++) t->w[i] = -ts * v[i] - s * t->v[i] + tdb * u[i] + db * t->u[i];
}

void spatial_accelerations_tangent(const double angles[8], double ux, double uy, const PlantParameters *p,
                                   double big_l, double dl1, const Load3 *load, const double seed[17], double dd[4],
                                   double tdd[4]) {
    /* Forward-mode differentiation by hand of (S2)-(S6): M q' = r' - M' q by the same elimination
       (plant3d_equations.accelerations_tangent, operation for operation). */
    double ddl1 = load->hoist, f2x = load->f2x, f2y = load->f2y, c1 = load->c1, c2 = load->c2;
    double mu = p->m1 + p->m2, m2 = p->m2, l2 = p->l2;
    const double *ta = seed;
    double tux = seed[8], tuy = seed[9], tl = seed[10], tdl = seed[11], tddl = seed[12], tf1x = seed[13],
           tf1y = seed[14], tf2x = seed[15], tf2y = seed[16];
    System s;
    double q1[2], q2[2];
    system_of(angles, ux, uy, p, big_l, dl1, load, &s);
    solve(mu, m2, big_l, l2, s.c, s.r1, s.r2, q1, q2);
    dd[0] = q1[0] / s.one.cb, dd[1] = q1[1], dd[2] = q2[0] / s.two.cb, dd[3] = q2[1];
    const Cable *one = &s.one, *two = &s.two;
    const double *e1 = one->e, *u1 = one->u, *v1 = one->v, *de1 = one->de, *k1 = one->k, *u2 = two->u, *v2 = two->v;
    const double *g1 = s.g1, *g2 = s.g2, *d = s.d, *c = s.c;
    Cable t1, t2;
    cable_tangent(one, angles[1], angles[3], ta[0], ta[1], ta[2], ta[3], &t1);
    cable_tangent(two, angles[5], angles[7], ta[4], ta[5], ta[6], ta[7], &t2);
    const double *te1 = t1.e, *tu1 = t1.u, *tv1 = t1.v, *tde1 = t1.de, *tk1 = t1.k, *tu2 = t2.u, *tv2 = t2.v,
                 *tk2 = t2.k;
    double t_trolley[3] = {tux, tuy, 0.0}, tacc[3], tg2[3], td[3];
    for (int i = 0; i < 3; i++)
        tacc[i] = t_trolley[i] + tddl * e1[i] + ddl1 * te1[i] + 2.0 * (tdl * de1[i] + dl1 * tde1[i]) + tl * k1[i] +
                  big_l * tk1[i];
    double m2l2 = m2 * l2;
    double tg1[3] = {tf1x + tf2x - mu * tacc[0] - m2l2 * tk2[0], tf1y + tf2y - mu * tacc[1] - m2l2 * tk2[1],
                     -mu * tacc[2] - m2l2 * tk2[2]};
    for (int i = 0; i < 3; i++) tg2[i] = -tacc[i] - l2 * tk2[i];
    for (int i = 0; i < 3; i++) td[i] = t2.w[i] - t1.w[i];
    double q_u1 = -c1 * one->s - c2 * dot(d, v1), q_v1 = -c1 * angles[3] + c2 * dot(d, u1);
    double tq_u1 = -c1 * t1.s - c2 * (dot(td, v1) + dot(d, tv1));
    double tq_v1 = -c1 * ta[3] + c2 * (dot(td, u1) + dot(d, tu1));
    double tr1[2] = {dot(tu1, g1) + dot(u1, tg1) + tq_u1 / big_l - q_u1 * tl / (big_l * big_l),
                     dot(tv1, g1) + dot(v1, tg1) + tq_v1 / big_l - q_v1 * tl / (big_l * big_l)};
    double tr2[2] = {dot(tu2, g2) + dot(u2, tg2), dot(tv2, g2) + dot(v2, tg2)};
    if (m2 > 0) {
        tr2[0] += (tu2[0] * f2x + u2[0] * tf2x + c2 * (dot(td, v2) + dot(d, tv2)) / l2) / m2;
        tr2[1] += (tv2[0] * f2x + v2[0] * tf2x + tv2[1] * f2y + v2[1] * tf2y - c2 * (dot(td, u2) + dot(d, tu2)) / l2) /
                  m2;
    }
    double tc[4] = {dot(tu1, u2) + dot(u1, tu2), dot(tu1, v2) + dot(u1, tv2), dot(tv1, u2) + dot(v1, tu2),
                    dot(tv1, v2) + dot(v1, tv2)};
    /* M' q moved to the right-hand side: M' = [[mu L' I, m2 l2 C'], [L' C^T + L C'^T, 0]] */
    double rhs1[2] = {tr1[0] - mu * tl * q1[0] - m2l2 * (tc[0] * q2[0] + tc[1] * q2[1]),
                      tr1[1] - mu * tl * q1[1] - m2l2 * (tc[2] * q2[0] + tc[3] * q2[1])};
    double rhs2[2] = {tr2[0] - tl * (c[0] * q1[0] + c[2] * q1[1]) - big_l * (tc[0] * q1[0] + tc[2] * q1[1]),
                      tr2[1] - tl * (c[1] * q1[0] + c[3] * q1[1]) - big_l * (tc[1] * q1[0] + tc[3] * q1[1])};
    double tq1[2], tq2[2];
    solve(mu, m2, big_l, l2, c, rhs1, rhs2, tq1, tq2);
    /* a'' = q / cos b: (a'')' = (q' + a'' sin(b) b') / cos b */
    tdd[0] = (tq1[0] + dd[0] * one->sb * ta[2]) / one->cb;
    tdd[1] = tq1[1];
    tdd[2] = (tq2[0] + dd[2] * two->sb * ta[6]) / two->cb;
    tdd[3] = tq2[1];
}

void spatial_rk4_step(double s[N_SPATIAL], double ux, double uy, double dt, const PlantParameters *p,
                      const Load3 *load) {
    double x = s[X3], vx = s[DX3], y = s[Y3], vy = s[DY3];
    double a1 = s[A1], w1 = s[DA1], b1 = s[B1], z1 = s[DB1], a2 = s[A2], w2 = s[DA2], b2 = s[B2], z2 = s[DB2];
    double big_l = s[L13], dl = s[DL13], hoist = load->hoist, h2 = 0.5 * dt;
    /* l1'' = hoist is constant over the step: l1 and its rate are exact at every stage */
    double ls[3] = {big_l, big_l + h2 * dl + 0.5 * hoist * h2 * h2, big_l + dt * dl + 0.5 * hoist * dt * dt};
    double dls[3] = {dl, dl + h2 * hoist, dl + dt * hoist};
    double k1[4], k2[4], k3[4], k4[4];
    spatial_accelerations((double[8]){a1, w1, b1, z1, a2, w2, b2, z2}, ux, uy, p, ls[0], dls[0], load, k1);
    double w1b = w1 + h2 * k1[0], z1b = z1 + h2 * k1[1], w2b = w2 + h2 * k1[2], z2b = z2 + h2 * k1[3];
    spatial_accelerations((double[8]){a1 + h2 * w1, w1b, b1 + h2 * z1, z1b, a2 + h2 * w2, w2b, b2 + h2 * z2, z2b}, ux,
                          uy, p, ls[1], dls[1], load, k2);
    double w1c = w1 + h2 * k2[0], z1c = z1 + h2 * k2[1], w2c = w2 + h2 * k2[2], z2c = z2 + h2 * k2[3];
    spatial_accelerations((double[8]){a1 + h2 * w1b, w1c, b1 + h2 * z1b, z1c, a2 + h2 * w2b, w2c, b2 + h2 * z2b, z2c},
                          ux, uy, p, ls[1], dls[1], load, k3);
    double w1d = w1 + dt * k3[0], z1d = z1 + dt * k3[1], w2d = w2 + dt * k3[2], z2d = z2 + dt * k3[3];
    spatial_accelerations((double[8]){a1 + dt * w1c, w1d, b1 + dt * z1c, z1d, a2 + dt * w2c, w2d, b2 + dt * z2c, z2d},
                          ux, uy, p, ls[2], dls[2], load, k4);
    double sixth = dt / 6.0;
    /* x'' = ux and y'' = uy are constant over the step, so RK4 integrates x and y exactly */
    s[X3] = x + dt * vx + h2 * dt * ux;
    s[DX3] = vx + dt * ux;
    s[Y3] = y + dt * vy + h2 * dt * uy;
    s[DY3] = vy + dt * uy;
    s[A1] = a1 + sixth * (w1 + 2.0 * w1b + 2.0 * w1c + w1d);
    s[DA1] = w1 + sixth * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
    s[B1] = b1 + sixth * (z1 + 2.0 * z1b + 2.0 * z1c + z1d);
    s[DB1] = z1 + sixth * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
    s[A2] = a2 + sixth * (w2 + 2.0 * w2b + 2.0 * w2c + w2d);
    s[DA2] = w2 + sixth * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]);
    s[B2] = b2 + sixth * (z2 + 2.0 * z2b + 2.0 * z2c + z2d);
    s[DB2] = z2 + sixth * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]);
    s[L13] = ls[2];
    s[DL13] = dls[2];
}

/* The angle of a cable of direction e from the downward vertical, in [0, pi]. */
static double swing(const double e[3]) { return ATAN2(sqrt(e[0] * e[0] + e[1] * e[1]), -e[2]); }

void spatial_outputs(const double s[N_SPATIAL], const PlantParameters *p, double out[9]) {
    double big_l = s[L13], dl1 = s[DL13], m1 = p->m1, m2 = p->m2, l2 = p->l2;
    Cable one, two;
    cable(s[A1], s[DA1], s[B1], s[DB1], &one);
    cable(s[A2], s[DA2], s[B2], s[DB2], &two);
    const double *e1 = one.e, *e2 = two.e, *de1 = one.de, *de2 = two.de;
    double r1[3] = {s[X3] + big_l * e1[0], s[Y3] + big_l * e1[1], big_l * e1[2]};
    double r2[3] = {r1[0] + l2 * e2[0], r1[1] + l2 * e2[1], r1[2] + l2 * e2[2]};
    double v1[3] = {s[DX3] + dl1 * e1[0] + big_l * de1[0], s[DY3] + dl1 * e1[1] + big_l * de1[1],
                    dl1 * e1[2] + big_l * de1[2]};
    double v2[3] = {v1[0] + l2 * de2[0], v1[1] + l2 * de2[1], v1[2] + l2 * de2[2]};
    double kinetic = 0.5 * (m1 * dot(v1, v1) + m2 * dot(v2, v2));
    double values[9] = {r1[0], r1[1], r1[2], r2[0], r2[1], r2[2], swing(e1), swing(e2),
                        kinetic + p->g * (m1 * r1[2] + m2 * r2[2])};
    for (int i = 0; i < 9; i++) out[i] = values[i];
}

/* The change of swing() along te (0 hanging straight down, where it has a kink). */
static double swing_tangent(const double e[3], const double te[3]) {
    double h = sqrt(e[0] * e[0] + e[1] * e[1]);
    if (h == 0.0) return 0.0;
    double th = (e[0] * te[0] + e[1] * te[1]) / h;
    return (-e[2] * th + h * te[2]) / (h * h + e[2] * e[2]);
}

void spatial_outputs_tangent(const double s[N_SPATIAL], const PlantParameters *p, const double t[N_SPATIAL],
                             double out[9]) {
    double big_l = s[L13], dl1 = s[DL13], m1 = p->m1, m2 = p->m2, l2 = p->l2;
    double tl = t[L13], tdl = t[DL13];
    Cable one, two, t1, t2;
    cable(s[A1], s[DA1], s[B1], s[DB1], &one);
    cable(s[A2], s[DA2], s[B2], s[DB2], &two);
    cable_tangent(&one, s[DA1], s[DB1], t[A1], t[DA1], t[B1], t[DB1], &t1);
    cable_tangent(&two, s[DA2], s[DB2], t[A2], t[DA2], t[B2], t[DB2], &t2);
    const double *e1 = one.e, *e2 = two.e, *de1 = one.de, *de2 = two.de, *te1 = t1.e, *te2 = t2.e, *tde1 = t1.de,
                 *tde2 = t2.de;
    double tr1[3] = {t[X3] + tl * e1[0] + big_l * te1[0], t[Y3] + tl * e1[1] + big_l * te1[1],
                     tl * e1[2] + big_l * te1[2]};
    double tr2[3], tv1[3], tv2[3];
    for (int i = 0; i < 3; i++) tr2[i] = tr1[i] + l2 * te2[i];
    double v1[3] = {s[DX3] + dl1 * e1[0] + big_l * de1[0], s[DY3] + dl1 * e1[1] + big_l * de1[1],
                    dl1 * e1[2] + big_l * de1[2]};
    double v2[3] = {v1[0] + l2 * de2[0], v1[1] + l2 * de2[1], v1[2] + l2 * de2[2]};
    double tv0[3] = {t[DX3], t[DY3], 0.0};
    for (int i = 0; i < 3; i++) tv1[i] = tv0[i] + tdl * e1[i] + dl1 * te1[i] + tl * de1[i] + big_l * tde1[i];
    for (int i = 0; i < 3; i++) tv2[i] = tv1[i] + l2 * tde2[i];
    double tkinetic = m1 * dot(v1, tv1) + m2 * dot(v2, tv2);
    double values[9] = {tr1[0], tr1[1], tr1[2], tr2[0], tr2[1], tr2[2], swing_tangent(e1, te1), swing_tangent(e2, te2),
                        tkinetic + p->g * (m1 * tr1[2] + m2 * tr2[2])};
    for (int i = 0; i < 9; i++) out[i] = values[i];
}
