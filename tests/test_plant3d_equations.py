"""The spatial crane's equations (crane_fmu/model/plant3d_equations.py) against a symbolic Lagrangian derivation.

The derivation is written from the physics alone: the positions of hook and load, their kinetic and potential
energy, the forces' virtual work and Rayleigh's dissipation function of the cables' angular velocities; sympy
forms the Euler-Lagrange equations, and numpy solves them at random points. It runs on first use.
"""

import functools
import math
import random

import numpy as np
import pytest

sympy = pytest.importorskip("sympy")

from crane_fmu.model import plant3d_equations as eq3  # noqa: E402
from crane_fmu.model import plant_equations as eq2  # noqa: E402
from crane_fmu.model.parameters import PlantParameters  # noqa: E402

pytestmark = pytest.mark.quick  # no build: in the quick subset

m1, m2, l2, g = sympy.symbols("m1 m2 l2 g", positive=True)
ux, uy, dL, ddL, L0 = sympy.symbols("ux uy dL ddL L0", real=True)
F1x, F1y, F2x, F2y, c1, c2 = sympy.symbols("F1x F1y F2x F2y c1 c2", real=True)
Q = sympy.symbols("q_a1 q_b1 q_a2 q_b2", real=True)  # the angles
W = sympy.symbols("w_a1 w_b1 w_a2 w_b2", real=True)  # their rates
DD = sympy.symbols("dd_a1 dd_b1 dd_a2 dd_b2", real=True)  # their accelerations
X0, Y0, VX, VY = sympy.symbols("x y vx vy", real=True)  # the trolley's position and speed
ARGS = (*Q, *W, ux, uy, m1, m2, L0, l2, g, dL, ddL, F1x, F1y, F2x, F2y, c1, c2)


def _direction(a, b):
    return sympy.Matrix([sympy.sin(a) * sympy.cos(b), sympy.sin(b), -sympy.cos(a) * sympy.cos(b)])


def _rate(f):
    """The time derivative of ``f`` along the motion (the chain rule over every quantity that moves)."""
    moving = [*zip(Q, W), *zip(W, DD), (X0, VX), (Y0, VY), (VX, ux), (VY, uy), (L0, dL), (dL, ddL)]
    return sum((f.diff(q) * rate for q, rate in moving), sympy.S.Zero)


@functools.cache
def _derived():
    """``(M, r, eqs)``: the Euler-Lagrange equations ``eqs`` (with the trolley's speed in them) and ``M dd = r``
    at the trolley's speed 0 as numeric functions of :data:`ARGS`."""
    e1, e2 = _direction(Q[0], Q[1]), _direction(Q[2], Q[3])
    r1 = sympy.Matrix([X0, Y0, 0]) + L0 * e1
    r2 = r1 + l2 * e2
    v1, v2 = r1.applyfunc(_rate), r2.applyfunc(_rate)
    kinetic = (m1 * v1.dot(v1) + m2 * v2.dot(v2)) / 2
    potential = g * (m1 * r1[2] + m2 * r2[2])
    lagrangian = kinetic - potential
    w1, w2 = e1.cross(e1.applyfunc(_rate)), e2.cross(e2.applyfunc(_rate))  # the cables' angular velocities
    dissipation = (c1 * w1.dot(w1) + c2 * (w2 - w1).dot(w2 - w1)) / 2
    f1, f2 = sympy.Matrix([F1x, F1y, 0]), sympy.Matrix([F2x, F2y, 0])
    eqs = []
    for q, w in zip(Q, W):
        generalised = f1.dot(r1.diff(q)) + f2.dot(r2.diff(q)) - dissipation.diff(w)
        eqs.append(_rate(lagrangian.diff(w)) - lagrangian.diff(q) - generalised)
    matrix, rhs = sympy.linear_eq_to_matrix([e.subs({VX: 0, VY: 0}) for e in eqs], DD)
    return sympy.lambdify(ARGS, matrix, "numpy"), sympy.lambdify(ARGS, rhs, "numpy"), eqs


