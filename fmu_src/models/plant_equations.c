/*
 * Eqs (4)-(9) with hoisting, forces and damping, and their RK4 steps. Each expression keeps the
 * order of operations of crane_fmu/model/plant_equations.py, the specification: C and Python
 * evaluate a + b + c and a * b * c from the left alike, so the same IEEE operations give the
 * same numbers (with contraction into fused multiply-adds switched off, -ffp-contract=off).
 */
#include "plant_equations.h"

#include "plant_math.h"

void angular_accelerations(double theta1, double dtheta1, double theta2, double dtheta2, double u,
                           const PlantParameters *p, double big_l, double dl1, const Load *load, double dd[2]) {
    /* With d = theta1 - theta2, L = l1(t), Q1 = -c1 w1 + c2 (w2 - w1), Q2 = -c2 (w2 - w1), mu = m1 + m2:
         mu L dd1 + m2 l2 cos(d) dd2 = -mu (u cos th1 + g sin th1) - m2 l2 w2^2 sin d
                                       - 2 mu L' w1 + (F1 + F2) cos th1 + Q1 / L          eq (8) / L
         L cos(d) dd1 + l2 dd2 = -u cos th2 - g sin th2 + L w1^2 sin d
                                 - L'' sin d - 2 L' w1 cos d + (F2 cos th2 + Q2 / l2) / m2  eq (9) / (m2 l2) */
    double m1m2 = p->m1 + p->m2, l2 = p->l2, g = p->g;
    double s1 = SIN(theta1), co1 = COS(theta1), s2 = SIN(theta2), co2 = COS(theta2);
    double d = theta1 - theta2, sd = SIN(d), cd = COS(d);
    double q1 = -load->c1 * dtheta1 + load->c2 * (dtheta2 - dtheta1);
    double r1 = (-m1m2 * (u * co1 + g * s1) - p->m2 * l2 * dtheta2 * dtheta2 * sd +
                 (-2.0 * m1m2 * dl1 * dtheta1 + (load->f1 + load->f2) * co1 + q1 / big_l));
    double r2 = -u * co2 - g * s2 + big_l * dtheta1 * dtheta1 * sd + (-load->hoist * sd - 2.0 * dl1 * dtheta1 * cd);
    if (p->m2 > 0) r2 += (load->f2 * co2 - load->c2 * (dtheta2 - dtheta1) / l2) / p->m2;
    double a = m1m2 * big_l, b = p->m2 * l2 * cd, c = big_l * cd, e = l2;
    double det = a * e - b * c; /* L l2 (m1 + m2 sin^2 d) > 0 */
    dd[0] = (e * r1 - b * r2) / det;
    dd[1] = (a * r2 - c * r1) / det;
}

/* Eqs (8)-(9) of the paper as printed: angular_accelerations() less its terms that vanish here. */
static void paper_accelerations(double theta1, double dtheta1, double theta2, double dtheta2, double u,
                                double big_l, double a, double al2, const PlantParameters *p, double dd[2]) {
    double m1m2 = p->m1 + p->m2, m2l2 = p->m2 * p->l2, l2 = p->l2, g = p->g;
    double d = theta1 - theta2, sd = SIN(d), cd = COS(d);
    double r1 = -m1m2 * (u * COS(theta1) + g * SIN(theta1)) - m2l2 * dtheta2 * dtheta2 * sd;
    double r2 = -u * COS(theta2) - g * SIN(theta2) + big_l * dtheta1 * dtheta1 * sd;
    double b = m2l2 * cd, c = big_l * cd;
    double det = al2 - b * c;
    dd[0] = (l2 * r1 - b * r2) / det;
    dd[1] = (a * r2 - c * r1) / det;
}

/* The end of an RK4 step from the state s at its start (overwritten): the swing rates at the four stages (w1 and
   w2: at the start, b, c, d) and the angular accelerations k1..k4. x'' = u is constant over the step, so RK4
   integrates x exactly. */
static void rk4_end(double s[N_SWING], double u, double dt, const double w1[4], const double w2[4],
                    const double k1[2], const double k2[2], const double k3[2], const double k4[2]) {
    double x = s[X], v = s[DX], a1 = s[THETA1], a2 = s[THETA2], h2 = 0.5 * dt, sixth = dt / 6.0;
    s[X] = x + dt * v + h2 * dt * u;
    s[DX] = v + dt * u;
    s[THETA1] = a1 + sixth * (w1[0] + 2.0 * w1[1] + 2.0 * w1[2] + w1[3]);
    s[DTHETA1] = w1[0] + sixth * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
    s[THETA2] = a2 + sixth * (w2[0] + 2.0 * w2[1] + 2.0 * w2[2] + w2[3]);
    s[DTHETA2] = w2[0] + sixth * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
}

