"""What physics allows in S4's gust: the least peak swing a controller can keep after moving like the MPC until then.

Issue 51 (item 2) bounds the MPC's peak swing in every scenario by its own peak on the nominal move (S2) plus 2 deg.
In S4 (S2 with a 10 N half-sine push on the payload at 1.5-2.0 s) the push comes in phase with the move's own
largest swing, and the MPC's peak passes the bound. Whether any controller could keep within it, having moved as the
MPC moves until it reacts, is answered here for one that knows the rest of the gust from then on (no causal
controller does better):

    minimise   z  (the largest |theta1|, |theta2| from the reaction on)
    subject to s_(k+1) = Ad s_k + Bd u_k + Ed F_k    (the crane linearised about rest, :func:`.floor.crane_model`,
                                                      u and the gust's mean held over GRID),
               s_0 = the MPC's state at the reaction, |u_k| <= u_max, |v_k| <= v_max,
               and S4's targets: the trolley within 5 mm and both angles within 0.5 deg from the arrival
               target's time (6.4 s) on, both angles within 0.1 deg from the residual window's start.

A linear program (scipy HiGHS), as :mod:`.wind_floor`'s. The swing it bounds is near 17 deg, where the linear model
is off by a few per cent: :func:`replay` plays its input on the nonlinear plant (the board's, with the gust) and
gives the peak there too. ``python -m crane_fmu.analysis.gust_peak`` prints both for reactions at and after the
gust's onset (the MPC's own S4 run up to each).

A controller that does not know the gust in advance does worse. :func:`receding` plays one that knows all else: from
the reaction on, every interval it takes the gust's mean force over the interval just past (what the prediction's
error over it shows), assumes it constant until the gust's end (given) and solves the same program from the nonlinear
plant's state, applying the plan until the next solve under the true gust. One causal strategy, not the best one:
what it keeps, a causal controller can keep. And the MPC itself told the gust's present force (:func:`mpc_run`'s
``told``: its offset-free mode fed by an estimator with no lag), for comparison.
"""

import dataclasses
import math
from collections import namedtuple

import numpy as np
import scipy.sparse as sp

from crane_fmu.analysis import planar_scenarios
from crane_fmu.analysis.scenarios import STOPPED_DEG
from crane_fmu.analysis.wind_floor import ARRIVAL_DEG, TROLLEY_BAND, _held, solve
from crane_fmu.model import disturbances, mpc, plant
from crane_fmu.model.parameters import PlantParameters

GRID = 0.01  # s: the hold of u and of the gust's force (floor.GRID)
STEP = 1e-3  # s: the board's communication step
STOP = 10.0  # s: S4's run
REACTIONS = (1.50, 1.55, 1.60, 1.65, 1.70)  # s: when the controller takes over from the MPC (main)

Peak = namedtuple("Peak", "peak_deg u")
Peak.__doc__ = "The least peak swing [deg] from the reaction on and the trolley's acceleration [m/s2] per interval."


def gust_forces(t0, count, grid=GRID, gust=None):
    """``(F1, F2)`` [N] per grid interval from ``t0``: the Gust component's force sampled every :data:`STEP` (as the
    board samples it) and averaged over each interval (default: S4's gust)."""
    c = disturbances.GUST.check({**disturbances.GUST.defaults(), **(planar_scenarios.GUST if gust is None else gust)})
    per = int(round(grid / STEP))
    samples = np.array([disturbances.gust(c, t0 + k * STEP) for k in range(count * per)])
    return samples.reshape(count, per, 2).mean(axis=1)


