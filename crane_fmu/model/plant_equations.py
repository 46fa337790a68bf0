"""The crane's equations of motion: eqs (4)-(9), extended by hoisting, horizontal forces and damping.

The swing state is ``(x, dx, theta1, dtheta1, theta2, dtheta2)`` in SI units;
with hoisting it continues with the main cable length and its rate ``(l1, dl1)``
(the positions below name them). The input is the trolley acceleration
``u = x''`` [m/s2]. Angles are measured from the downward vertical, positive in
+x direction (Fig. 3).

Beyond the paper (each term vanishes at its default, leaving eqs (8)-(9)):
the hoist acceleration ``l1''`` (positive lowers the hook), horizontal forces
``F1`` on the hook and ``F2`` on the payload, viscous damping ``c1`` at the
trolley joint and ``c2`` at the hook joint. Plain functions of (state, input,
parameters); the drive and its limits are in :mod:`.plant_limits`, the FMU
kind in :mod:`.plant`.
"""

import math

# positions in the swing-and-hoist state
X, DX, THETA1, DTHETA1, THETA2, DTHETA2, L1, DL1 = range(8)
SWING = slice(X, DTHETA2 + 1)

NO_LOAD = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # (dl1, ddl1, F1, F2, c1, c2): the paper's model


def angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p, l1=None, load=NO_LOAD):
    """Solve the Lagrange equations (8) and (9), extended, for the angular accelerations.

    Parameters
    ----------
    theta1, dtheta1, theta2, dtheta2 : float
        Swing angles [rad] and rates [rad/s].
    u : float
        Trolley acceleration [m/s2].
    p : PlantParameters
        Masses, cable lengths and gravity.
    l1 : float, optional
        The main cable's length now [m] (default ``p.l1``).
    load : tuple
        ``(dl1, ddl1, F1, F2, c1, c2)``: the main cable's rate [m/s] and
        acceleration [m/s2], the horizontal forces on hook and payload [N], the
        joint damping coefficients [N m s/rad]; :data:`NO_LOAD` is the paper's model.

    Returns
    -------
    (float, float)
        ``(ddtheta1, ddtheta2)`` [rad/s2].

    Notes
    -----
    With ``d = theta1 - theta2``, ``L = l1(t)``, the damping torques
    ``Q1 = -c1 w1 + c2 (w2 - w1)``, ``Q2 = -c2 (w2 - w1)`` and ``mu = m1 + m2``, the
    Lagrange equations of eqs (4)-(7) with a time-varying ``L`` (derived symbolically
    in ``tests/test_equations.py``), eq (8) divided by ``L`` and eq (9) by ``m2 l2``, are::

        mu L dd1 + m2 l2 cos(d) dd2 = -mu (u cos th1 + g sin th1) - m2 l2 w2^2 sin d
                                      - 2 mu L' w1 + (F1 + F2) cos th1 + Q1 / L
        L cos(d) dd1 + l2 dd2 = -u cos th2 - g sin th2 + L w1^2 sin d
                                - L'' sin d - 2 L' w1 cos d + (F2 cos th2 + Q2 / l2) / m2

    With ``L' = L'' = F1 = F2 = c1 = c2 = 0`` these are eqs (8) and (9). The
    determinant ``L l2 (m1 + m2 sin^2 d)`` is positive for m1 > 0, and dividing (9)
    by m2 keeps the case m2 = 0 regular (then F2 and c2 must be 0).
    """
    m1m2 = p.m1 + p.m2
    l2, g = p.l2, p.g
    big_l = p.l1 if l1 is None else l1
    dl1, ddl1, f1, f2, c1, c2 = load
    s1, co1 = math.sin(theta1), math.cos(theta1)
    s2, co2 = math.sin(theta2), math.cos(theta2)
    d = theta1 - theta2
    sd, cd = math.sin(d), math.cos(d)
    q1 = -c1 * dtheta1 + c2 * (dtheta2 - dtheta1)
    r1 = (-m1m2 * (u * co1 + g * s1) - p.m2 * l2 * dtheta2 * dtheta2 * sd
          + (-2.0 * m1m2 * dl1 * dtheta1 + (f1 + f2) * co1 + q1 / big_l))
    r2 = -u * co2 - g * s2 + big_l * dtheta1 * dtheta1 * sd + (-ddl1 * sd - 2.0 * dl1 * dtheta1 * cd)
    if p.m2 > 0:
        r2 += (f2 * co2 - c2 * (dtheta2 - dtheta1) / l2) / p.m2
    a, b = m1m2 * big_l, p.m2 * l2 * cd
    c, e = big_l * cd, l2
    det = a * e - b * c
    return (e * r1 - b * r2) / det, (a * r2 - c * r1) / det