void paper_step(double s[N_SWING], double u, double dt, const PlantParameters *p) {
    double a1 = s[THETA1], w1 = s[DTHETA1], a2 = s[THETA2], w2 = s[DTHETA2], big_l = s[L1];
    double a = (p->m1 + p->m2) * big_l, al2 = a * p->l2, h2 = 0.5 * dt;
    double k1[2], k2[2], k3[2], k4[2];
    paper_accelerations(a1, w1, a2, w2, u, big_l, a, al2, p, k1);
    double w1b = w1 + h2 * k1[0], w2b = w2 + h2 * k1[1];
    paper_accelerations(a1 + h2 * w1, w1b, a2 + h2 * w2, w2b, u, big_l, a, al2, p, k2);
    double w1c = w1 + h2 * k2[0], w2c = w2 + h2 * k2[1];
    paper_accelerations(a1 + h2 * w1b, w1c, a2 + h2 * w2b, w2c, u, big_l, a, al2, p, k3);
    double w1d = w1 + dt * k3[0], w2d = w2 + dt * k3[1];
    paper_accelerations(a1 + dt * w1c, w1d, a2 + dt * w2c, w2d, u, big_l, a, al2, p, k4);
    rk4_end(s, u, dt, (double[4]){w1, w1b, w1c, w1d}, (double[4]){w2, w2b, w2c, w2d}, k1, k2, k3, k4);
    s[DL1] = 0.0;
}

void rk4_step(double s[N_SWING], double u, double dt, const PlantParameters *p, const Load *load) {
    double a1 = s[THETA1], w1 = s[DTHETA1], a2 = s[THETA2], w2 = s[DTHETA2];
    double big_l = s[L1], dl = s[DL1], hoist = load->hoist, h2 = 0.5 * dt;
    /* l1'' = hoist is constant over the step: l1 and its rate are exact at every stage */
    double ls[3] = {big_l, big_l + h2 * dl + 0.5 * hoist * h2 * h2, big_l + dt * dl + 0.5 * hoist * dt * dt};
    double dls[3] = {dl, dl + h2 * hoist, dl + dt * hoist};
    double k1[2], k2[2], k3[2], k4[2];
    angular_accelerations(a1, w1, a2, w2, u, p, ls[0], dls[0], load, k1);
    angular_accelerations(a1 + h2 * w1, w1 + h2 * k1[0], a2 + h2 * w2, w2 + h2 * k1[1], u, p, ls[1], dls[1], load,
                          k2);
    double w1b = w1 + h2 * k1[0], w2b = w2 + h2 * k1[1];
    double w1c = w1 + h2 * k2[0], w2c = w2 + h2 * k2[1];
    angular_accelerations(a1 + h2 * w1b, w1c, a2 + h2 * w2b, w2c, u, p, ls[1], dls[1], load, k3);
    double w1d = w1 + dt * k3[0], w2d = w2 + dt * k3[1];
    angular_accelerations(a1 + dt * w1c, w1d, a2 + dt * w2c, w2d, u, p, ls[2], dls[2], load, k4);
    rk4_end(s, u, dt, (double[4]){w1, w1b, w1c, w1d}, (double[4]){w2, w2b, w2c, w2d}, k1, k2, k3, k4);
    s[L1] = ls[2];
    s[DL1] = dls[2];
}

void plant_outputs(const double s[N_SWING], const PlantParameters *p, double out[11]) {
    double x = s[X], dx = s[DX], theta1 = s[THETA1], dtheta1 = s[DTHETA1], theta2 = s[THETA2], dtheta2 = s[DTHETA2];
    double l1 = s[L1], dl1 = s[DL1], m1 = p->m1, m2 = p->m2, l2 = p->l2;
    double s1 = SIN(theta1), c1 = COS(theta1), s2 = SIN(theta2), c2 = COS(theta2);
    double x1 = x + l1 * s1, y1 = -l1 * c1;                       /* eq (4) */
    double x2 = x1 + l2 * s2, y2 = y1 - l2 * c2;                  /* eq (5) */
    double vx1 = dx + l1 * dtheta1 * c1 + dl1 * s1, vy1 = l1 * dtheta1 * s1 - dl1 * c1;
    double vx2 = vx1 + l2 * dtheta2 * c2, vy2 = vy1 + l2 * dtheta2 * s2;
    double kinetic = 0.5 * (m1 * (vx1 * vx1 + vy1 * vy1) + m2 * (vx2 * vx2 + vy2 * vy2)); /* eq (6) */
    double values[11] = {x, dx, theta1, dtheta1, theta2, dtheta2, x1, y1, x2, y2,
                         kinetic + p->g * (m1 * y1 + m2 * y2)}; /* + eq (7) */
    for (int i = 0; i < 11; i++) out[i] = values[i];
}