def least_peak(state, t0, forces=None, p=None, u_max=2.0, v_max=1.0, x_d=planar_scenarios.DISTANCE,
               arrival_from=planar_scenarios.GUST_S, residual_from=None, stop=STOP, grid=GRID):
    """The :class:`Peak` of the least largest swing from ``t0`` on, from ``state`` (x, dx, theta1, dtheta1, theta2,
    dtheta2) at ``t0``, with ``forces`` per grid interval (default: S4's gust, :func:`gust_forces`), or None when the
    targets cannot be met. ``arrival_from`` / ``residual_from``: the arrival's and the residual's bands from then on
    (``arrival_from`` None, ``residual_from`` inf: not asked; the residual's default: S4's window on the crane ``p``).
    """
    p = PlantParameters() if p is None else p
    if residual_from is None:
        residual_from = planar_scenarios.residual_from(stop, planar_scenarios.PLAN, dataclasses.asdict(p))
    n, count = 6, int(round((stop - t0) / grid))
    ad, bd, ed = _held(p, grid)
    forces = gust_forces(t0, count, grid) if forces is None else np.asarray(forces)
    states, z = n * (count + 1), n * (count + 1) + count
    shift = sp.kron(sp.eye(count, count + 1, 1), sp.identity(n)) - sp.kron(sp.eye(count, count + 1), sp.csr_matrix(ad))
    dynamics = sp.hstack([shift, -sp.kron(sp.identity(count), sp.csr_matrix(bd.reshape(-1, 1))),
                          sp.csr_matrix((count * n, 1))])
    initial = sp.csr_matrix((np.ones(n), (np.arange(n), np.arange(n))), shape=(n, z + 1))
    a_eq = sp.vstack([dynamics, initial]).tocsr()
    b_eq = np.concatenate([(forces @ ed.T).reshape(-1), np.asarray(state, float)])
    rows, cols, values, upper = [], [], [], []

    def within(var, centre, width, scale=1.0, by_z=False):
        """|var - centre| * scale <= width (+ z)"""
        for sign in (1.0, -1.0):
            rows.append(len(upper)), cols.append(var), values.append(sign * scale)
            if by_z:
                rows.append(len(upper)), cols.append(z), values.append(-1.0)
            upper.append(width + sign * centre * scale)

    degree = 1.0 / math.radians(1.0)  # the angles' rows in degrees: rows of like size
    for k in range(count + 1):
        t = t0 + k * grid + 1e-9
        within(n * k + 1, 0.0, v_max)
        if arrival_from is not None and t >= arrival_from:
            within(n * k, x_d, TROLLEY_BAND)
        for i in (2, 4):
            within(n * k + i, 0.0, 0.0, degree, by_z=True)
            if arrival_from is not None and t >= arrival_from:
                within(n * k + i, 0.0, ARRIVAL_DEG, degree)
            if t >= residual_from:
                within(n * k + i, 0.0, STOPPED_DEG, degree)
    a_ub = sp.csr_matrix((values, (rows, cols)), shape=(len(upper), z + 1))
    cost = np.zeros(z + 1)
    cost[z] = 1.0
    bounds = [(None, None)] * states + [(-u_max, u_max)] * count + [(0.0, None)]
    x = solve(cost, a_ub, upper, a_eq, b_eq, bounds, "the gust's peak")
    return None if x is None else Peak(float(x[z]), x[states:z])


def _plant(p=None):
    values = {**plant.COMPONENT.defaults(), **planar_scenarios.DRIVE, "theta1_0": 0.0}
    if p is not None:
        values.update({k: getattr(p, k) for k in ("m1", "m2", "l1", "l2", "g")})
    return plant.configure(values)


def mpc_run(stop, gust=None, x_d=planar_scenarios.DISTANCE, told=0.0):
    """The MPC (Python, configured as on the board) on the nominal plant with S4's gust (``gust``: the Gust's
    parameters; default S4's) for ``stop`` seconds, as the board's master calls them: ``(times, plant states)``
    (every state's first six entries: x, dx, theta1, dtheta1, theta2, dtheta2). ``told``: the MPC's ``offset_free``
    (1 or 2) with the gust's present force as its ``F2_hat``, ``F1_hat`` (an estimator with no lag); 0: none."""
    pc, gc = _plant(), disturbances.GUST.check({**disturbances.GUST.defaults(),
                                                **(planar_scenarios.GUST if gust is None else gust)})
    cc = mpc.configure({**mpc.COMPONENT.defaults(), "h": STEP, "x_d": x_d, "offset_free": told})
    ps, cs = pc.state0, mpc.initial_state(cc)
    times, states = [], []
    for k in range(round(stop / STEP) + 1):
        times.append(k * STEP), states.append(ps)
        out = plant.COMPONENT.output(pc, ps, (0.0,) * 4)
        forces = disturbances.gust(gc, k * STEP)
        inputs = tuple(out[:6]) + (out[11], *(forces[::-1] if told else (0.0, 0.0)))
        u = mpc.COMPONENT.output(cc, cs, inputs)[0]
        ps = plant.update(pc, ps, (u, 0.0, *forces), k * STEP, STEP)
        cs = mpc.update(cc, cs, inputs, k * STEP, STEP)
        cs = getattr(cs, "state", cs)
    return np.array(times), np.array([s[:6] for s in states])