def accelerations_tangent(theta1, dtheta1, theta2, dtheta2, u, p, l1, load, seed):
    """:func:`angular_accelerations` and their directional derivative along ``seed``, exactly.

    Parameters
    ----------
    theta1, dtheta1, theta2, dtheta2, u, p, l1, load
        As for :func:`angular_accelerations`.
    seed : tuple
        The direction: the changes of ``(theta1, dtheta1, theta2, dtheta2, u, l1, dl1, ddl1, F1, F2)``
        (``l1`` counts only when given; the damping is a parameter).

    Returns
    -------
    ((float, float), (float, float))
        ``(ddtheta1, ddtheta2)`` and their derivative along ``seed``.

    Notes
    -----
    Forward-mode differentiation by hand of the two equations of :func:`angular_accelerations`,
    ``M(q, L) dd = r``: ``M dd' = r' - M' dd``, solved with the same determinant.
    """
    dd1, dd2 = angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p, l1, load)
    t1, tw1, t2, tw2, tu, tl, tdl, tddl, tf1, tf2 = seed
    m1m2, m2l2 = p.m1 + p.m2, p.m2 * p.l2
    l2, g = p.l2, p.g
    big_l = p.l1 if l1 is None else l1
    tl = 0.0 if l1 is None else tl
    dl1, ddl1, f1, f2, c1, c2 = load
    s1, co1 = math.sin(theta1), math.cos(theta1)
    s2, co2 = math.sin(theta2), math.cos(theta2)
    d, td = theta1 - theta2, t1 - t2
    sd, cd = math.sin(d), math.cos(d)
    q1 = -c1 * dtheta1 + c2 * (dtheta2 - dtheta1)
    tq1 = -c1 * tw1 + c2 * (tw2 - tw1)
    tr1 = (-m1m2 * (tu * co1 + (g * co1 - u * s1) * t1) - m2l2 * dtheta2 * (2.0 * tw2 * sd + dtheta2 * cd * td)
           - 2.0 * m1m2 * (tdl * dtheta1 + dl1 * tw1) + (tf1 + tf2) * co1 - (f1 + f2) * s1 * t1
           + tq1 / big_l - q1 * tl / (big_l * big_l))
    tr2 = (-tu * co2 + (u * s2 - g * co2) * t2
           + dtheta1 * (tl * dtheta1 * sd + big_l * (2.0 * tw1 * sd + dtheta1 * cd * td))
           - tddl * sd - ddl1 * cd * td - 2.0 * (tdl * dtheta1 * cd + dl1 * tw1 * cd - dl1 * dtheta1 * sd * td))
    if p.m2 > 0:
        tr2 += (tf2 * co2 - f2 * s2 * t2 - c2 * (tw2 - tw1) / l2) / p.m2
    a, b = m1m2 * big_l, m2l2 * cd
    c, e = big_l * cd, l2
    # M' dd moved to the right-hand side; M' = [[m1m2 L', -m2 l2 sin(d) d'], [L' cos(d) - L sin(d) d', 0]]
    rhs1 = tr1 - m1m2 * tl * dd1 + m2l2 * sd * td * dd2
    rhs2 = tr2 - (tl * cd - big_l * sd * td) * dd1
    det = a * e - b * c
    return (dd1, dd2), ((e * rhs1 - b * rhs2) / det, (a * rhs2 - c * rhs1) / det)