def _derived_accelerations(angles, u, p, length, load):
    """The derivation's ``(dda1, ddb1, dda2, ddb2)``, solved by numpy."""
    matrix, rhs, *_ = _derived()
    a1, da1, b1, db1, a2, da2, b2, db2 = angles
    args = (a1, b1, a2, b2, da1, db1, da2, db2, *u, p.m1, p.m2, length, p.l2, p.g, *load)
    kind = complex if any(isinstance(v, complex) for v in args) else float
    return tuple(np.linalg.solve(np.array(matrix(*args), kind), np.array(rhs(*args), kind).ravel()))


def _random_cases(n=40, seed=5):
    rng = random.Random(seed)
    for _ in range(n):
        p = PlantParameters(m1=rng.uniform(0.5, 10), m2=rng.uniform(0.1, 10), l1=1.0, l2=rng.uniform(0.1, 2),
                            g=rng.uniform(1, 20))
        angles = tuple(rng.uniform(-1.2, 1.2) if i % 2 == 0 else rng.uniform(-2, 2) for i in range(8))
        u = (rng.uniform(-5, 5), rng.uniform(-5, 5))
        length, rate = rng.uniform(0.3, 3), rng.uniform(-1, 1)
        load = (rng.uniform(-2, 2), *(rng.uniform(-50, 50) for _ in range(4)), rng.uniform(0, 5), rng.uniform(0, 5))
        yield p, angles, u, length, rate, load


def test_the_trolleys_speed_does_not_enter_the_equations():
    """Only the trolley's acceleration moves the pendulums (Galilean invariance): the equations' derivatives by the
    trolley's speed vanish at random points."""
    eqs = _derived()[2]
    args = (*ARGS, *DD, VX, VY)
    by_speed = sympy.lambdify(args, [e.diff(v) for e in eqs for v in (VX, VY)], "numpy")
    rng = random.Random(2)
    for _ in range(10):
        values = [rng.uniform(0.2, 1) for _ in range(len(args))]
        assert np.abs(by_speed(*values)).max() < 1e-12


def test_code_accelerations_equal_the_derivation():
    """Both are double-precision evaluations of the same equations, solved differently: 1e-9 relative."""
    for p, angles, u, length, rate, load in _random_cases():
        expected = _derived_accelerations(angles, u, p, length, (rate, *load))
        got = eq3.angular_accelerations(angles, *u, p, length, rate, load)
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-9)


def test_a_massless_load_is_regular():
    """m2 = 0 (then F2 and c2 are 0): the hook is a spherical pendulum and the load's cable still has a motion."""
    p = PlantParameters(m2=0.0)
    angles, load = (0.3, 0.1, -0.2, 0.4, 0.5, -0.3, 0.1, 0.2), (0.1, 3.0, -2.0, 0.0, 0.0, 0.5, 0.0)
    got = eq3.angular_accelerations(angles, 0.5, -0.7, p, 1.2, 0.3, load)
    assert all(map(math.isfinite, got))
    # the hook's own equations do not see the load: those of a spherical pendulum with the same hook
    alone = eq3.angular_accelerations(angles[:4] + (0.0,) * 4, 0.5, -0.7, p, 1.2, 0.3, load)
    assert got[:2] == pytest.approx(alone[:2], rel=1e-12)


def test_in_the_plane_it_is_the_planar_crane():
    """b1 = b2 = 0 at rest out of the plane, no y acceleration or force: the planar eqs (8)-(9) extended, and the
    out-of-plane accelerations exactly 0 (the motion stays in the plane)."""
    rng = random.Random(9)
    for p, angles, u, length, rate, load in _random_cases(20):
        a1, da1, _, _, a2, da2, _, _ = angles
        planar_load = (rate, load[0], load[1], load[3], load[5], load[6])
        dd1, dd2 = eq2.angular_accelerations(a1, da1, a2, da2, u[0], p, length, planar_load)
        spatial = (load[0], load[1], 0.0, load[3], 0.0, load[5], load[6])
        got = eq3.angular_accelerations((a1, da1, 0.0, 0.0, a2, da2, 0.0, 0.0), u[0], 0.0, p, length, rate, spatial)
        assert (got[0], got[2]) == pytest.approx((dd1, dd2), rel=1e-12, abs=1e-12 * (1 + abs(rng.random())))
        assert got[1] == 0 and got[3] == 0