def replay(state, t0, u, grid=GRID, stop=STOP):
    """The largest |theta1|, |theta2| [deg] on the nonlinear plant (the board's, with S4's gust) from ``state`` at
    ``t0`` under the inputs ``u`` held over each grid interval (stepped every :data:`STEP`)."""
    pc, gc = _plant(), disturbances.GUST.check({**disturbances.GUST.defaults(), **planar_scenarios.GUST})
    ps = tuple(state) + tuple(pc.state0[6:])
    per, peak = int(round(grid / STEP)), 0.0
    for k in range(int(round((stop - t0) / STEP))):
        t = t0 + k * STEP
        ps = plant.update(pc, ps, (u[min(k // per, len(u) - 1)], 0.0, *disturbances.gust(gc, t)), t, STEP)
        peak = max(peak, abs(ps[2]), abs(ps[4]))
    return math.degrees(peak)


def receding(start, every=0.05, last=None):
    """The largest |theta1|, |theta2| [deg] of the causal strategy (module notes) reacting at ``start`` (the MPC's
    run before), planning every ``every`` [s] until the gust's end (``last``; then its last plan is held)."""
    gust = {**disturbances.GUST.defaults(), **planar_scenarios.GUST}
    end = gust["start"] + gust["duration"]
    last = end if last is None else last
    times, states = mpc_run(start)
    pc, gc = _plant(), disturbances.GUST.check(gust)
    k, per, hold = int(round(start / STEP)), int(round(every / STEP)), int(round(GRID / STEP))
    ps = tuple(states[k]) + tuple(pc.state0[6:])
    peak = max(np.max(np.abs(states[:k + 1, 2])), np.max(np.abs(states[:k + 1, 4])))
    u, j = None, 0
    while k < int(round(STOP / STEP)):
        t = k * STEP
        if t <= last + 1e-9:
            seen = np.mean([disturbances.gust(gc, t - i * STEP) for i in range(1, per + 1)], axis=0)
            ahead = t + GRID * np.arange(int(round((STOP - t) / GRID)))
            u, j = least_peak(ps[:6], t, np.where((ahead < end - 1e-9)[:, None], seen, 0.0)).u, 0
        for _ in range(min(per, int(round(STOP / STEP)) - k)):
            ps = plant.update(pc, ps, (u[min(j // hold, len(u) - 1)], 0.0, *disturbances.gust(gc, k * STEP)),
                              k * STEP, STEP)
            j, k = j + 1, k + 1
            peak = max(peak, abs(ps[2]), abs(ps[4]))
    return math.degrees(peak)


def main(reactions=REACTIONS, out=print):
    """Print the least peak (linear, and the nonlinear plant's under its input) for each reaction time."""
    times, states = mpc_run(max(reactions))
    before = max(np.max(np.abs(states[:, 2])), np.max(np.abs(states[:, 4])))
    out(f"the MPC's largest swing up to {max(reactions):.2f} s: {math.degrees(before):.2f} deg")
    for t0 in reactions:
        k = int(round(t0 / STEP))
        found = least_peak(states[k], t0)
        if found is None:
            out(f"reacting at {t0:.2f} s: S4's targets cannot be met")
            continue
        sofar = math.degrees(max(np.max(np.abs(states[:k + 1, 2])), np.max(np.abs(states[:k + 1, 4]))))
        out(f"reacting at {t0:.2f} s (the gust known from then on): least peak {found.peak_deg:.2f} deg (linear), "
            f"{replay(states[k], t0, found.u):.2f} deg on the nonlinear plant; before it {sofar:.2f} deg")
    for t0 in reactions[:2]:
        out(f"reacting at {t0:.2f} s, the force seen over the last interval assumed to last to the gust's end "
            f"(receding, every 50 ms): peak {receding(t0):.2f} deg on the nonlinear plant")
    for mode in (1.0, 2.0):
        states = mpc_run(STOP, told=mode)[1]
        out(f"the MPC told the gust's present force (offset_free {mode:g}): peak "
            f"{math.degrees(max(np.max(np.abs(states[:, 2])), np.max(np.abs(states[:, 4])))):.2f} deg")


if __name__ == "__main__":
    main()
