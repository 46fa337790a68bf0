"""Writes hard_hit_60deg_plan.json: the least-time problem of crane_fmu/analysis/hard_hit_floor.py solved by IPOPT.

Needs casadi (``pip install casadi``; not a dependency of the toolkit, which solves the same problem with scipy's
SLSQP, slower). Run from the repository: ``python tests/data/hard_hit_plan_ipopt.py``. The same equations (eqs (8),
(9) of :func:`crane_fmu.model.plant_equations.angular_accelerations`), the same RK4 (2 sub-steps), grid, limits,
band and rest; started from the uncontrolled swing over 7 s.
"""

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np

from crane_fmu.analysis import hard_hit_floor as hhf
from crane_fmu.model.parameters import PlantParameters

P = PlantParameters()
START_DEG, BAND, U_MAX, V_MAX, GUESS = 60.0, math.radians(0.5), 2.0, 1.0, 7.0


def derivative(s, u):
    mu, d = P.m1 + P.m2, s[2] - s[4]
    r1 = -mu * (u * ca.cos(s[2]) + P.g * ca.sin(s[2])) - P.m2 * P.l2 * s[5] ** 2 * ca.sin(d)
    r2 = -u * ca.cos(s[4]) - P.g * ca.sin(s[4]) + P.l1 * s[3] ** 2 * ca.sin(d)
    a, b, c, e = mu * P.l1, P.m2 * P.l2 * ca.cos(d), P.l1 * ca.cos(d), P.l2
    det = a * e - b * c
    return ca.vertcat(s[1], u, s[3], (e * r1 - b * r2) / det, s[5], (a * r2 - c * r1) / det)


def rk4(s, u, dt):
    h = dt / hhf.SUBSTEPS
    for _ in range(hhf.SUBSTEPS):
        k1 = derivative(s, u)
        k2 = derivative(s + h / 2 * k1, u)
        k3 = derivative(s + h / 2 * k2, u)
        k4 = derivative(s + h * k3, u)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s


def main():
    n, m = hhf.INTERVALS, hhf.HOLD_INTERVALS
    start = [0.0, 0.0, math.radians(START_DEG), 0.0, 0.0, 0.0]
    opti = ca.Opti()
    big_t, states, u = opti.variable(), opti.variable(6, n + m + 1), opti.variable(n + m)
    opti.subject_to(states[:, 0] == start)
    for k in range(n + m):
        opti.subject_to(states[:, k + 1] == rk4(states[:, k], u[k], big_t / n if k < n else hhf.HOLD / m))
    opti.subject_to(opti.bounded(-U_MAX, u, U_MAX))
    opti.subject_to(opti.bounded(-V_MAX, states[1, :], V_MAX))
    opti.subject_to(opti.bounded(-BAND, states[[2, 4], n:], BAND))
    opti.subject_to(states[2:, n + m] == 0)
    opti.subject_to(opti.bounded(1.0, big_t, 15.0))
    opti.minimize(big_t + 1e-6 * ca.sumsqr(u[:n]))
    free = [np.array(start)]
    for k in range(n + m):
        free.append(hhf.rk4(free[-1], 0.0, GUESS / n if k < n else hhf.HOLD / m, P))
    opti.set_initial(big_t, GUESS)
    opti.set_initial(states, np.array(free).T)
    opti.set_initial(u, 0.0)
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "max_iter": 3000, "tol": 1e-9, "sb": "yes"})
    solution = opti.solve()
    plan = json.loads((Path(__file__).parent / "hard_hit_60deg_plan.json").read_text())
    plan.update(seconds=float(solution.value(big_t)),
                u=[min(U_MAX, max(-U_MAX, float(v))) for v in solution.value(u)])  # IPOPT's 1e-8 past the bounds
    (Path(__file__).parent / "hard_hit_60deg_plan.json").write_text(json.dumps(plan, indent=0))
    print(f"T = {plan['seconds']:.4f} s")


if __name__ == "__main__":
    main()
