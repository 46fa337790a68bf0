"""What physics allows in S10's turbulent wind: the least residual swing any controller can leave, case by case.

S10 moves the load 2 m in a turbulent wind (:mod:`crane_fmu.model.wind`) whose slow part leans the hanging load
by tenths of a degree about the mean wind's equilibrium for seconds at a time. Whether a target can be met there
is a question of the crane's physics, answered here for a controller that knows the whole wind in advance (no
controller can do better, so a target this one cannot meet, no controller meets):

    minimise   z  (the largest angle from the mean wind's equilibrium in the residual window)
    subject to s_(k+1) = Ad s_k + Bd u_k + Ed F_k    (the crane linearised about rest, :func:`.floor.crane_model`,
                                                      u and the drag held over GRID),
               s_0 = rest, |u_k| <= u_max, |v_k| <= v_max,
               |theta_i - theta_i,eq| <= z            (in the residual window),
               and the scenario's other targets as constraints (:data:`ARRIVALS`).

``F_k`` is the Wind component's drag on a hook and load at rest (the seed's turbulence, the case's
``l1``/``l2``), its mean over each grid interval: the drag's dependence on the load's own speed (under 0.1 m/s
against 10 m/s after the move) is left out. A linear program (scipy HiGHS); ``None`` where its constraints cannot
all hold (solved by HiGHS' interior point method: its dual simplex met numerical trouble in some cases). Like
:mod:`.floor`'s, a floor of the linearised crane: on the plant a close estimate, not a proof.

A controller that does not know the future wind does worse. :func:`receding` plays one that knows all else: the
case's plant, its state and the turbulence now. Every ``replan`` seconds it solves the same program (its bands soft)
from the state it is in, the drag forecast by the turbulence's conditional mean (decaying with the Dryden time
constant ``L / U``), applies the plan until the next solve under the true drag, from rest at the target in the mean
wind's equilibrium after the move. It is one causal strategy, not the best one: what it meets, a causal controller
can meet; what it misses, it does not show out of reach. It misses the swing about the mean wind's equilibrium in
about a third of the cases: the lean of the gusts it cannot see coming. That is why S10 measures the swing about the
load's lean (:func:`.wind_equilibrium.lean`) instead, and :func:`lean_witness` shows those targets within physics:
the same program with the angles taken from the lean, its plan checked on the board's 1 ms step.

``python -m crane_fmu.analysis.wind_floor`` prints every case of the board's design (``--causal``: the receding
strategy's figures; ``--lean``: the witness of S10's targets as measured).
"""

import dataclasses
import math
import sys
from collections import namedtuple

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp

from crane_fmu.analysis import floor, planar_scenarios
from crane_fmu.analysis.wind_equilibrium import lean, wind_deflection
from crane_fmu.model import wind
from crane_fmu.model.parameters import PlantParameters

GRID = floor.GRID  # s: the hold of u and of the drag
STEP = 1e-3  # s: the board's communication step, the wind's sample
DEGREE = math.pi / 180.0
TROLLEY_BAND, ARRIVAL_DEG = 0.005, 0.5  # m, deg: S2's arrival band of the trolley, the arrival's of the angles
MARGIN_M = 0.002  # m: the witness plans within a band this much narrower, as its grid's hold is checked on 1 ms
SOFT = 10.0  # deg per band: with soft bands, the cost of exceeding a band by its width (1 % of it: 0.1 deg)
# where the arrival of S10 is measured: the trolley within 5 mm (S2's band), or the load within the board's load
# band, with every angle within 0.5 deg of the equilibrium from the arrival target's time on
ARRIVALS = ("load", "trolley", None)

Plan = namedtuple("Plan", "residual_deg u excess")
Plan.__doc__ = ("The least residual swing [deg], the trolley's acceleration [m/s2] over each grid interval that "
                "leaves it, and with soft bands by how much of their width it exceeds them.")
Left = namedtuple("Left", "residual_deg load_error_m arrived")
Left.__doc__ = ("What a strategy left against S10's targets: the largest angle in the residual window [deg] from the "
                "mean wind's equilibrium (:func:`receding`) or the load's lean (:func:`lean_witness`), the load's "
                "largest error there [m], and whether the arrival's bands held from their time on.")
WindCase = namedtuple("WindCase", "plant wind x_d stop_time residual_from arrival_from")
WindCase.__doc__ = ("One case of S10: the plant's and the Wind's parameters, the target [m], the run's length, the "
                    "residual window's start and the arrival target's time [s].")


