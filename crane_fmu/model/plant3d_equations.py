"""The overhead crane in three dimensions: a spatial double pendulum under a trolley that moves in x and y.

The trolley (bridge and trolley of an overhead crane) moves in the horizontal plane with the
accelerations ``ux = x''`` and ``uy = y''`` [m/s2]; the hook (m1) hangs on the main cable of length
``L = l1(t)`` (the hoist), the load (m2) on the cable l2 below the hook. Each cable's direction
is the unit vector, with ``z`` up,

    (S1)  e(a, b) = (sin a cos b, sin b, -cos a cos b),

regular at the vertical (singular only with the cable horizontal, ``cos b = 0``); ``a`` is the angle
of the cable's projection onto the x-z plane from the downward vertical (the planar crane's theta),
``b`` the cable's angle out of that plane, towards +y. With ``b = 0`` everything is the planar crane
of :mod:`.plant_equations`.

The swing-and-hoist state is ``(x, dx, y, dy, a1, da1, b1, db1, a2, da2, b2, db2, l1, dl1)`` in SI
units (the positions below name them).

Equations of motion (derived symbolically in ``tests/test_plant3d_equations.py``). With each cable's
orthonormal frame ``(u, v, e)``, ``u = (cos a, 0, sin a)``, ``v = (-sin a sin b, cos b, cos a sin b)``,

    (S2)  e' = s u + b' v,    s = cos(b) a',
    (S3)  e'' = cos(b) a'' u + b'' v + k,    k = a'^2 cos(b) (-sin a, 0, cos a) - 2 a' b' sin(b) u - b'^2 e.

The hook is at ``r1 = (x, y, 0) + L e1`` and the load at ``r2 = r1 + l2 e2``. d'Alembert's principle
along each cable's tangents (the Lagrange equations of ``a`` divided by ``L cos b`` resp.
``m2 l2 cos b``, of ``b`` by ``L`` resp. ``m2 l2``), in the tangential accelerations
``q1 = (cos(b1) a1'', b1'')`` and ``q2 = (cos(b2) a2'', b2'')``, are

    (S4)  mu L q1 + m2 l2 C q2 = R1,    L C^T q1 + l2 q2 = R2,    C = [[u1.u2, u1.v2], [v1.u2, v1.v2]],

with ``mu = m1 + m2``, ``A1 = (ux, uy, 0) + L'' e1 + 2 L' e1' + L k1`` the hook's acceleration less
its tangential part, ``F1``, ``F2`` the horizontal forces on hook and load, ``z = (0, 0, 1)``,

    (S5)  R1 = (t . (F1 + F2 - mu g z - mu A1 - m2 l2 k2) + Q_t / L  for t = u1, v1),
          R2 = (t . (-g z - A1 - l2 k2) + (t . F2 + Q_t / l2) / m2  for t = u2, v2),

and the damping's generalised forces from Rayleigh's function
``D = (c1 |w1|^2 + c2 |w2 - w1|^2) / 2`` of the cables' angular velocities ``w = e x e' = -s v + b' u``
(``c1`` at the trolley joint, ``c2`` at the hook joint, as in the planar model):

    (S6)  Q_u1 = -c1 s1 - c2 d.v1,  Q_v1 = -c1 b1' + c2 d.u1,  Q_u2 = c2 d.v2,  Q_v2 = -c2 d.u2,  d = w2 - w1.

Eliminating ``q2`` leaves the 2x2 system ``L S q1 = R1 - m2 C R2``, ``S = mu I - m2 C C^T``
(symmetric; its determinant is positive for m1 > 0, since C's singular values are at most 1:
``m1 + m2 sin^2(a1 - a2)`` times ``mu`` in the plane), solved by Cramer's rule; then
``q2 = (R2 - L C^T q1) / l2`` (:func:`_solve`, the fixed elimination the C twin repeats).
"""

import math

from .plant_equations import substeps  # noqa: F401 (the same sub-step rule as the planar plant)