def paper_stepper(p):
    """:func:`rk4_step` of the 8-element state when l1 is at rest and nothing but u acts: the same numbers, faster.

    Returns ``step(state, u, dt)`` with the constants of ``p`` bound once. The accelerations are
    eqs (8)-(9) with the arithmetic of :func:`angular_accelerations` less its terms that vanish here.
    """
    m1m2, m2l2, l2, g = p.m1 + p.m2, p.m2 * p.l2, p.l2, p.g
    sin, cos = math.sin, math.cos

    def accelerations(theta1, dtheta1, theta2, dtheta2, u, big_l, a, al2):
        d = theta1 - theta2
        sd, cd = sin(d), cos(d)
        r1 = -m1m2 * (u * cos(theta1) + g * sin(theta1)) - m2l2 * dtheta2 * dtheta2 * sd
        r2 = -u * cos(theta2) - g * sin(theta2) + big_l * dtheta1 * dtheta1 * sd
        b, c = m2l2 * cd, big_l * cd
        det = al2 - b * c
        return (l2 * r1 - b * r2) / det, (a * r2 - c * r1) / det

    def step(state, u, dt):
        x, v, a1, w1, a2, w2, big_l, _ = state
        a = m1m2 * big_l
        al2 = a * l2
        h2 = 0.5 * dt
        k1a, k1b = accelerations(a1, w1, a2, w2, u, big_l, a, al2)
        w1b, w2b = w1 + h2 * k1a, w2 + h2 * k1b
        k2a, k2b = accelerations(a1 + h2 * w1, w1b, a2 + h2 * w2, w2b, u, big_l, a, al2)
        w1c, w2c = w1 + h2 * k2a, w2 + h2 * k2b
        k3a, k3b = accelerations(a1 + h2 * w1b, w1c, a2 + h2 * w2b, w2c, u, big_l, a, al2)
        w1d, w2d = w1 + dt * k3a, w2 + dt * k3b
        k4a, k4b = accelerations(a1 + dt * w1c, w1d, a2 + dt * w2c, w2d, u, big_l, a, al2)
        s = dt / 6.0
        return (x + dt * v + h2 * dt * u, v + dt * u,
                a1 + s * (w1 + 2.0 * w1b + 2.0 * w1c + w1d), w1 + s * (k1a + 2.0 * k2a + 2.0 * k3a + k4a),
                a2 + s * (w2 + 2.0 * w2b + 2.0 * w2c + w2d), w2 + s * (k1b + 2.0 * k2b + 2.0 * k3b + k4b),
                big_l, 0.0)

    return step


def derivative(state, u, p, hoist=0.0, forces=(0.0, 0.0, 0.0, 0.0)):
    """Time derivative of the state for a held trolley acceleration ``u`` (and hoist acceleration).

    Parameters
    ----------
    state : tuple
        ``(x, dx, theta1, dtheta1, theta2, dtheta2)``, or with ``(l1, dl1)`` appended.
    hoist : float
        ``l1''`` [m/s2]; needs the 8-element state.
    forces : tuple
        ``(F1, F2, c1, c2)``.

    Notes
    -----
    ``x'' = u`` by definition of the input (eq 12: f1 = 0, b1 = 1); the angular
    accelerations come from eqs (8)-(9), see :func:`angular_accelerations`.
    """
    _, dx, theta1, dtheta1, theta2, dtheta2 = state[SWING]
    if len(state) == 6:
        dd1, dd2 = angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p, None, (0.0, 0.0, *forces))
        return (dx, u, dtheta1, dd1, dtheta2, dd2)
    l1, dl1 = state[L1], state[DL1]
    dd1, dd2 = angular_accelerations(theta1, dtheta1, theta2, dtheta2, u, p, l1, (dl1, hoist, *forces))
    return (dx, u, dtheta1, dd1, dtheta2, dd2, dl1, hoist)