def cases(n=planar_scenarios.CASES):
    """The ``n`` cases of S10's paired design (the board's)."""
    out = []
    for case in planar_scenarios.design(n):
        plant = {k: case[k] for k in ("l1", "l2", "m1", "m2")}
        out.append(WindCase(plant, {"seed": case["seed"], "l1": case["l1"], "l2": case["l2"]},
                            planar_scenarios.DISTANCE, 10.0,
                            planar_scenarios.residual_from(10.0, planar_scenarios.PLAN, plant),
                            planar_scenarios.GUST_S))
    return out


def still_speed(values, stop_time, step=STEP):
    """The Wind component's speed [m/s] at each of its samples (every ``step``) over ``stop_time``."""
    c = wind.COMPONENT.check(values)
    state, samples = wind._initial_state(c), int(round(stop_time / step))
    speed = np.empty(samples)
    for k in range(samples):
        speed[k] = c.mean + state[1]
        state = wind._update(c, state, None, k * step, step)
    return speed


def still_drag(values, stop_time, step=STEP, grid=GRID, speed=None):
    """``(F1, F2)`` per grid interval [N]: the Wind component's drag on a hook and a load at rest, sampled as the
    board samples it (every ``step``; ``speed``: those samples, if already drawn) and averaged over each ``grid``
    interval."""
    speed = still_speed(values, stop_time, step) if speed is None else speed
    return _drag(wind.COMPONENT.check(values), speed).reshape(int(round(stop_time / grid)), -1, 2).mean(axis=1)


def _drag(c, speed):
    """``(F1, F2)`` [N] on a hook and a load at rest in the wind ``speed`` (an array of them: one row each)."""
    return np.stack([wind.drag(c.drag1, speed, 0.0), wind.drag(c.drag2, speed, 0.0)], axis=1)


def _held(p, grid):
    """``(Ad, Bd, Ed)``: the linearised crane's exact step over ``grid`` with ``u`` and the forces held."""
    a, b, e = floor.crane_model(p)
    exact = scipy.linalg.expm(np.block([[a, b[:, None], e], [np.zeros((3, 9))]]) * grid)
    return exact[:6, :6], exact[:6, 6], exact[:6, 7:]


def least_residual(case, arrival="load", load_band=None, **limits):
    """The least residual swing [deg] about the mean wind's equilibrium a controller knowing the wind can leave in
    ``case`` while meeting S10's other targets (:func:`plan`), or None when they cannot all be met."""
    found = plan(case, arrival, load_band, **limits)
    return None if found is None else found.residual_deg