# positions in the spatial swing-and-hoist state
X, DX, Y, DY, A1, DA1, B1, DB1, A2, DA2, B2, DB2, L1, DL1 = range(14)
ANGLES = slice(A1, DB2 + 1)  # (a1, da1, b1, db1, a2, da2, b2, db2)

NO_LOAD = (0.0,) * 7  # (ddl1, F1x, F1y, F2x, F2y, c1, c2): nothing but the trolley acts


def _dot(p, q):
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def _cable(a, da, b, db):
    """One cable's direction and its rates: ``(sb, cb, e, u, v, s, de, k, w)`` of (S1)-(S3) and ``w = e x e'``."""
    sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
    e = (sa * cb, sb, -ca * cb)
    u = (ca, 0.0, sa)
    v = (-sa * sb, cb, ca * sb)
    s = cb * da
    de = (s * u[0] + db * v[0], s * u[1] + db * v[1], s * u[2] + db * v[2])
    aa, ab, bb = da * da * cb, 2.0 * da * db * sb, db * db
    k = (-aa * sa - ab * u[0] - bb * e[0], -ab * u[1] - bb * e[1], aa * ca - ab * u[2] - bb * e[2])
    w = (-s * v[0] + db * u[0], -s * v[1] + db * u[1], -s * v[2] + db * u[2])
    return sb, cb, e, u, v, s, de, k, w


def _solve(mu, m2, big_l, l2, c, r1, r2):
    """``(q1, q2)`` of (S4) for the coupling ``c`` (rows of C) and right-hand sides ``r1``, ``r2``: the elimination.

    ``L S q1 = r1 - m2 C r2`` with ``S = mu I - m2 C C^T`` by Cramer's rule, then ``q2 = (r2 - L C^T q1) / l2``.
    """
    (c11, c12), (c21, c22) = c
    s11 = mu - m2 * (c11 * c11 + c12 * c12)
    s12 = -m2 * (c11 * c21 + c12 * c22)
    s22 = mu - m2 * (c21 * c21 + c22 * c22)
    h1 = r1[0] - m2 * (c11 * r2[0] + c12 * r2[1])
    h2 = r1[1] - m2 * (c21 * r2[0] + c22 * r2[1])
    det = (s11 * s22 - s12 * s12) * big_l
    p1 = (s22 * h1 - s12 * h2) / det
    p2 = (s11 * h2 - s12 * h1) / det
    return (p1, p2), ((r2[0] - big_l * (c11 * p1 + c21 * p2)) / l2, (r2[1] - big_l * (c12 * p1 + c22 * p2)) / l2)


def _system(angles, ux, uy, p, big_l, dl1, load):
    """The cables' kinematics and the terms of (S4)-(S6): ``(one, two, c, r1, r2)`` and, for the tangent, ``G1``,
    ``G2`` (the vectors projected in R1 and R2) and ``d = w2 - w1``."""
    a1, da1, b1, db1, a2, da2, b2, db2 = angles
    ddl1, f1x, f1y, f2x, f2y, c1, c2 = load
    mu, m2, l2, g = p.m1 + p.m2, p.m2, p.l2, p.g
    one, two = _cable(a1, da1, b1, db1), _cable(a2, da2, b2, db2)
    _, _, e1, u1, v1, s1, de1, k1, w1 = one
    _, _, _, u2, v2, _, _, k2, w2 = two
    acc = (ux + ddl1 * e1[0] + 2.0 * dl1 * de1[0] + big_l * k1[0],  # A1: the hook's acceleration but q1's part
           uy + ddl1 * e1[1] + 2.0 * dl1 * de1[1] + big_l * k1[1],
           ddl1 * e1[2] + 2.0 * dl1 * de1[2] + big_l * k1[2])
    m2l2 = m2 * l2
    g1 = (f1x + f2x - mu * acc[0] - m2l2 * k2[0], f1y + f2y - mu * acc[1] - m2l2 * k2[1],
          -mu * g - mu * acc[2] - m2l2 * k2[2])
    g2 = (-acc[0] - l2 * k2[0], -acc[1] - l2 * k2[1], -g - acc[2] - l2 * k2[2])
    d = (w2[0] - w1[0], w2[1] - w1[1], w2[2] - w1[2])
    r1 = (_dot(u1, g1) + (-c1 * s1 - c2 * _dot(d, v1)) / big_l,
          _dot(v1, g1) + (-c1 * db1 + c2 * _dot(d, u1)) / big_l)
    r2 = [_dot(u2, g2), _dot(v2, g2)]
    if m2 > 0:
        r2[0] += (u2[0] * f2x + c2 * _dot(d, v2) / l2) / m2
        r2[1] += (v2[0] * f2x + v2[1] * f2y - c2 * _dot(d, u2) / l2) / m2
    c = ((_dot(u1, u2), _dot(u1, v2)), (_dot(v1, u2), _dot(v1, v2)))
    return one, two, c, r1, r2, g1, g2, d


