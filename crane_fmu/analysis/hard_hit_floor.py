"""The hard hit's floor: the least time the nonlinear crane needs to bring a large swing within a band and keep it.

Issue 51 asks for 60 deg -> 0.5 deg in at most 6.5 s. Whether any controller can do that is a question of the
crane's physics under its drive's limits, answered here on the NONLINEAR model (eqs (8)-(9),
:func:`crane_fmu.model.plant_equations.angular_accelerations`), not on its linearisation as
:mod:`.floor` does for the scoreboard's small swings.

Method (:data:`METHOD`): direct multiple shooting. The trolley acceleration ``u`` is held over ``N`` equal
intervals of ``[0, T]`` and ``M`` intervals of a hold ``[T, T + H]``; each interval is integrated by RK4 in
:data:`SUBSTEPS` sub-steps, the shooting nodes' states are variables tied by equality constraints, their exact
derivatives (and the derivative in ``T``) by forward-mode differentiation of RK4 over
:func:`~crane_fmu.model.plant_equations.accelerations_tangent`. Constraints: ``|u| <= u_max``, ``|v| <= v_max``
at every node (the speed is piecewise linear between them), both angles within ``band`` at every node of the hold
and the swing at exact rest (angles and rates zero) at its end, so that the crane stays within the band for ever
after with ``u = 0``. The trolley's position is free (no rail ends bind: the plan moves it less than a metre).
Objective: ``T``; solver: scipy's SLSQP, started from the uncontrolled swing.

What it is: a locally optimal plan (the problem is not convex): the time it finds is one the crane can achieve
(:func:`check_plan` simulates it with scipy's DOP853 and an independent check asks a shorter ``T`` to be
infeasible), an upper bound of the least time on the grid, and a close estimate of it; it is not a proof that no
faster plan exists.
"""

import math
from collections import namedtuple

import numpy as np
import scipy.optimize
from scipy.integrate import solve_ivp

from crane_fmu.model import plant_equations
from crane_fmu.model.parameters import PlantParameters

GRID = 0.05  # s: the hold of u before T is T / INTERVALS, about this (the MPC's 50 ms QP period)
INTERVALS = 120  # N: intervals of [0, T]
HOLD = 2.4  # s: H, about one period of the slow mode (2.37 s): the band held over it, rest at its end
HOLD_INTERVALS = 48  # M: intervals of the hold (50 ms)
SUBSTEPS = 2  # RK4 sub-steps per interval
BAND = math.radians(0.5)  # rad: issue 51's band for a hard hit
SEGMENT = 12  # intervals per shooting segment (0.6 s)
METHOD = (f"least time on the nonlinear crane (eqs (8)-(9)): u held over {INTERVALS} equal intervals of [0, T] "
          f"(~{GRID * 1e3:g} ms), the band held over {HOLD:g} s after T and the swing at rest at its end, "
          "|u| and |v| within the drive limits; direct multiple shooting, RK4, scipy SLSQP: a local optimum")

Plan = namedtuple("Plan", "seconds hold u hold_u states hold_states success message")
Plan.__doc__ = ("A least-time plan: ``T`` and the hold ``H`` [s], the held inputs over ``[0, T]`` (``N``) and over "
                "the hold (``M``), the nodes' states (``N + 1`` and ``M + 1`` rows of the state), "
                "and the solver's outcome.")

_NO_SEED = (0.0,) * 5  # the tangent's seeds of l1, dl1, ddl1, F1, F2: none


def _derivative(s, u, p):
    dd1, dd2 = plant_equations.angular_accelerations(s[2], s[3], s[4], s[5], u, p)
    return np.array((s[1], u, s[3], dd1, s[5], dd2))


def _tangent(s, u, p, ds, du):
    """The derivative and its directional derivative along ``(ds, du)``, exactly."""
    (dd1, dd2), (t1, t2) = plant_equations.accelerations_tangent(s[2], s[3], s[4], s[5], u, p, None,
                                                                 plant_equations.NO_LOAD,
                                                                 (ds[2], ds[3], ds[4], ds[5], du) + _NO_SEED)
    return np.array((s[1], u, s[3], dd1, s[5], dd2)), np.array((ds[1], du, ds[3], t1, ds[5], t2))


def rk4(s, u, dt, p, substeps=SUBSTEPS):
    """The state after ``dt`` with ``u`` held: ``substeps`` classic RK4 steps."""
    h = dt / substeps
    for _ in range(substeps):
        k1 = _derivative(s, u, p)
        k2 = _derivative(s + 0.5 * h * k1, u, p)
        k3 = _derivative(s + 0.5 * h * k2, u, p)
        k4 = _derivative(s + h * k3, u, p)
        s = s + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return s