def plan(case, arrival="load", load_band=None, u_max=2.0, v_max=1.0, grid=GRID, start=None, forces=None,
         soft=False, about="equilibrium"):
    """The :class:`Plan` of the least residual swing about the mean wind's equilibrium in ``case`` with S10's other
    targets met, or None when they cannot all be met.

    ``arrival``: the arrival target's band from ``case.arrival_from`` on, on the load (within ``load_band``) or the
    trolley (within 5 mm), every angle within 0.5 deg of the equilibrium; None: no arrival target. The load stays
    within ``load_band`` (default: the board's, :data:`.planar_scenarios.LOAD_BAND_M`) in the residual window.
    ``start``: ``(t0, state)`` to plan from (default: rest at 0 s); ``forces``: the drag over each interval from
    ``t0`` (default the case's, :func:`still_drag`); ``soft``: the bands may be exceeded at a cost (:data:`SOFT`).
    ``about="lean"``: the angles taken from the load's lean instead (S10's measure, :func:`.wind_equilibrium.lean`
    over the grid), where it is known.
    """
    if about not in ("equilibrium", "lean"):
        raise ValueError(f"about must be 'equilibrium' or 'lean', got {about!r}")
    if arrival not in ARRIVALS:
        raise ValueError(f"arrival must be one of {ARRIVALS}, got {arrival!r}")
    band = planar_scenarios.LOAD_BAND_M if load_band is None else load_band
    p = dataclasses.replace(PlantParameters(), **case.plant)
    t0, state0 = start if start is not None else (0.0, np.zeros(6))
    n, count = 6, int(round((case.stop_time - t0) / grid))
    ad, bd, ed = _held(p, grid)
    if forces is None:
        forces = still_drag(case.wind, case.stop_time, grid=grid)[-count:]
    # variables: the states s_0..s_N (n each), the inputs u_0..u_(N-1), z [deg], the bands' excess (soft)
    states, z = n * (count + 1), n * (count + 1) + count
    excess = z + 1
    shift = sp.kron(sp.eye(count, count + 1, 1), sp.identity(n)) - sp.kron(sp.eye(count, count + 1), sp.csr_matrix(ad))
    dynamics = sp.hstack([shift, -sp.kron(sp.identity(count), sp.csr_matrix(bd.reshape(-1, 1))),
                          sp.csr_matrix((count * n, 2))])
    initial = sp.csr_matrix((np.ones(n), (np.arange(n), np.arange(n))), shape=(n, z + 2))
    a_eq = sp.vstack([dynamics, initial]).tocsr()
    b_eq = np.concatenate([(forces @ ed.T).reshape(-1), state0])

    rows, cols, values, upper = [], [], [], []

    def within(terms, centre, width, scale=1.0, by_z=False, band=False):
        """|sum(coef * var) - centre| * scale <= width (+ z; + width * excess for a soft band)"""
        for sign in (1.0, -1.0):
            for var, coef in terms:
                rows.append(len(upper)), cols.append(var), values.append(sign * coef * scale)
            if by_z or (band and soft):
                rows.append(len(upper)), cols.append(z if by_z else excess), values.append(-1.0 if by_z else -width)
            upper.append(width + sign * centre * scale)

    def s(k, i):
        return n * k + i

    equilibrium = wind_deflection(case.plant, case.wind)
    load = ((0, 1.0), (2, p.l1), (4, p.l2))  # the load's position, linearised (eqs (4)-(5))
    half = round(planar_scenarios.mode_periods(**case.plant)[0] / grid) // 2 if about == "lean" else 0
    for k in range(count + 1):
        t = t0 + k * grid + 1e-9
        in_window, arrived = t >= case.residual_from, arrival is not None and t >= case.arrival_from
        within([(s(k, 1), 1.0)], 0.0, v_max)
        if in_window or (arrived and arrival == "load"):
            within([(s(k, i), c) for i, c in load], case.x_d, band, band=True)
        if arrived and arrival == "trolley":
            within([(s(k, 0), 1.0)], case.x_d, TROLLEY_BAND, band=True)
        if about == "lean" and not half <= k <= count - half:
            continue  # the lean unknown: not measured
        for i, angle in ((2, equilibrium[0]), (4, equilibrium[1])):  # in degrees: rows of like size
            terms = [(s(k, i), 1.0)] + [(s(j, i), -1.0 / (2 * half + 1)) for j in range(k - half, k + half + 1)
                                        if about == "lean"]
            centre = angle if about == "equilibrium" else 0.0
            if in_window:
                within(terms, centre, 0.0, scale=1.0 / DEGREE, by_z=True)
            if arrived:
                within(terms, centre, ARRIVAL_DEG, scale=1.0 / DEGREE, band=True)
    a_ub = sp.csr_matrix((values, (rows, cols)), shape=(len(upper), z + 2))
    cost = np.zeros(z + 2)
    cost[z], cost[excess] = 1.0, SOFT
    bounds = [(None, None)] * states + [(-u_max, u_max)] * count + [(0.0, None), (0.0, None if soft else 0.0)]
    x = solve(cost, a_ub, upper, a_eq, b_eq, bounds, "the wind floor's")
    return None if x is None else Plan(float(x[z]), x[states:z], float(x[excess]))


def solve(cost, a_ub, upper, a_eq, b_eq, bounds, name):
    """The solution of the linear program (scipy HiGHS' interior point method: its dual simplex met numerical
    trouble in some cases), None where its constraints cannot all hold; a failure raises, naming the program."""
    result = scipy.optimize.linprog(cost, A_ub=a_ub, b_ub=np.array(upper), A_eq=a_eq, b_eq=b_eq, bounds=bounds,
                                    method="highs-ipm")
    if result.status == 2:  # infeasible
        return None
    if result.status != 0:
        raise RuntimeError(f"{name} linear program failed: {result.message}")
    return result.x