def angular_accelerations(angles, ux, uy, p, big_l, dl1=0.0, load=NO_LOAD):
    """Solve the Lagrange equations (S4)-(S6) for the angular accelerations.

    Parameters
    ----------
    angles : tuple
        ``(a1, da1, b1, db1, a2, da2, b2, db2)``: the cables' angles [rad] and rates [rad/s].
    ux, uy : float
        The trolley's accelerations [m/s2].
    p : PlantParameters
        Masses, cable lengths and gravity (``p.l1`` is not used: ``big_l`` is the main cable now).
    big_l, dl1 : float
        The main cable's length [m] and rate [m/s] now.
    load : tuple
        ``(ddl1, F1x, F1y, F2x, F2y, c1, c2)``: the hoist's acceleration [m/s2], the horizontal forces
        on hook and load [N], the damping at the trolley and hook joints [N m s/rad].

    Returns
    -------
    tuple
        ``(dda1, ddb1, dda2, ddb2)`` [rad/s2].
    """
    one, two, c, r1, r2, _, _, _ = _system(angles, ux, uy, p, big_l, dl1, load)
    q1, q2 = _solve(p.m1 + p.m2, p.m2, big_l, p.l2, c, r1, r2)
    return q1[0] / one[1], q1[1], q2[0] / two[1], q2[1]


def _cable_tangent(cable, a, da, b, db, ta, tda, tb, tdb):
    """The change of :func:`_cable`'s ``(sb, cb, e, u, v, s, de, k, w)`` along ``(ta, tda, tb, tdb)``.

    ``e_a = cos(b) u``, ``e_b = v``, ``u_a = (-sin a, 0, cos a)``, ``v_a = -sin(b) u``, ``v_b = -e``.
    """
    sb, cb, e, u, v, s, de, k, w = cable
    sa, ca = u[2], u[0]
    tsb, tcb = cb * tb, -sb * tb
    te = tuple(cb * u[i] * ta + v[i] * tb for i in range(3))
    tu = (-sa * ta, 0.0, ca * ta)
    tv = tuple(-sb * u[i] * ta - e[i] * tb for i in range(3))
    ts = tcb * da + cb * tda
    tde = tuple(ts * u[i] + s * tu[i] + tdb * v[i] + db * tv[i] for i in range(3))
    aa, ab, bb = da * da * cb, 2.0 * da * db * sb, db * db
    taa = 2.0 * da * tda * cb + da * da * tcb
    tab = 2.0 * (tda * db * sb + da * tdb * sb + da * db * tsb)
    tbb = 2.0 * db * tdb
    tk = (-taa * sa - aa * ca * ta - tab * u[0] - ab * tu[0] - tbb * e[0] - bb * te[0],
          -tab * u[1] - ab * tu[1] - tbb * e[1] - bb * te[1],
          taa * ca - aa * sa * ta - tab * u[2] - ab * tu[2] - tbb * e[2] - bb * te[2])
    tw = tuple(-ts * v[i] - s * tv[i] + tdb * u[i] + db * tu[i] for i in range(3))
    return tsb, tcb, te, tu, tv, ts, tde, tk, tw