void accelerations_tangent(double theta1, double dtheta1, double theta2, double dtheta2, double u,
                           const PlantParameters *p, double big_l, double dl1, const Load *load, const double seed[10],
                           double dd[2], double tdd[2]) {
    /* Forward-mode differentiation by hand of M(q, L) dd = r: M dd' = r' - M' dd, the same determinant
       (plant_equations.accelerations_tangent, operation for operation). */
    angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p, big_l, dl1, load, dd);
    double t1 = seed[0], tw1 = seed[1], t2 = seed[2], tw2 = seed[3], tu = seed[4], tl = seed[5], tdl = seed[6],
           tddl = seed[7], tf1 = seed[8], tf2 = seed[9];
    double m1m2 = p->m1 + p->m2, m2l2 = p->m2 * p->l2, l2 = p->l2, g = p->g;
    double ddl1 = load->hoist, f1 = load->f1, f2 = load->f2, c1 = load->c1, c2 = load->c2;
    double s1 = SIN(theta1), co1 = COS(theta1), s2 = SIN(theta2), co2 = COS(theta2);
    double d = theta1 - theta2, td = t1 - t2, sd = SIN(d), cd = COS(d);
    double q1 = -c1 * dtheta1 + c2 * (dtheta2 - dtheta1);
    double tq1 = -c1 * tw1 + c2 * (tw2 - tw1);
    double tr1 = (-m1m2 * (tu * co1 + (g * co1 - u * s1) * t1) - m2l2 * dtheta2 * (2.0 * tw2 * sd + dtheta2 * cd * td)
                  - 2.0 * m1m2 * (tdl * dtheta1 + dl1 * tw1) + (tf1 + tf2) * co1 - (f1 + f2) * s1 * t1
                  + tq1 / big_l - q1 * tl / (big_l * big_l));
    double tr2 = (-tu * co2 + (u * s2 - g * co2) * t2
                  + dtheta1 * (tl * dtheta1 * sd + big_l * (2.0 * tw1 * sd + dtheta1 * cd * td))
                  - tddl * sd - ddl1 * cd * td - 2.0 * (tdl * dtheta1 * cd + dl1 * tw1 * cd - dl1 * dtheta1 * sd * td));
    if (p->m2 > 0) tr2 += (tf2 * co2 - f2 * s2 * t2 - c2 * (tw2 - tw1) / l2) / p->m2;
    double a = m1m2 * big_l, b = m2l2 * cd, c = big_l * cd, e = l2;
    /* M' dd moved to the right-hand side; M' = [[m1m2 L', -m2 l2 sin(d) d'], [L' cos(d) - L sin(d) d', 0]] */
    double rhs1 = tr1 - m1m2 * tl * dd[0] + m2l2 * sd * td * dd[1];
    double rhs2 = tr2 - (tl * cd - big_l * sd * td) * dd[0];
    double det = a * e - b * c;
    tdd[0] = (e * rhs1 - b * rhs2) / det;
    tdd[1] = (a * rhs2 - c * rhs1) / det;
}

void outputs_tangent(const double s[N_SWING], const PlantParameters *p, const double t[N_SWING], double out[11]) {
    double dx = s[DX], theta1 = s[THETA1], dtheta1 = s[DTHETA1], theta2 = s[THETA2], dtheta2 = s[DTHETA2];
    double l1 = s[L1], dl1 = s[DL1], m1 = p->m1, m2 = p->m2, l2 = p->l2;
    double tx = t[X], tdx = t[DX], t1 = t[THETA1], tw1 = t[DTHETA1], t2 = t[THETA2], tw2 = t[DTHETA2], tl = t[L1],
           tdl = t[DL1];
    double s1 = SIN(theta1), c1 = COS(theta1), s2 = SIN(theta2), c2 = COS(theta2);
    double tx1 = tx + tl * s1 + l1 * c1 * t1, ty1 = -tl * c1 + l1 * s1 * t1;
    double tx2 = tx1 + l2 * c2 * t2, ty2 = ty1 + l2 * s2 * t2;
    double vx1 = dx + l1 * dtheta1 * c1 + dl1 * s1, vy1 = l1 * dtheta1 * s1 - dl1 * c1;
    double vx2 = vx1 + l2 * dtheta2 * c2, vy2 = vy1 + l2 * dtheta2 * s2;
    double tvx1 = tdx + (tl * dtheta1 + l1 * tw1) * c1 - l1 * dtheta1 * s1 * t1 + tdl * s1 + dl1 * c1 * t1;
    double tvy1 = (tl * dtheta1 + l1 * tw1) * s1 + l1 * dtheta1 * c1 * t1 - tdl * c1 + dl1 * s1 * t1;
    double tvx2 = tvx1 + l2 * (tw2 * c2 - dtheta2 * s2 * t2);
    double tvy2 = tvy1 + l2 * (tw2 * s2 + dtheta2 * c2 * t2);
    double tkinetic = m1 * (vx1 * tvx1 + vy1 * tvy1) + m2 * (vx2 * tvx2 + vy2 * tvy2);
    double values[11] = {tx, tdx, t1, tw1, t2, tw2, tx1, ty1, tx2, ty2, tkinetic + p->g * (m1 * ty1 + m2 * ty2)};
    for (int i = 0; i < 11; i++) out[i] = values[i];
}