def lean_witness(case, grid=0.02):
    """The :class:`Left` figures, on the board's 1 ms step, of the plan (:func:`plan`, ``about="lean"``, on
    ``grid``) that leaves the least swing about the load's lean in ``case`` over S10's run, or None when S10's
    targets cannot all be met on ``grid``: a controller that knows the wind in advance can leave this."""
    case = case._replace(stop_time=planar_scenarios.WIND_RUN_S)
    found = plan(case, load_band=planar_scenarios.LOAD_BAND_M - MARGIN_M, grid=grid, about="lean")
    if found is None:
        return None
    p = dataclasses.replace(PlantParameters(), **case.plant)
    ad, bd, ed = _held(p, STEP)
    states, hold = [np.zeros(6)], round(grid / STEP)
    for k, f in enumerate(still_drag(case.wind, case.stop_time, grid=STEP)):
        states.append(ad @ states[-1] + bd * found.u[k // hold] + ed @ f)
    states, t = np.array(states), np.arange(len(states)) * STEP + 1e-9
    samples = round(planar_scenarios.mode_periods(**case.plant)[0] / STEP)
    swing = np.abs(np.degrees(np.stack([states[:, i] - lean(states[:, i], samples) for i in (2, 4)], axis=1)))
    load = np.abs(states[:, 0] + p.l1 * states[:, 2] + p.l2 * states[:, 4] - case.x_d)
    known = ~np.isnan(swing[:, 0])
    window, arrived = known & (t >= case.residual_from), known & (t >= case.arrival_from)
    return Left(float(swing[window].max()), float(load[window].max()),
                bool((swing[arrived] <= ARRIVAL_DEG).all() and (load[arrived] <= planar_scenarios.LOAD_BAND_M).all()))


def receding(case, replan=0.25, grid=0.05, after=3.6):
    """The :class:`Left` figures of the receding strategy (module notes) in ``case``: from rest at the target in
    the mean wind's equilibrium at ``after`` [s] (the move's end), planning every ``replan`` [s] on ``grid``."""
    c = wind.COMPONENT.check(case.wind)
    p = dataclasses.replace(PlantParameters(), **case.plant)
    ad, bd, ed = _held(p, grid)
    speed = still_speed(case.wind, case.stop_time)  # each 1 ms sample's
    true, turbulence = still_drag(case.wind, case.stop_time, grid=grid, speed=speed), speed - c.mean
    equilibrium = wind_deflection(case.plant, case.wind)
    offset = p.l1 * math.sin(equilibrium[0]) + p.l2 * math.sin(equilibrium[1])
    state = np.array([case.x_d - offset, 0.0, equilibrium[0], 0.0, equilibrium[1], 0.0])
    k, count, residual, error, arrived = int(round(after / grid)), len(true), 0.0, 0.0, True
    while k < count:
        now = turbulence[int(round(k * grid / STEP))]
        ahead = (np.arange(count - k) + 0.5) * grid
        forecast = c.mean + now * np.exp(-ahead / c.time_constant)  # the turbulence's conditional mean
        u = plan(case, grid=grid, start=(k * grid, state), forces=_drag(c, forecast), soft=True).u
        for u_k in u[:int(round(replan / grid))]:
            state = ad @ state + bd * u_k + ed @ true[k]
            k += 1
            t = k * grid + 1e-9
            swing = max(abs(state[2] - equilibrium[0]), abs(state[4] - equilibrium[1]))
            load = abs(state[0] + p.l1 * state[2] + p.l2 * state[4] - case.x_d)
            if t >= case.residual_from:
                residual, error = max(residual, swing), max(error, load)
            if t >= case.arrival_from and (swing > ARRIVAL_DEG * DEGREE or load > planar_scenarios.LOAD_BAND_M):
                arrived = False
    return Left(math.degrees(residual), float(error), arrived)


def main(n=planar_scenarios.CASES, causal=False, lean_measured=False, out=print):
    """Print each case's floor with the arrival on the load and on the trolley, and the worst of each; ``causal``:
    the receding strategy's figures against S10's targets measured about the mean wind's equilibrium instead;
    ``lean_measured``: :func:`lean_witness`' figures against S10's targets as the board measures them."""
    if causal or lean_measured:
        met = []
        for number, case in enumerate(cases(n), 1):
            r = receding(case) if causal else lean_witness(case)
            if r is None:  # the witness's program infeasible on its grid
                met.append((False, False, False))
                out(f"#{number:02d} lean witness: infeasible")
                continue
            met.append((r.residual_deg <= planar_scenarios.WIND_CUT_DEG, r.load_error_m <= planar_scenarios.LOAD_BAND_M,
                        r.arrived))
            out(f"#{number:02d} {'receding' if causal else 'lean witness'}: residual {r.residual_deg:.3f} deg, load "
                f"{r.load_error_m * 1e3:.1f} mm, arrival {'met' if r.arrived else 'missed'}")
        out(f"{'receding' if causal else 'lean witness'}, of {n} cases: residual met in {sum(m[0] for m in met)}, "
            f"load in {sum(m[1] for m in met)}, arrival in {sum(m[2] for m in met)}, all three in "
            f"{sum(all(m) for m in met)}")
        return
    load, trolley = [], []
    for number, case in enumerate(cases(n), 1):
        load.append(least_residual(case, "load"))
        trolley.append(least_residual(case, "trolley"))
        out(f"#{number:02d} least residual about the equilibrium: arrival on the load "
            f"{_deg(load[-1])}, on the trolley {_deg(trolley[-1])}")
    for name, floors in (("the load", load), ("the trolley", trolley)):
        met = [f for f in floors if f is not None]
        out(f"arrival on {name}: feasible in {len(met)} of {n} cases, the largest least residual "
            f"{max(met):.3f} deg, above {planar_scenarios.WIND_CUT_DEG:.2f} deg in "
            f"{sum(f > planar_scenarios.WIND_CUT_DEG for f in met)}")


def _deg(value):
    return "infeasible" if value is None else f"{value:.3f} deg"


if __name__ == "__main__":
    main(causal="--causal" in sys.argv[1:], lean_measured="--lean" in sys.argv[1:])