def accelerations_tangent(angles, ux, uy, p, big_l, dl1, load, seed):
    """:func:`angular_accelerations` and their directional derivative along ``seed``, exactly.

    Parameters
    ----------
    angles, ux, uy, p, big_l, dl1, load
        As for :func:`angular_accelerations`.
    seed : tuple
        The direction: the changes of ``(a1, da1, b1, db1, a2, da2, b2, db2, ux, uy, l1, dl1, ddl1, F1x, F1y,
        F2x, F2y)`` (the damping is a parameter).

    Returns
    -------
    (tuple, tuple)
        ``(dda1, ddb1, dda2, ddb2)`` and their derivative along ``seed``.

    Notes
    -----
    Forward-mode differentiation by hand of (S2)-(S6); the derivative of the solution of ``M q = r`` is the
    solution of ``M q' = r' - M' q``, by the same elimination (:func:`_solve`).
    """
    a1, da1, b1, db1, a2, da2, b2, db2 = angles
    ddl1, f1x, f1y, f2x, f2y, c1, c2 = load
    mu, m2, l2 = p.m1 + p.m2, p.m2, p.l2
    t_angles, (tux, tuy, tl, tdl, tddl, tf1x, tf1y, tf2x, tf2y) = seed[:8], seed[8:]
    one, two, c, r1, r2, g1, g2, d = _system(angles, ux, uy, p, big_l, dl1, load)
    q1, q2 = _solve(mu, m2, big_l, l2, c, r1, r2)
    dd = (q1[0] / one[1], q1[1], q2[0] / two[1], q2[1])
    _, _, e1, u1, v1, s1, de1, k1, _ = one
    sb2, cb2, _, u2, v2, _, _, _, _ = two
    t1 = _cable_tangent(one, a1, da1, b1, db1, *t_angles[:4])
    t2 = _cable_tangent(two, a2, da2, b2, db2, *t_angles[4:])
    _, _, te1, tu1, tv1, ts1, tde1, tk1, tw1 = t1
    _, _, _, tu2, tv2, _, _, tk2, tw2 = t2
    t_trolley = (tux, tuy, 0.0)
    tacc = tuple(t_trolley[i] + tddl * e1[i] + ddl1 * te1[i] + 2.0 * (tdl * de1[i] + dl1 * tde1[i])
                 + tl * k1[i] + big_l * tk1[i] for i in range(3))
    m2l2 = m2 * l2
    tg1 = (tf1x + tf2x - mu * tacc[0] - m2l2 * tk2[0], tf1y + tf2y - mu * tacc[1] - m2l2 * tk2[1],
           -mu * tacc[2] - m2l2 * tk2[2])
    tg2 = tuple(-tacc[i] - l2 * tk2[i] for i in range(3))
    td = tuple(tw2[i] - tw1[i] for i in range(3))
    q_u1, q_v1 = -c1 * s1 - c2 * _dot(d, v1), -c1 * db1 + c2 * _dot(d, u1)
    tq_u1 = -c1 * ts1 - c2 * (_dot(td, v1) + _dot(d, tv1))
    tq_v1 = -c1 * t_angles[3] + c2 * (_dot(td, u1) + _dot(d, tu1))
    tr1 = (_dot(tu1, g1) + _dot(u1, tg1) + tq_u1 / big_l - q_u1 * tl / (big_l * big_l),
           _dot(tv1, g1) + _dot(v1, tg1) + tq_v1 / big_l - q_v1 * tl / (big_l * big_l))
    tr2 = [_dot(tu2, g2) + _dot(u2, tg2), _dot(tv2, g2) + _dot(v2, tg2)]
    if m2 > 0:
        tr2[0] += (tu2[0] * f2x + u2[0] * tf2x + c2 * (_dot(td, v2) + _dot(d, tv2)) / l2) / m2
        tr2[1] += (tv2[0] * f2x + v2[0] * tf2x + tv2[1] * f2y + v2[1] * tf2y
                   - c2 * (_dot(td, u2) + _dot(d, tu2)) / l2) / m2
    tc = ((_dot(tu1, u2) + _dot(u1, tu2), _dot(tu1, v2) + _dot(u1, tv2)),
          (_dot(tv1, u2) + _dot(v1, tu2), _dot(tv1, v2) + _dot(v1, tv2)))
    # M' q moved to the right-hand side: M' = [[mu L' I, m2 l2 C'], [L' C^T + L C'^T, 0]]
    rhs1 = (tr1[0] - mu * tl * q1[0] - m2l2 * (tc[0][0] * q2[0] + tc[0][1] * q2[1]),
            tr1[1] - mu * tl * q1[1] - m2l2 * (tc[1][0] * q2[0] + tc[1][1] * q2[1]))
    rhs2 = (tr2[0] - tl * (c[0][0] * q1[0] + c[1][0] * q1[1]) - big_l * (tc[0][0] * q1[0] + tc[1][0] * q1[1]),
            tr2[1] - tl * (c[0][1] * q1[0] + c[1][1] * q1[1]) - big_l * (tc[0][1] * q1[0] + tc[1][1] * q1[1]))
    tq1, tq2 = _solve(mu, m2, big_l, l2, c, rhs1, rhs2)
    # a'' = q / cos b: (a'')' = (q' + a'' sin(b) b') / cos b
    tdd = ((tq1[0] + dd[0] * one[0] * t_angles[2]) / one[1], tq1[1],
           (tq2[0] + dd[2] * sb2 * t_angles[6]) / cb2, tq2[1])
    return dd, tdd


