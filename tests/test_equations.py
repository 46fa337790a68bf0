"""The model's equations against a symbolic Lagrangian derivation of eqs (4)-(7) (tests/derivation.py)."""

import functools
import math
import random

import pytest

sympy = pytest.importorskip("sympy")

from derivation import (  # noqa: E402
    F1,
    F2,
    a1,
    a2,
    c1,
    c2,
    dd1,
    dd2,
    ddL,
    dL,
    extended,
    g,
    l1,
    l2,
    m1,
    m2,
    paper,
    plain,
    solve_linear,
    u,
    w1,
    w2,
)

from crane_fmu.model import backstepping as controller  # noqa: E402
from crane_fmu.model import plant  # noqa: E402
from crane_fmu.model.parameters import PlantParameters  # noqa: E402

pytestmark = pytest.mark.quick  # no build: in the quick subset



def _random_cases(n=40, seed=1):
    rng = random.Random(seed)
    for _ in range(n):
        p = PlantParameters(m1=rng.uniform(0.5, 10), m2=rng.uniform(0.1, 10), l1=rng.uniform(0.2, 3),
                            l2=rng.uniform(0.1, 2), g=rng.uniform(1, 20))
        yield p, [rng.uniform(-1.5, 1.5) for _ in range(4)], rng.uniform(-20, 20)


def test_paper_eqs_8_9_are_the_lagrange_equations():
    """Eqs (8) and (9) as printed equal l1 resp. l2 times the Euler-Lagrange expressions."""
    eq8 = (l1 * (m1 + m2) * (u * sympy.cos(a1) + g * sympy.sin(a1) + l1 * dd1)
           + l1 * l2 * m2 * dd2 * sympy.cos(a1 - a2) + l1 * l2 * m2 * w2 ** 2 * sympy.sin(a1 - a2))
    eq9 = (l2 * m2 * u * sympy.cos(a2) + l1 * l2 * m2 * dd1 * sympy.cos(a1 - a2) + l2 ** 2 * m2 * dd2
           - l1 * l2 * m2 * w1 ** 2 * sympy.sin(a1 - a2) + l2 * m2 * g * sympy.sin(a2))
    assert sympy.simplify(eq8 - plain(paper().EQS[0])) == 0
    assert sympy.simplify(eq9 - plain(paper().EQS[1])) == 0


def test_code_accelerations_equal_symbolic_solution():
    # Both sides are double-precision evaluations of the same closed form: 1e-9 relative.
    for p, (q1, r1, q2, r2), acc in _random_cases():
        expected = paper().ACCEL(q1, r1, q2, r2, acc, p.m1, p.m2, p.l1, p.l2, p.g)
        got = plant.angular_accelerations(q1, r1, q2, r2, acc, p)
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("form", ["derived", "printed"])
def test_f_and_b_of_eq_14_against_the_derivation(form):
    """f = accelerations at u = 0 and b = d(accel)/du; only the printed b3 disagrees (sign)."""
    b_sym = [sympy.diff(paper().SOLUTION[d], u) for d in (dd1, dd2)]
    b_fn = sympy.lambdify((a1, w1, a2, w2, m1, m2, l1, l2, g), b_sym)
    for p, (q1, r1, q2, r2), _ in _random_cases():
        (f1, f2, f3), (b1, b2, b3) = controller.drift_and_input_gain(q1, r1, q2, r2, p, form)
        f_expected = paper().ACCEL(q1, r1, q2, r2, 0.0, p.m1, p.m2, p.l1, p.l2, p.g)
        b_expected = b_fn(q1, r1, q2, r2, p.m1, p.m2, p.l1, p.l2, p.g)
        assert (f1, b1) == (0.0, 1.0)
        assert (f2, f3) == pytest.approx(f_expected, rel=1e-9, abs=1e-9)
        assert b2 == pytest.approx(b_expected[0], rel=1e-9, abs=1e-12)
        if form == "derived":
            assert b3 == pytest.approx(b_expected[1], rel=1e-9, abs=1e-12)
        elif abs(b_expected[1]) > 1e-6:
            assert b3 == pytest.approx(-b_expected[1], rel=1e-9)