def rk4_step(state, u, dt, p, hoist=0.0, forces=(0.0, 0.0, 0.0, 0.0)):
    """Advance ``state`` (6 or 8 elements, see :func:`derivative`) by ``dt``: one classical RK4 step, inputs held."""
    x, v, a1, w1, a2, w2 = state[SWING]
    h2 = 0.5 * dt
    if len(state) == 8:
        big_l, dl = state[L1], state[DL1]
        # l1'' = hoist is constant over the step: l1 and its rate are exact at every stage
        ls = (big_l, big_l + h2 * dl + 0.5 * hoist * h2 * h2, big_l + dt * dl + 0.5 * hoist * dt * dt)
        dls = (dl, dl + h2 * hoist, dl + dt * hoist)
    else:
        ls, dls = (None, None, None), (0.0, 0.0, 0.0)
    f = [(dls[i], hoist, *forces) for i in range(3)]
    k1 = angular_accelerations(a1, w1, a2, w2, u, p, ls[0], f[0])
    k2 = angular_accelerations(a1 + h2 * w1, w1 + h2 * k1[0], a2 + h2 * w2, w2 + h2 * k1[1], u, p, ls[1], f[1])
    w1b, w2b = w1 + h2 * k1[0], w2 + h2 * k1[1]
    w1c, w2c = w1 + h2 * k2[0], w2 + h2 * k2[1]
    k3 = angular_accelerations(a1 + h2 * w1b, w1c, a2 + h2 * w2b, w2c, u, p, ls[1], f[1])
    w1d, w2d = w1 + dt * k3[0], w2 + dt * k3[1]
    k4 = angular_accelerations(a1 + dt * w1c, w1d, a2 + dt * w2c, w2d, u, p, ls[2], f[2])
    s = dt / 6.0
    # x'' = u is constant over the step, so RK4 integrates x exactly.
    new = (
        x + dt * v + h2 * dt * u,
        v + dt * u,
        a1 + s * (w1 + 2.0 * w1b + 2.0 * w1c + w1d),
        w1 + s * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        a2 + s * (w2 + 2.0 * w2b + 2.0 * w2c + w2d),
        w2 + s * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
    )
    return new if len(state) == 6 else new + (ls[2], dls[2])


def linearisation(p):
    """The swing dynamics linearised about the hanging equilibrium: ``q'' = -W q - w u``, ``q = (theta1, theta2)``.

    Returns
    -------
    (W, w)
        ``W`` (2x2, lists of rows) [1/s2] and ``w`` (2) [rad/m].

    Notes
    -----
    Eqs (8)-(9) divided as in :func:`angular_accelerations`, with ``sin q = q``,
    ``cos q = 1`` and the quadratic rate terms dropped, give ``N q'' + K q = -n u`` with
    ``N = [[(m1+m2) l1, m2 l2], [l1, l2]]``, ``K = diag((m1+m2) g, g)``,
    ``n = (m1+m2, 1)``; ``det N = m1 l1 l2 > 0``.
    """
    m12 = p.m1 + p.m2
    a, b, c, d = m12 * p.l1, p.m2 * p.l2, p.l1, p.l2
    det = a * d - b * c
    inv = ((d / det, -b / det), (-c / det, a / det))  # N^-1
    big_w = [[inv[i][0] * m12 * p.g, inv[i][1] * p.g] for i in range(2)]
    small_w = [inv[i][0] * m12 + inv[i][1] for i in range(2)]
    return big_w, small_w


MAX_SUBSTEPS = 10_000_000  # per communication step: about a minute of computing


def substeps(step, max_substep):
    """Number of equal RK4 sub-steps no longer than ``max_substep`` covering ``step``.

    Raises
    ------
    ValueError
        If the step is not positive and finite, or needs more than
        :data:`MAX_SUBSTEPS` sub-steps (a host must never hang in doStep).
    """
    if not (step > 0 and math.isfinite(step)):
        raise ValueError(f"communication step must be > 0 and finite, got {step!r}")
    # The 1e-9 slack keeps h = 1 ms with max_substep = 1 ms at one sub-step
    # despite rounding in h.
    n = step / max_substep - 1e-9
    if not n <= MAX_SUBSTEPS:
        raise ValueError(f"communication step {step!r} s needs more than {MAX_SUBSTEPS} RK4 sub-steps of at most "
                         f"max_substep = {max_substep!r} s")
    return max(1, math.ceil(n))