def derivative(state, ux, uy, p, hoist=0.0, forces=(0.0,) * 6):
    """Time derivative of the 14-element state for held trolley accelerations and hoist acceleration.

    ``forces`` is ``(F1x, F1y, F2x, F2y, c1, c2)``.
    """
    dd = angular_accelerations(state[ANGLES], ux, uy, p, state[L1], state[DL1], (hoist, *forces))
    return (state[DX], ux, state[DY], uy, state[DA1], dd[0], state[DB1], dd[1], state[DA2], dd[2], state[DB2], dd[3],
            state[DL1], hoist)


def rk4_step(state, ux, uy, dt, p, hoist=0.0, forces=(0.0,) * 6):
    """Advance the 14-element ``state`` by ``dt``: one classical RK4 step, the inputs held.

    The trolley's ``x'' = ux``, ``y'' = uy`` and the hoist's ``l1'' = hoist`` are constant over the step, so
    RK4 integrates them exactly (and gives the cable's length and rate exactly at every stage).
    """
    x, vx, y, vy = state[X:DY + 1]
    a1, w1, b1, z1, a2, w2, b2, z2 = state[ANGLES]
    big_l, dl = state[L1], state[DL1]
    h2 = 0.5 * dt
    ls = (big_l, big_l + h2 * dl + 0.5 * hoist * h2 * h2, big_l + dt * dl + 0.5 * hoist * dt * dt)
    dls = (dl, dl + h2 * hoist, dl + dt * hoist)
    f = [(hoist, *forces)] * 3

    def acc(angles, i):
        return angular_accelerations(angles, ux, uy, p, ls[i], dls[i], f[i])

    k1 = acc((a1, w1, b1, z1, a2, w2, b2, z2), 0)
    w1b, z1b, w2b, z2b = w1 + h2 * k1[0], z1 + h2 * k1[1], w2 + h2 * k1[2], z2 + h2 * k1[3]
    k2 = acc((a1 + h2 * w1, w1b, b1 + h2 * z1, z1b, a2 + h2 * w2, w2b, b2 + h2 * z2, z2b), 1)
    w1c, z1c, w2c, z2c = w1 + h2 * k2[0], z1 + h2 * k2[1], w2 + h2 * k2[2], z2 + h2 * k2[3]
    k3 = acc((a1 + h2 * w1b, w1c, b1 + h2 * z1b, z1c, a2 + h2 * w2b, w2c, b2 + h2 * z2b, z2c), 1)
    w1d, z1d, w2d, z2d = w1 + dt * k3[0], z1 + dt * k3[1], w2 + dt * k3[2], z2 + dt * k3[3]
    k4 = acc((a1 + dt * w1c, w1d, b1 + dt * z1c, z1d, a2 + dt * w2c, w2d, b2 + dt * z2c, z2d), 2)
    s = dt / 6.0
    return (x + dt * vx + h2 * dt * ux, vx + dt * ux, y + dt * vy + h2 * dt * uy, vy + dt * uy,
            a1 + s * (w1 + 2.0 * w1b + 2.0 * w1c + w1d), w1 + s * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
            b1 + s * (z1 + 2.0 * z1b + 2.0 * z1c + z1d), z1 + s * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
            a2 + s * (w2 + 2.0 * w2b + 2.0 * w2c + w2d), w2 + s * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]),
            b2 + s * (z2 + 2.0 * z2b + 2.0 * z2c + z2d), z2 + s * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]),
            ls[2], dls[2])