CODE_SEED = ("a1", "da1", "b1", "db1", "a2", "da2", "b2", "db2", "ux", "uy", "l1", "dl1", "ddl1", "F1x", "F1y", "F2x",
             "F2y")  # accelerations_tangent's seed order


def test_code_directional_derivatives_equal_the_derivation_differentiated():
    """accelerations_tangent along each unit seed against the derivation's accelerations differentiated by the
    complex step (exact to rounding: ``Im f(x + i h) / h`` at h = 1e-30, no difference taken)."""
    h = 1e-30
    for p, angles, u, length, rate, load in _random_cases(12):
        values = (*angles, *u, length, rate, *load[:5])
        for k, name in enumerate(CODE_SEED):
            moved = [complex(v) for v in values]
            moved[k] += 1j * h
            expected = np.imag(_derived_accelerations(moved[:8], moved[8:10], p, moved[10],
                                                      (*moved[11:], *load[5:]))) / h
            seed = tuple(float(i == k) for i in range(len(CODE_SEED)))
            value, got = eq3.accelerations_tangent(angles, *u, p, length, rate, load, seed)
            assert value == eq3.angular_accelerations(angles, *u, p, length, rate, load)
            assert got == pytest.approx(tuple(expected), rel=1e-9, abs=1e-9), name


def _positions(state, p, s):
    """Hook and load positions (S1) after a time ``s`` of the state's rates held."""
    x, dx, y, dy, a1, da1, b1, db1, a2, da2, b2, db2, length, rate = state
    f1 = np.array([math.sin(a1 + s * da1) * math.cos(b1 + s * db1), math.sin(b1 + s * db1),
                   -math.cos(a1 + s * da1) * math.cos(b1 + s * db1)])
    f2 = np.array([math.sin(a2 + s * da2) * math.cos(b2 + s * db2), math.sin(b2 + s * db2),
                   -math.cos(a2 + s * da2) * math.cos(b2 + s * db2)])
    q1 = np.array([x + s * dx, y + s * dy, 0.0]) + (length + s * rate) * f1
    return q1, q1 + p.l2 * f2


def test_outputs_are_the_positions_swing_angles_and_energy_of_the_derivation():
    rng = random.Random(4)
    p = PlantParameters()
    for _ in range(10):
        state = tuple(rng.uniform(-1, 1) for _ in range(12)) + (rng.uniform(0.5, 2), rng.uniform(-1, 1))
        x, dx, y, dy, a1, da1, b1, db1, a2, da2, b2, db2, length, rate = state
        e1 = np.array([math.sin(a1) * math.cos(b1), math.sin(b1), -math.cos(a1) * math.cos(b1)])
        e2 = np.array([math.sin(a2) * math.cos(b2), math.sin(b2), -math.cos(a2) * math.cos(b2)])
        r1 = np.array([x, y, 0.0]) + length * e1
        r2 = r1 + p.l2 * e2
        # velocities by differentiating the positions numerically along the motion (central, h = 1e-6)
        (p1, p2), (n1, n2) = _positions(state, p, 1e-6), _positions(state, p, -1e-6)
        v1, v2 = (p1 - n1) / 2e-6, (p2 - n2) / 2e-6
        energy = 0.5 * (p.m1 * v1 @ v1 + p.m2 * v2 @ v2) + p.g * (p.m1 * r1[2] + p.m2 * r2[2])
        swing = [math.acos(-e[2]) for e in (e1, e2)]
        got = eq3.outputs(state, p)
        assert got[:6] == pytest.approx((*r1, *r2), rel=1e-14, abs=1e-14)
        assert got[6:8] == pytest.approx(swing, rel=1e-12)
        assert got[8] == pytest.approx(energy, rel=1e-8)
