"""The crane's equations derived symbolically (sympy) from the Lagrangian of eqs (4)-(7): the independent reference
that test_equations.py holds the plant's code to and that test_fmus, test_plant and test_reproduce integrate.

The derivations run on first use, not when the module is imported (every test process collects its importers):
``ACCEL``, ``INPUT_GAIN`` (eqs (8)-(9)) and ``EXT_ACCEL`` (hoisting, forces, damping) are attributes derived then.
"""

import functools
from types import SimpleNamespace

import pytest

sympy = pytest.importorskip("sympy")

t = sympy.symbols("t")
m1, m2, l1, l2, g, u = sympy.symbols("m1 m2 l1 l2 g u", positive=True)
xt = sympy.Function("x")(t)
th1 = sympy.Function("theta1")(t)
th2 = sympy.Function("theta2")(t)


def _lagrange_equations():
    """Euler-Lagrange equations for theta1, theta2 with the trolley motion x(t) prescribed."""
    x1, y1 = xt + l1 * sympy.sin(th1), -l1 * sympy.cos(th1)  # eq (4)
    x2, y2 = x1 + l2 * sympy.sin(th2), y1 - l2 * sympy.cos(th2)  # eq (5)
    T = (m1 * (x1.diff(t) ** 2 + y1.diff(t) ** 2) + m2 * (x2.diff(t) ** 2 + y2.diff(t) ** 2)) / 2  # eq (6)
    V = g * (m1 * y1 + m2 * y2)  # eq (7)
    L = T - V
    eqs = [sympy.simplify(L.diff(q.diff(t)).diff(t) - L.diff(q)) for q in (th1, th2)]
    return [e.subs(xt.diff(t, 2), u) for e in eqs]


a1, a2, w1, w2, dd1, dd2 = sympy.symbols("a1 a2 w1 w2 dd1 dd2")


def plain(expr):
    """Replace theta(t) and its derivatives by plain symbols."""
    return expr.subs({th1.diff(t, 2): dd1, th2.diff(t, 2): dd2}).subs(
        {th1.diff(t): w1, th2.diff(t): w2}).subs({th1: a1, th2: a2})


@functools.cache
def paper():
    """``EQS``, ``SOLUTION``, ``ACCEL``, ``INPUT_GAIN``: eqs (8)-(9) derived, solved for the angular accelerations, and
    the accelerations and their input gains (b2, b3 of eq (11)) as functions, from the derivation alone."""
    eqs = _lagrange_equations()
    solution = sympy.solve([plain(e) for e in eqs], [dd1, dd2], dict=True)[0]
    accel = sympy.lambdify((a1, w1, a2, w2, u, m1, m2, l1, l2, g), (solution[dd1], solution[dd2]))
    gain = sympy.lambdify((a1, w1, a2, w2, m1, m2, l1, l2, g), [sympy.diff(solution[d], u) for d in (dd1, dd2)])
    return SimpleNamespace(EQS=eqs, SOLUTION=solution, ACCEL=accel, INPUT_GAIN=gain)


def __getattr__(name):
    """``EQS``, ``SOLUTION``, ``ACCEL``, ``INPUT_GAIN``, ``EXT`` and ``EXT_ACCEL``, derived on first use."""
    if name in ("EQS", "SOLUTION", "ACCEL", "INPUT_GAIN"):
        return getattr(paper(), name)
    if name in ("EXT", "EXT_ACCEL"):
        return getattr(extended(), name)
    raise AttributeError(name)


# --- the extended plant: hoisting l1(t), horizontal forces, joint damping --------------------

F1, F2, c1, c2 = sympy.symbols("F1 F2 c1 c2", real=True)
L = sympy.Function("L")(t)
dL, ddL = sympy.symbols("dL ddL", real=True)


def _extended_equations():
    """Euler-Lagrange equations with l1 = L(t), the forces' virtual work and Rayleigh's dissipation function.

    ``d/dt dT/dq' - dT/dq + dV/dq = Q_F - dD/dq'`` with ``Q_F = F1 dx1/dq + F2 dx2/dq`` and
    ``D = (c1 theta1'^2 + c2 (theta2' - theta1')^2) / 2``.
    """
    x1, y1 = xt + L * sympy.sin(th1), -L * sympy.cos(th1)
    x2, y2 = x1 + l2 * sympy.sin(th2), y1 - l2 * sympy.cos(th2)
    T = (m1 * (x1.diff(t) ** 2 + y1.diff(t) ** 2) + m2 * (x2.diff(t) ** 2 + y2.diff(t) ** 2)) / 2
    V = g * (m1 * y1 + m2 * y2)
    D = (c1 * th1.diff(t) ** 2 + c2 * (th2.diff(t) - th1.diff(t)) ** 2) / 2
    lagrangian = T - V
    eqs = []
    for q in (th1, th2):
        forces = F1 * x1.diff(q) + F2 * x2.diff(q) - D.diff(q.diff(t))
        eqs.append(lagrangian.diff(q.diff(t)).diff(t) - lagrangian.diff(q) - forces)
    subs = {xt.diff(t, 2): u, L.diff(t, 2): ddL}
    eqs = [plain(e.subs(subs)).subs(L.diff(t), dL).subs(L, l1) for e in eqs]
    return [sympy.expand(e) for e in eqs]  # the trolley's speed x'(t) cancels


def solve_linear(eqs):
    """``(dd1, dd2)`` from the two equations, linear in them, by Cramer's rule."""
    a, b = sympy.linear_eq_to_matrix(eqs, [dd1, dd2])
    det = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    return (b[0] * a[1, 1] - a[0, 1] * b[1]) / det, (a[0, 0] * b[1] - a[1, 0] * b[0]) / det


@functools.cache
def extended():
    """``EXT``, ``EXT_ACCEL``: the extended equations and their angular accelerations as a function."""
    ext = _extended_equations()
    return SimpleNamespace(EXT=ext, EXT_ACCEL=sympy.lambdify((a1, w1, a2, w2, u, m1, m2, l1, l2, g, dL, ddL, F1, F2,
                                                              c1, c2), solve_linear(ext)))