def outputs(state, p):
    """Hook and load positions ``x1, y1, z1, x2, y2, z2`` (z up), the cables' swing angles and the energy.

    Notes
    -----
    ``r1 = (x, y, 0) + L e1``, ``r2 = r1 + l2 e2``; kinetic energy of hook and load (with the hoisting speed)
    plus their potential energy ``g (m1 z1 + m2 z2)``: conserved with the trolley at constant velocity, no
    hoisting, no forces and no damping. The swing angle of a cable is its angle from the vertical,
    ``atan2(|e_horizontal|, -e_z)``. Written out on scalars (every output of every step): the directions and
    rates of :func:`_cable`, the same numbers.
    """
    x, dx, y, dy, a1, da1, b1, db1, a2, da2, b2, db2, big_l, dl1 = state[:DL1 + 1]
    m1, m2, l2 = p.m1, p.m2, p.l2
    sin, cos = math.sin, math.cos
    sa1, ca1, sb1, cb1 = sin(a1), cos(a1), sin(b1), cos(b1)
    sa2, ca2, sb2, cb2 = sin(a2), cos(a2), sin(b2), cos(b2)
    e10, e12, e20, e22 = sa1 * cb1, -ca1 * cb1, sa2 * cb2, -ca2 * cb2
    s1, s2 = cb1 * da1, cb2 * da2
    x1, y1, z1 = x + big_l * e10, y + big_l * sb1, big_l * e12
    x2, y2, z2 = x1 + l2 * e20, y1 + l2 * sb2, z1 + l2 * e22
    # e' = s u + b' v, u = (cos a, 0, sin a), v = (-sin a sin b, cos b, cos a sin b)
    vx1 = dx + dl1 * e10 + big_l * (s1 * ca1 + db1 * (-sa1 * sb1))
    vy1 = dy + dl1 * sb1 + big_l * (db1 * cb1)
    vz1 = dl1 * e12 + big_l * (s1 * sa1 + db1 * (ca1 * sb1))
    vx2 = vx1 + l2 * (s2 * ca2 + db2 * (-sa2 * sb2))
    vy2 = vy1 + l2 * (db2 * cb2)
    vz2 = vz1 + l2 * (s2 * sa2 + db2 * (ca2 * sb2))
    kinetic = 0.5 * (m1 * (vx1 * vx1 + vy1 * vy1 + vz1 * vz1) + m2 * (vx2 * vx2 + vy2 * vy2 + vz2 * vz2))
    return (x1, y1, z1, x2, y2, z2, math.atan2(math.sqrt(e10 * e10 + sb1 * sb1), -e12),
            math.atan2(math.sqrt(e20 * e20 + sb2 * sb2), -e22), kinetic + p.g * (m1 * z1 + m2 * z2))