def _rk4_jacobian(s, u, dt, p, substeps=SUBSTEPS):
    """``(state after dt, d/ds (6x6), d/du (6), d/d(dt) (6))`` of :func:`rk4`, by forward-mode differentiation."""
    seeds = [(np.eye(6)[i], 0.0, 0.0) for i in range(6)] + [(np.zeros(6), 1.0, 0.0), (np.zeros(6), 0.0, 1.0)]
    columns = []
    end = None
    for ds0, du, ddt in seeds:
        x, dx = np.array(s, float), ds0.copy()
        h, dh = dt / substeps, ddt / substeps
        for _ in range(substeps):
            k1, t1 = _tangent(x, u, p, dx, du)
            k2, t2 = _tangent(x + 0.5 * h * k1, u, p, dx + 0.5 * (dh * k1 + h * t1), du)
            k3, t3 = _tangent(x + 0.5 * h * k2, u, p, dx + 0.5 * (dh * k2 + h * t2), du)
            k4, t4 = _tangent(x + h * k3, u, p, dx + dh * k3 + h * t3, du)
            total, dtotal = k1 + 2.0 * k2 + 2.0 * k3 + k4, t1 + 2.0 * t2 + 2.0 * t3 + t4
            x, dx = x + h / 6.0 * total, dx + (dh * total + h * dtotal) / 6.0
        end = x
        columns.append(dx)
    jac = np.array(columns).T
    return end, jac[:, :6], jac[:, 6], jac[:, 7]


def least_time(start, band=BAND, p=None, u_max=2.0, v_max=1.0, guess=7.0, intervals=INTERVALS,
               hold=HOLD, hold_intervals=HOLD_INTERVALS, segment=SEGMENT, max_iterations=500, progress=None,
               initial=None, times=(0.5, 30.0)):
    """The least time [s] (a local optimum, :data:`METHOD`) from ``start`` until both angles stay within ``band``.

    Parameters
    ----------
    start : sequence of float
        ``(x, dx, theta1, dtheta1, theta2, dtheta2)`` at t = 0.
    guess : float
        The first ``T`` [s]; the shooting nodes start on the uncontrolled swing.
    initial : (float, sequence of float), optional
        Instead: a plan to start from, ``(T, inputs)`` with ``intervals + hold_intervals`` inputs.
    times : (float, float)
        The bounds of ``T`` [s]; equal bounds ask whether that ``T`` is feasible (``Plan.success``).
    segment : int
        Intervals per shooting segment: the states at the segments' starts are variables.

    Returns
    -------
    Plan
    """
    p = p or PlantParameters()
    if not band > 0:
        raise ValueError(f"band must be > 0 rad, got {band!r}")
    n, m = intervals, hold_intervals
    nodes = n + m
    firsts = list(range(0, nodes, segment))  # the intervals that start a segment
    count = len(firsts) - 1  # segment start states that are variables (the first is the start)
    start = np.asarray(start, float)
    iu, ix = 1, 1 + nodes  # z = (T, u_0..u_{nodes-1}, the states at firsts[1:])
    dt_hold = hold / m
    banded = list(range(n, nodes + 1))  # the nodes from T on

    def run(z, derivatives):
        """Each node's state and, with ``derivatives``, its derivative in z (node k's row block)."""
        big_t, u = z[0], z[iu:ix]
        states = np.empty((nodes + 1, 6))
        jac = np.zeros((nodes + 1, 6, len(z))) if derivatives else None
        ends, end_jac = [], []
        for k in range(nodes):
            if k in firsts:
                j = firsts.index(k)
                if k > 0:
                    ends.append(states[k].copy())
                    if derivatives:
                        end_jac.append(jac[k].copy())
                s_k = start if j == 0 else z[ix + 6 * (j - 1): ix + 6 * j]
                states[k] = s_k
                if derivatives:
                    jac[k] = 0.0
                    if j > 0:
                        jac[k][:, ix + 6 * (j - 1): ix + 6 * j] = np.eye(6)
            dt = big_t / n if k < n else dt_hold
            if derivatives:
                states[k + 1], d_s, d_u, d_dt = _rk4_jacobian(states[k], u[k], dt, p)
                jac[k + 1] = d_s @ jac[k]
                jac[k + 1][:, iu + k] += d_u
                if k < n:
                    jac[k + 1][:, 0] += d_dt / n
            else:
                states[k + 1] = rk4(states[k], u[k], dt, p)
        return states, jac, ends, end_jac

    cache = {}

    def evaluate(z, derivatives=True):
        """:func:`run` of ``z``, kept for the next call (a solver asks for values and derivatives at one point)."""
        key = (z.tobytes(), derivatives)
        if key not in cache:
            if derivatives or (z.tobytes(), True) not in cache:
                cache.clear()
                cache[key] = run(z, derivatives)
            else:
                key = (z.tobytes(), True)
        return cache[key]

    def equalities(z):
        states, _, ends, _ = evaluate(z, False)
        return np.concatenate([e - z[ix + 6 * j: ix + 6 * j + 6] for j, e in enumerate(ends)] + [states[nodes, 2:]])

    def equalities_jacobian(z):
        _, jac, _, end_jac = evaluate(z)
        rows = []
        for j, ej in enumerate(end_jac):
            block = ej.copy()
            block[:, ix + 6 * j: ix + 6 * j + 6] -= np.eye(6)
            rows.append(block)
        return np.vstack(rows + [jac[nodes][2:]])

    def inequalities(z):  # >= 0: the speed at every node, both angles from T on
        states = evaluate(z, False)[0]
        v = states[1:, 1]
        angles = states[banded][:, [2, 4]].ravel()
        return np.concatenate([v_max - v, v_max + v, band - angles, band + angles])

    def inequalities_jacobian(z):
        jac = evaluate(z)[1]
        dv = jac[1:, 1, :]
        da = jac[banded][:, [2, 4], :].reshape(-1, len(z))
        return np.vstack([-dv, dv, -da, da])

    lower = [times[0]] + [-u_max] * nodes + [-math.inf] * (6 * count)
    upper = [times[1]] + [u_max] * nodes + [math.inf] * (6 * count)
    z0 = np.concatenate([[guess], np.zeros(nodes), np.zeros(6 * count)])
    if initial is not None:
        z0[0], z0[iu:ix] = initial[0], np.clip(initial[1], -u_max, u_max)
    free = run(z0, False)[0]  # the uncontrolled swing, or the initial plan's
    z0[ix:] = np.concatenate([free[k] for k in firsts[1:]])
    result = scipy.optimize.minimize(
        lambda z: z[0], z0, jac=lambda z: np.eye(len(z))[0], method="SLSQP",
        bounds=scipy.optimize.Bounds(lower, upper),
        constraints=[{"type": "eq", "fun": equalities, "jac": equalities_jacobian},
                     {"type": "ineq", "fun": inequalities, "jac": inequalities_jacobian}],
        options={"maxiter": max_iterations, "ftol": 1e-10}, callback=progress)
    z = result.x
    states = run(z, False)[0]
    worst = max(float(np.max(np.abs(equalities(z)))), float(-np.min(np.minimum(inequalities(z), 0.0))))
    success = bool(result.success) and worst < 1e-7
    return Plan(float(z[0]), hold, z[iu:iu + n], z[iu + n:ix], states[:n + 1], states[n:], success,
                f"{result.message} ({result.nit} iterations); worst constraint violation {worst:.1e}")