def test_energy_is_that_of_eqs_6_7():
    p = PlantParameters()
    state = (0.3, 0.7, 0.2, -0.4, -0.1, 0.9)
    x, dx, q1, r1, q2, r2 = state
    vx1, vy1 = dx + p.l1 * r1 * math.cos(q1), p.l1 * r1 * math.sin(q1)
    vx2, vy2 = vx1 + p.l2 * r2 * math.cos(q2), vy1 + p.l2 * r2 * math.sin(q2)
    T = 0.5 * p.m1 * (vx1 ** 2 + vy1 ** 2) + 0.5 * p.m2 * (vx2 ** 2 + vy2 ** 2)
    V = -p.g * p.l1 * p.m1 * math.cos(q1) + p.g * p.m2 * (-p.l1 * math.cos(q1) - p.l2 * math.cos(q2))
    assert plant.energy(state, p) == pytest.approx(T + V, rel=1e-12)


# --- the extended plant: hoisting l1(t), horizontal forces, joint damping --------------------



def test_extended_equations_reduce_to_eqs_8_9_without_hoisting_forces_and_damping():
    at_rest = {dL: 0, ddL: 0, F1: 0, F2: 0, c1: 0, c2: 0}
    for ext, eq in zip(extended().EXT, (plain(e) for e in paper().EQS)):
        assert sympy.trigsimp(sympy.expand(sympy.expand_trig(ext.subs(at_rest) - eq))) == 0


def test_code_accelerations_equal_the_extended_derivation():
    rng = random.Random(7)
    for p, (q1, r1, q2, r2), acc in _random_cases():
        load = (rng.uniform(-1, 1), rng.uniform(-2, 2), rng.uniform(-50, 50), rng.uniform(-50, 50),
                rng.uniform(0, 5), rng.uniform(0, 5))
        length = rng.uniform(0.3, 3)
        expected = extended().EXT_ACCEL(q1, r1, q2, r2, acc, p.m1, p.m2, length, p.l2, p.g, *load)
        got = plant.angular_accelerations(q1, r1, q2, r2, acc, p, length, load)
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-9)


# the differentiated variables of plant_equations.accelerations_tangent's seed, in its order
_SEEDED = (a1, w1, a2, w2, u, l1, dL, ddL, F1, F2)


@functools.cache
def _ext_jacobian():
    """The extended accelerations differentiated by the seeded variables (derived on first use)."""
    return sympy.lambdify((a1, w1, a2, w2, u, m1, m2, l1, l2, g, dL, ddL, F1, F2, c1, c2),
                          [[sympy.diff(e, v) for v in _SEEDED] for e in solve_linear(extended().EXT)])


def test_code_directional_derivatives_equal_the_derivation_differentiated():
    """accelerations_tangent along each unit seed against sympy's derivative of the extended derivation."""
    rng = random.Random(11)
    for p, (q1, r1, q2, r2), acc in _random_cases(20):
        load = (rng.uniform(-1, 1), rng.uniform(-2, 2), rng.uniform(-50, 50), rng.uniform(-50, 50),
                rng.uniform(0, 5), rng.uniform(0, 5))
        length = rng.uniform(0.3, 3)
        expected = _ext_jacobian()(q1, r1, q2, r2, acc, p.m1, p.m2, length, p.l2, p.g, *load)
        for k in range(len(_SEEDED)):
            seed = tuple(float(j == k) for j in range(len(_SEEDED)))
            _, got = plant.accelerations_tangent(q1, r1, q2, r2, acc, p, length, load, seed)
            assert got == pytest.approx((expected[0][k], expected[1][k]), rel=1e-9, abs=1e-9), _SEEDED[k]