def _swing_tangent(e, te):
    """The change of :func:`_swing` along ``te``: ``d atan2(h, -ez)`` with ``h = |e_horizontal|``."""
    h = math.sqrt(e[0] * e[0] + e[1] * e[1])
    if h == 0.0:  # hanging straight down: the swing angle has a kink (|.|), no derivative; 0 by convention
        return 0.0
    th = (e[0] * te[0] + e[1] * te[1]) / h
    return (-e[2] * th + h * te[2]) / (h * h + e[2] * e[2])


def outputs_tangent(state, p, seed):
    """The derivative of :func:`outputs` along ``seed`` (a change of the 14-element ``state``), exactly."""
    x, dx, y, dy = state[X:DY + 1]
    big_l, dl1, m1, m2, l2 = state[L1], state[DL1], p.m1, p.m2, p.l2
    tx, tdx, ty, tdy = seed[X:DY + 1]
    tl, tdl = seed[L1], seed[DL1]
    one, two = _cable(*state[A1:DB1 + 1]), _cable(*state[A2:DB2 + 1])
    _, _, e1, _, _, _, de1, _, _ = one
    _, _, e2, _, _, _, de2, _, _ = two
    _, _, te1, _, _, _, tde1, _, _ = _cable_tangent(one, *state[A1:DB1 + 1], *seed[A1:DB1 + 1])
    _, _, te2, _, _, _, tde2, _, _ = _cable_tangent(two, *state[A2:DB2 + 1], *seed[A2:DB2 + 1])
    tr1 = (tx + tl * e1[0] + big_l * te1[0], ty + tl * e1[1] + big_l * te1[1], tl * e1[2] + big_l * te1[2])
    tr2 = tuple(tr1[i] + l2 * te2[i] for i in range(3))
    v1 = (dx + dl1 * e1[0] + big_l * de1[0], dy + dl1 * e1[1] + big_l * de1[1], dl1 * e1[2] + big_l * de1[2])
    v2 = (v1[0] + l2 * de2[0], v1[1] + l2 * de2[1], v1[2] + l2 * de2[2])
    tv0 = (tdx, tdy, 0.0)
    tv1 = tuple(tv0[i] + tdl * e1[i] + dl1 * te1[i] + tl * de1[i] + big_l * tde1[i] for i in range(3))
    tv2 = tuple(tv1[i] + l2 * tde2[i] for i in range(3))
    tkinetic = m1 * _dot(v1, tv1) + m2 * _dot(v2, tv2)
    return tr1 + tr2 + (_swing_tangent(e1, te1), _swing_tangent(e2, te2), tkinetic + p.g * (m1 * tr1[2] + m2 * tr2[2]))


