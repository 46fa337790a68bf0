"""Linear analysis about the hanging equilibrium: natural frequencies and closed-loop poles."""

import math

import numpy as np

from crane_fmu.model import backstepping, plant


def natural_frequencies(p):
    """The two natural frequencies [Hz] of the linearised free double pendulum, low first.

    Notes
    -----
    Eqs (8)-(9) linearised about theta1 = theta2 = 0 with u = 0 give
    ``M q'' + K q = 0`` with ``M = [[(m1+m2) l1^2, m2 l1 l2], [m2 l1 l2, m2 l2^2]]``
    and ``K = diag((m1+m2) g l1, m2 g l2)``; the frequencies solve ``det(K - w^2 M) = 0``.
    """
    m12 = p.m1 + p.m2
    mass = np.array([[m12 * p.l1 ** 2, p.m2 * p.l1 * p.l2], [p.m2 * p.l1 * p.l2, p.m2 * p.l2 ** 2]])
    stiffness = np.diag([m12 * p.g * p.l1, p.m2 * p.g * p.l2])
    omega_sq = np.linalg.eigvals(np.linalg.solve(mass, stiffness))
    return sorted(float(math.sqrt(w.real) / (2 * math.pi)) for w in omega_sq)


def closed_loop_jacobian(p, gains, eps=1e-6):
    """Jacobian of the continuous-time closed loop ``s' = F(s, control(s))`` at the target.

    Central differences of the model's own functions about ``x = x_d`` and zero
    swing; exact to about ``eps^2`` relative.
    """
    target = np.array([gains.x_d, 0.0, gains.theta1_d, 0.0, gains.theta2_d, 0.0])

    def field(s):
        return np.array(plant.derivative(tuple(s), backstepping.control(tuple(s), p, gains), p))

    jac = np.empty((6, 6))
    for j in range(6):
        step = np.zeros(6)
        step[j] = eps
        jac[:, j] = (field(target + step) - field(target - step)) / (2 * eps)
    return jac


def closed_loop_poles(p, gains):
    """Eigenvalues of :func:`closed_loop_jacobian` [1/s], sorted by real part (largest first)."""
    poles = np.linalg.eigvals(closed_loop_jacobian(p, gains))
    return sorted(poles, key=lambda z: -z.real)