def simulate_plan(plan, start, p=None, rtol=1e-11, atol=1e-12, samples=20):
    """The plan's held inputs applied to the nonlinear crane integrated by scipy's DOP853 (not the plan's RK4):
    ``(times, states)`` over ``[0, T + H]``, ``samples`` points per interval."""
    p = p or PlantParameters()
    n, m = len(plan.u), len(plan.hold_u)
    edges = [plan.seconds * k / n for k in range(n + 1)]
    edges += [plan.seconds + plan.hold * k / m for k in range(1, m + 1)]
    inputs = list(plan.u) + list(plan.hold_u)
    times, states = [0.0], [np.asarray(start, float)]
    for k, u in enumerate(inputs):
        grid = np.linspace(edges[k], edges[k + 1], samples + 1)
        sol = solve_ivp(lambda t, s, u=u: plant_equations.derivative(s, u, p), (edges[k], edges[k + 1]),
                        states[-1], method="DOP853", rtol=rtol, atol=atol, t_eval=grid)
        times += list(sol.t[1:])
        states += list(sol.y.T[1:])
    return np.array(times), np.array(states)


def check_plan(plan, start, band=BAND, p=None):
    """What a plan achieves on the crane simulated by DOP853: ``(largest angle [rad] from T on, largest |u|,
    largest |v|, largest angle rate [rad/s] at T + H)``."""
    times, states = simulate_plan(plan, start, p)
    after = times >= plan.seconds - 1e-12
    angles = float(np.max(np.abs(states[after][:, [2, 4]])))
    inputs = np.abs(np.concatenate([plan.u, plan.hold_u]))
    return angles, float(np.max(inputs)), float(np.max(np.abs(states[:, 1]))), float(np.max(np.abs(states[-1, 2:])))


def settling(plan, start, band=BAND, p=None, coast=10.0):
    """The plan's settling time by the board's metric (``settling_0.5deg_s`` for the default band): the last time
    [s] either angle is outside ``band`` on the crane integrated by DOP853 (:func:`simulate_plan`), the plan
    followed by ``coast`` seconds of ``u = 0``; and the largest angle [rad] over that coast."""
    p = p or PlantParameters()
    times, states = simulate_plan(plan, start, p)
    sol = solve_ivp(lambda t, s: plant_equations.derivative(s, 0.0, p), (times[-1], times[-1] + coast), states[-1],
                    method="DOP853", rtol=1e-11, atol=1e-12, t_eval=np.linspace(times[-1], times[-1] + coast,
                                                                                  round(coast * 1000) + 1))
    times = np.concatenate([times, sol.t[1:]])
    angles = np.max(np.abs(np.vstack([states, sol.y.T[1:]])[:, [2, 4]]), axis=1)
    outside = times[angles > band]
    return (float(outside[-1]) if len(outside) else 0.0), float(np.max(np.abs(sol.y[[2, 4]])))