def swing_stepper(p):
    """:func:`rk4_step` when the cable is at rest and nothing but the trolley acts: the same numbers, faster.

    Returns ``step(state, ux, uy, dt)`` with the constants of ``p`` bound once. The accelerations are those of
    :func:`angular_accelerations` less its terms that vanish here (hoisting, forces, damping) and its products with
    the frames' zero components, written out on scalars.
    """
    mu, m2, l2, g = p.m1 + p.m2, p.m2, p.l2, p.g
    m2l2, mug = m2 * l2, -mu * g
    sin, cos = math.sin, math.cos

    def accelerations(a1, da1, b1, db1, a2, da2, b2, db2, ux, uy, big_l):
        sa1, ca1, sb1, cb1 = sin(a1), cos(a1), sin(b1), cos(b1)
        sa2, ca2, sb2, cb2 = sin(a2), cos(a2), sin(b2), cos(b2)
        e10, e12 = sa1 * cb1, -ca1 * cb1
        v10, v12 = -sa1 * sb1, ca1 * sb1
        e20, e22 = sa2 * cb2, -ca2 * cb2
        v20, v22 = -sa2 * sb2, ca2 * sb2
        aa, ab, bb = da1 * da1 * cb1, 2.0 * da1 * db1 * sb1, db1 * db1
        k10, k11, k12 = -aa * sa1 - ab * ca1 - bb * e10, -bb * sb1, aa * ca1 - ab * sa1 - bb * e12
        aa, ab, bb = da2 * da2 * cb2, 2.0 * da2 * db2 * sb2, db2 * db2
        k20, k21, k22 = -aa * sa2 - ab * ca2 - bb * e20, -bb * sb2, aa * ca2 - ab * sa2 - bb * e22
        acc0, acc1, acc2 = ux + big_l * k10, uy + big_l * k11, big_l * k12
        g10, g11, g12 = -mu * acc0 - m2l2 * k20, -mu * acc1 - m2l2 * k21, mug - mu * acc2 - m2l2 * k22
        g20, g21, g22 = -acc0 - l2 * k20, -acc1 - l2 * k21, -g - acc2 - l2 * k22
        r10 = ca1 * g10 + sa1 * g12
        r11 = v10 * g10 + cb1 * g11 + v12 * g12
        r20 = ca2 * g20 + sa2 * g22
        r21 = v20 * g20 + cb2 * g21 + v22 * g22
        c11, c12 = ca1 * ca2 + sa1 * sa2, ca1 * v20 + sa1 * v22
        c21, c22 = v10 * ca2 + v12 * sa2, v10 * v20 + cb1 * cb2 + v12 * v22
        s11 = mu - m2 * (c11 * c11 + c12 * c12)  # _solve, written out
        s12 = -m2 * (c11 * c21 + c12 * c22)
        s22 = mu - m2 * (c21 * c21 + c22 * c22)
        h1 = r10 - m2 * (c11 * r20 + c12 * r21)
        h2 = r11 - m2 * (c21 * r20 + c22 * r21)
        det = (s11 * s22 - s12 * s12) * big_l
        p1 = (s22 * h1 - s12 * h2) / det
        p2 = (s11 * h2 - s12 * h1) / det
        return (p1 / cb1, p2, (r20 - big_l * (c11 * p1 + c21 * p2)) / l2 / cb2,
                (r21 - big_l * (c12 * p1 + c22 * p2)) / l2)

    def step(state, ux, uy, dt):
        x, vx, y, vy, a1, w1, b1, z1, a2, w2, b2, z2, big_l, _ = state
        h2 = 0.5 * dt
        k1 = accelerations(a1, w1, b1, z1, a2, w2, b2, z2, ux, uy, big_l)
        w1b, z1b, w2b, z2b = w1 + h2 * k1[0], z1 + h2 * k1[1], w2 + h2 * k1[2], z2 + h2 * k1[3]
        k2 = accelerations(a1 + h2 * w1, w1b, b1 + h2 * z1, z1b, a2 + h2 * w2, w2b, b2 + h2 * z2, z2b, ux, uy, big_l)
        w1c, z1c, w2c, z2c = w1 + h2 * k2[0], z1 + h2 * k2[1], w2 + h2 * k2[2], z2 + h2 * k2[3]
        k3 = accelerations(a1 + h2 * w1b, w1c, b1 + h2 * z1b, z1c, a2 + h2 * w2b, w2c, b2 + h2 * z2b, z2c, ux, uy,
                           big_l)
        w1d, z1d, w2d, z2d = w1 + dt * k3[0], z1 + dt * k3[1], w2 + dt * k3[2], z2 + dt * k3[3]
        k4 = accelerations(a1 + dt * w1c, w1d, b1 + dt * z1c, z1d, a2 + dt * w2c, w2d, b2 + dt * z2c, z2d, ux, uy,
                           big_l)
        s = dt / 6.0
        return (x + dt * vx + h2 * dt * ux, vx + dt * ux, y + dt * vy + h2 * dt * uy, vy + dt * uy,
                a1 + s * (w1 + 2.0 * w1b + 2.0 * w1c + w1d), w1 + s * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
                b1 + s * (z1 + 2.0 * z1b + 2.0 * z1c + z1d), z1 + s * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
                a2 + s * (w2 + 2.0 * w2b + 2.0 * w2c + w2d), w2 + s * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]),
                b2 + s * (z2 + 2.0 * z2b + 2.0 * z2c + z2d), z2 + s * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]),
                big_l, 0.0)

    return step