def advance(state, u, step, max_substep, p):
    """Integrate the paper's plant over one communication step with u held (zero-order hold)."""
    n = substeps(step, max_substep)
    dt = step / n
    for _ in range(n):
        state = rk4_step(state, u, dt, p)
    return state


def energy(state, p):
    """Kinetic plus potential energy of hook and payload [J], eqs (6)-(7)."""
    return outputs(state, p)[-1]


def outputs(state, p):
    """The swing state, hook and payload positions ``x1, y1, x2, y2`` and the energy.

    Notes
    -----
    Positions from eqs (4)-(5) with the main cable's length now (``state[L1]``,
    else ``p.l1``); kinetic energy eq (6), including the hoisting speed
    ``state[DL1]``, plus potential energy eq (7). The trolley's own mass is not
    part of the model, so with ``u = 0`` (constant trolley velocity), no
    hoisting, no forces and no damping this energy is conserved.
    """
    x, dx, theta1, dtheta1, theta2, dtheta2 = state[SWING]
    l1, dl1 = (state[L1], state[DL1]) if len(state) > DL1 else (p.l1, 0.0)
    m1, m2, l2 = p.m1, p.m2, p.l2
    s1, c1, s2, c2 = math.sin(theta1), math.cos(theta1), math.sin(theta2), math.cos(theta2)
    x1, y1 = x + l1 * s1, -l1 * c1
    x2, y2 = x1 + l2 * s2, y1 - l2 * c2
    vx1, vy1 = dx + l1 * dtheta1 * c1 + dl1 * s1, l1 * dtheta1 * s1 - dl1 * c1
    vx2, vy2 = vx1 + l2 * dtheta2 * c2, vy1 + l2 * dtheta2 * s2
    kinetic = 0.5 * (m1 * (vx1 * vx1 + vy1 * vy1) + m2 * (vx2 * vx2 + vy2 * vy2))
    return (x, dx, theta1, dtheta1, theta2, dtheta2, x1, y1, x2, y2,
            kinetic + p.g * (m1 * y1 + m2 * y2))


def outputs_tangent(state, p, seed):
    """The derivative of :func:`outputs` along ``seed`` (a change of the 8-element ``state``), exactly.

    Notes
    -----
    Eqs (4)-(7) as in :func:`outputs`, differentiated by hand (forward mode).
    """
    x, dx, theta1, dtheta1, theta2, dtheta2, l1, dl1 = state[:DL1 + 1]
    tx, tdx, t1, tw1, t2, tw2, tl, tdl = seed[:DL1 + 1]
    m1, m2, l2 = p.m1, p.m2, p.l2
    s1, c1, s2, c2 = math.sin(theta1), math.cos(theta1), math.sin(theta2), math.cos(theta2)
    tx1, ty1 = tx + tl * s1 + l1 * c1 * t1, -tl * c1 + l1 * s1 * t1
    tx2, ty2 = tx1 + l2 * c2 * t2, ty1 + l2 * s2 * t2
    vx1, vy1 = dx + l1 * dtheta1 * c1 + dl1 * s1, l1 * dtheta1 * s1 - dl1 * c1
    vx2, vy2 = vx1 + l2 * dtheta2 * c2, vy1 + l2 * dtheta2 * s2
    tvx1 = tdx + (tl * dtheta1 + l1 * tw1) * c1 - l1 * dtheta1 * s1 * t1 + tdl * s1 + dl1 * c1 * t1
    tvy1 = (tl * dtheta1 + l1 * tw1) * s1 + l1 * dtheta1 * c1 * t1 - tdl * c1 + dl1 * s1 * t1
    tvx2 = tvx1 + l2 * (tw2 * c2 - dtheta2 * s2 * t2)
    tvy2 = tvy1 + l2 * (tw2 * s2 + dtheta2 * c2 * t2)
    tkinetic = m1 * (vx1 * tvx1 + vy1 * tvy1) + m2 * (vx2 * tvx2 + vy2 * tvy2)
    return (tx, tdx, t1, tw1, t2, tw2, tx1, ty1, tx2, ty2, tkinetic + p.g * (m1 * ty1 + m2 * ty2))
