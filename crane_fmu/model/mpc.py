"""Constrained model-predictive control of the crane: the MpcController component.

Two optimisations on the crane linearised about the hanging equilibrium (the LQR's
model, :func:`.lqr.continuous_model`, held over the control interval ``T``):

1. **The plan**, once, at the first solve: the shortest move from the measured state
   to rest at ``x_d`` (bisection on the number of intervals ``n``; a move is
   possible when the QP ``min rho |s_n - s_target|^2 + |U|^2`` reaches the target),
   within ``(1 - margin)`` of the drive's limits: the whole move is seen at once.
2. **The tracking QP**, every interval ``T``: the input ``u = u*_k + du_0`` around the
   plan ``(s*_k, u*_k)`` from the QP over the horizon ``N``::

       minimise    sum_{k=1}^{N} e_k' Q e_k (P at k = N) + r sum_{k=0}^{N-1} du_k^2,
                   e_{k+1} = Ad e_k + Bd du_k,   e_0 = s - s*
       subject to  |u*_k + du_k| <= u_max,  |v_{k+1}| <= v_max

   with ``P`` the discrete Riccati solution (the LQR's terminal cost). The drive's
   limits are constraints of the QP: nothing is clipped afterwards. Between solves ``u``
   is held.

Both QPs are solved by :mod:`.qp` (our own primal active-set solver, warm-started
with the previous solution shifted by one interval; at its iteration cap it gives its
best feasible input and the FMU warns once). With ``l1_low < l1_high`` the designs
are made for cable lengths across that range and the one nearest the measured
``l1_now`` is used (as the LQR schedules its gains).

What is claimed is measured, not proven: ``crane-fmu targets`` and the scoreboard
give its figures; the plan is only as good as the linear model (a few tenths of a
degree at the end of a fast move on the nominal plant, degrees on a plant the model
does not know), which the tracking QP then removes.
"""

import dataclasses
import math
from collections import namedtuple

from . import limits, linalg, qp
from .component import Component, Step
from .lqr import DEFAULT_WEIGHTS, WEIGHTS, continuous_model
from .parameters import finite, plant_parameters, positive
from .tables import MEASURED_STATE, controller_model, input_, output, parameter, positions

RHO = 1e6  # the plan's weight on missing the target state
REACHED = 1e-3  # the plan reaches the target when every state is this close (m, m/s, rad, rad/s)
LONGEST_PLAN = 6.0  # s: a move that needs longer is not planned (the tracking QP regulates alone)
SCHEDULE_POINTS = 11

Design = namedtuple("Design", "l1 ad bd gain qp")
Design.__doc__ = ("The tracking QP for one cable length: the model ``(Ad, Bd)`` over the interval, ``F`` (N x 6) "
                  "of the linear term ``f = F e0``, and the prepared QP (:func:`.qp.prepare`).")

Config = namedtuple("Config", "designs x_d u_max v_max margin h every interval steps max_iterations memo")
Config.__doc__ = ("The designs (one, or one per scheduled cable length), the target, the limits, the plan's "
                  "margin, the communication step ``h``, the steps per interval (``every``), the interval, the "
                  "horizon in intervals, the QP's cap, and ``memo``: the last solve, which the FMU's output and "
                  "its step share.")

# The state: a header, then the last solution du (N), the rows it held at a bound (2N codes: 0, +1 upper,
# -1 lower), the plan's inputs u* (n) and its states s* ((n + 1) x 6).
HEADER = namedtuple("Header", "count u iterations warned plan_steps")(*range(5))


def predict_rows(ad, bd, steps):
    """``b_k = Ad^k Bd`` for ``k < steps``: the effect of an input ``k`` intervals before."""
    out, b = [], [row[0] for row in bd]
    for _ in range(steps):
        out.append(b)
        b = [linalg.dot(row, b) for row in ad]
    return out


def constraint_rows(steps, interval):
    """The rows of the input bounds (one per input) and of the speed bounds (prefix sums times ``interval``)."""
    return [(k, [1.0]) for k in range(steps)] + [(0, [interval] * (k + 1)) for k in range(steps)]


def design(p, weights, r, interval, steps):
    """The tracking QP of :mod:`.mpc` for the crane ``p``: its Hessian, linear-term gain and constraint rows.

    Notes
    -----
    With ``b_k = Ad^k Bd`` and ``Q_k = Q`` (``P`` for the last state), the predicted
    ``e_{k+1} = Ad^{k+1} e_0 + sum_{j<=k} b_{k-j} du_j`` gives
    ``H_ij = r delta_ij + sum_{k>=max(i,j)} b_{k-i}' Q_k b_{k-j}`` and
    ``F_i = sum_{k>=i} b_{k-i}' Q_k Ad^{k+1}``.
    """
    ad, bd = linalg.zoh(*continuous_model(p), interval)
    q = [[weights[i] if i == j else 0.0 for j in range(6)] for i in range(6)]
    terminal = linalg.dare(ad, bd, q, [[r]])
    b = predict_rows(ad, bd, steps)
    powers, power = [], ad  # Ad^(k+1) for state k+1
    for _ in range(steps):
        powers.append(power)
        power = linalg.matmul(ad, power)
    weight = [terminal if k == steps - 1 else q for k in range(steps)]
    hessian = [[0.0] * steps for _ in range(steps)]
    gain = []
    for i in range(steps):
        row_f = [0.0] * 6
        for k in range(i, steps):
            wb = [linalg.dot(w, b[k - i]) for w in weight[k]]
            for c in range(6):
                row_f[c] += linalg.dot(wb, [powers[k][a][c] for a in range(6)])
            for j in range(i, k + 1):
                hessian[i][j] += linalg.dot(wb, b[k - j])
        gain.append(row_f)
    for i in range(steps):
        hessian[i][i] += r
        for j in range(i + 1, steps):
            hessian[j][i] = hessian[i][j]
    return Design(p.l1, ad, bd, gain, qp.prepare(hessian, constraint_rows(steps, interval)))


def speed_envelope(v0, v_max, u_max, interval, k):
    """``(low, high)`` of the speed after ``k`` intervals: ``+-v_max``, widened to braking at ``u_max`` from ``v0``."""
    return min(-v_max, v0 + u_max * interval * k), max(v_max, v0 - u_max * interval * k)


def feasible_start(guess, v0, lower_u, upper_u, v_max, u_max, interval):
    """``guess`` moved, input by input, into the bounds and the speed envelope: a feasible start for the QP."""
    u, v = [], v0
    for k, value in enumerate(guess):
        low_v, high_v = speed_envelope(v0, v_max, u_max, interval, k + 1)
        low = max(lower_u[k], (low_v - v) / interval)
        high = min(upper_u[k], (high_v - v) / interval)
        value = min(max(value, low), high)
        u.append(value)
        v += interval * value
    return u


def rigid_move_time(distance, u_max, v_max):
    """The shortest rest-to-rest move [s] of the trolley alone: no crane move is shorter."""
    distance = abs(distance)
    if distance <= v_max * v_max / u_max:
        return 2.0 * math.sqrt(distance / u_max)
    return distance / v_max + v_max / u_max


def _resampled(solution, n):
    """A previous attempt's inputs and active rows stretched or shrunk to ``n`` intervals: the next one's start."""
    inputs, codes = solution
    old = len(inputs)
    picks = [min(old - 1, k * old // n) for k in range(n)]
    hint = [(k + block * n, codes[pick + block * old]) for block in (0, 1) for k, pick in enumerate(picks)
            if codes[pick + block * old]]
    return [inputs[pick] for pick in picks], hint


def plan_move(d, s0, target, u_max, v_max, interval, max_intervals):
    """The shortest move ``(u*, s*)`` from ``s0`` to rest at ``target`` within the limits, or ``((), ())``.

    Bisection on the number of intervals ``n``, from a first guess above the trolley's own
    shortest move (:func:`rigid_move_time`): a move of ``n`` intervals is possible when
    the solution of ``min RHO |s_n - target|^2 + |U|^2`` within the limits ends within
    :data:`REACHED` of the target in every state. Each attempt starts from the last
    one's solution, resampled to its length.
    """
    if max(abs(a - b) for a, b in zip(s0, target)) <= REACHED:
        return (), ()
    at_rest = abs(s0[1]) <= REACHED
    shortest = rigid_move_time(target[0] - s0[0], u_max, v_max) if at_rest else 0.0
    low = int(shortest / interval) - 1 if at_rest else 0  # too few (rounding aside)
    previous = None

    def attempt(n):
        nonlocal previous
        b = predict_rows(d.ad, d.bd, n)
        free = list(s0)
        for _ in range(n):
            free = [linalg.dot(row, free) for row in d.ad]
        miss = [t - f for t, f in zip(target, free)]  # what the inputs must add
        columns = [b[n - 1 - j] for j in range(n)]  # input j's effect on the end state
        hessian = [[RHO * linalg.dot(columns[i], columns[j]) + (1.0 if i == j else 0.0) for j in range(n)]
                   for i in range(n)]
        f = [-RHO * linalg.dot(columns[i], miss) for i in range(n)]
        prepared = qp.prepare(hessian, constraint_rows(n, interval))
        lower, upper = [-u_max] * n, [u_max] * n
        for k in range(n):
            low_v, high_v = speed_envelope(s0[1], v_max, u_max, interval, k + 1)
            lower.append(low_v - s0[1])
            upper.append(high_v - s0[1])
        guess, hint = _resampled(previous, n) if previous else ([0.0] * n, [])
        start = feasible_start(guess, s0[1], lower, upper, v_max, u_max, interval)
        solution = qp.solve(prepared, f, lower, upper, start, hint, max_iterations=20 * n)
        codes = [0] * (2 * n)
        for row, side in solution.active:
            codes[row] = side
        previous = (solution.x, codes)
        reach = [linalg.dot(c, solution.x) for c in zip(*columns)]
        return all(abs(r - m) <= REACHED for r, m in zip(reach, miss)), solution.x

    high = max(8, low + 1 + int(0.15 * low) + 4)
    ok, inputs = attempt(high)
    while not ok:
        low, high = high, 2 * high
        if high > max_intervals:
            return (), ()
        ok, inputs = attempt(high)
    while high - low > 1:
        mid = (low + high) // 2
        ok, found = attempt(mid)
        if ok:
            high, inputs = mid, found
        else:
            low = mid
    states, s = [tuple(s0)], list(s0)
    for value in inputs:
        s = [linalg.dot(row, s) + bk[0] * value for row, bk in zip(d.ad, d.bd)]
        states.append(tuple(s))
    return tuple(inputs), tuple(states)


def configure(values):
    """Validated parameters and the tracking designs (one, or one per scheduled cable length)."""
    p = plant_parameters(values)
    for name in WEIGHTS:
        value = values[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value < math.inf:
            raise ValueError(f"{name} must be >= 0 and finite, got {value!r}")
    for name in ("r", "h", "interval", "horizon"):
        positive(name, values[name])
    margin = values["margin"]
    if not 0 <= margin < 1:
        raise ValueError(f"margin must be >= 0 and < 1, got {margin!r}")
    cap = values["max_iterations"]
    if not (cap >= 1 and cap == int(cap)):
        raise ValueError(f"max_iterations must be a whole number >= 1, got {cap!r}")
    finite("x_d", values["x_d"])
    u_max, v_max = limits.check(values)
    if not (math.isfinite(u_max) and math.isfinite(v_max)):
        raise ValueError(f"u_max and v_max must be finite (the MPC's constraints), got {u_max!r}, {v_max!r}")
    h = values["h"]
    every = max(1, round(values["interval"] / h))
    interval = every * h
    steps = max(1, round(values["horizon"] / interval))
    if steps > 200:
        raise ValueError(f"horizon must be at most 200 intervals, got {values['horizon']!r} s = {steps} intervals "
                         f"of {interval!r} s")
    weights = [values[name] for name in WEIGHTS]
    low, high = values["l1_low"], values["l1_high"]
    if (low, high) == (0.0, 0.0):
        lengths = [p.l1]
    else:
        positive("l1_low", low)
        if not high > low or not math.isfinite(high):
            raise ValueError(f"l1_high must be finite and > l1_low = {low!r}, got {high!r}")
        lengths = [low + (high - low) * i / (SCHEDULE_POINTS - 1) for i in range(SCHEDULE_POINTS)]
    designs = tuple(design(dataclasses.replace(p, l1=length), weights, values["r"], interval, steps)
                    for length in lengths)
    return Config(designs=designs, x_d=values["x_d"], u_max=u_max, v_max=v_max, margin=margin, h=h, every=every,
                  interval=interval, steps=steps, max_iterations=int(cap), memo={})


def nearest_design(config, l1):
    """The design for the cable length nearest the measured ``l1`` (the only one without a schedule)."""
    designs = config.designs
    if len(designs) == 1 or not l1 > 0:
        return designs[0] if len(designs) == 1 else designs[len(designs) // 2]
    return min(designs, key=lambda d: abs(d.l1 - l1))


def initial_state(config):
    n = config.steps
    return (0.0, 0.0, 0.0, 0.0, 0.0) + (0.0,) * n + (0.0,) * (2 * n)


def _plan_of(config, state):
    """``(u*, s*)`` stored in ``state``."""
    n, start = int(state[HEADER.plan_steps]), len(HEADER) + 3 * config.steps
    inputs = state[start:start + n]
    flat = state[start + n:]
    return inputs, [flat[6 * k:6 * k + 6] for k in range(len(flat) // 6)]


def solve(config, state, measured, l1_now):
    """One solve: ``(u, new state without the count, messages)`` from the measured state."""
    c, n = config, config.steps
    d = nearest_design(c, l1_now)
    target = (c.x_d, 0.0, 0.0, 0.0, 0.0, 0.0)
    count = int(state[HEADER.count])
    if count == 0:
        shrink = 1.0 - c.margin
        plan_u, plan_s = plan_move(d, measured, target, c.u_max * shrink, c.v_max * shrink, c.interval,
                                   int(LONGEST_PLAN / c.interval))
        start_at = 0
    else:
        plan_u, plan_s = _plan_of(c, state)
        start_at = count // c.every  # intervals since the plan began
    ref_u = [plan_u[start_at + k] if start_at + k < len(plan_u) else 0.0 for k in range(n)]
    ref_s = plan_s[start_at] if start_at < len(plan_s) else target
    e0 = [a - b for a, b in zip(measured, ref_s)]
    f = [linalg.dot(row, e0) for row in d.gain]
    v0 = measured[1]
    lower = [-c.u_max - value for value in ref_u]
    upper = [c.u_max - value for value in ref_u]
    planned = v0
    for k in range(n):  # the speed rows bound what du adds to the plan's speed change from v0
        planned += c.interval * ref_u[k]
        low_v, high_v = speed_envelope(v0, c.v_max, c.u_max, c.interval, k + 1)
        lower.append(low_v - planned)
        upper.append(high_v - planned)
    previous = state[len(HEADER):len(HEADER) + n]
    guess = [ref_u[k] + (previous[k + 1] if k + 1 < n else 0.0) for k in range(n)] if count else ref_u
    absolute = feasible_start(guess, v0, [-c.u_max] * n, [c.u_max] * n, c.v_max, c.u_max, c.interval)
    start = [a - b for a, b in zip(absolute, ref_u)]
    codes = state[len(HEADER) + n:len(HEADER) + 3 * n]
    hint = []
    for row, code in enumerate(codes):  # each row one interval later: row k+1 of the last solve is row k now
        if code and row % n:
            hint.append((row - 1, int(code)))
    solution = qp.solve(d.qp, f, lower, upper, start, hint, c.max_iterations)
    new_codes = [0.0] * (2 * n)
    for row, side in solution.active:
        new_codes[row] = float(side)
    u = ref_u[0] + solution.x[0]
    messages = ()
    warned = state[HEADER.warned]
    if not solution.optimal and not warned:
        warned = 1.0
        messages = (f"MpcController: the QP stopped at its iteration cap ({c.max_iterations}) at t = "
                    f"{count * c.h!r} s; u is its best feasible input (warned once)",)
    plan_part = (tuple(plan_u) + tuple(v for s in plan_s for v in s)) if count == 0 else \
        state[len(HEADER) + 3 * n:]
    rest = ((u, float(solution.iterations), warned, float(len(plan_u))) + tuple(solution.x) + tuple(new_codes)
            + plan_part)
    return u, rest, messages


def _solved(config, state, inputs):
    """The solve at this state and these inputs (shared by the output and the step through ``memo``)."""
    memo = config.memo
    if memo.get("state") is not state or memo.get("inputs") != inputs:
        memo["state"], memo["inputs"] = state, inputs
        memo["value"] = solve(config, state, inputs[IN.x:IN.dtheta2 + 1], inputs[IN.l1_now])
    return memo["value"]


def _due(config, state):
    return int(state[HEADER.count]) % config.every == 0


def _plan_end(config, state):
    return state[HEADER.plan_steps] * config.interval


def _output(config, state, inputs):
    if _due(config, state):
        u, rest, _ = _solved(config, state, inputs)
        return u, rest[1], rest[3] * config.interval
    return state[HEADER.u], state[HEADER.iterations], _plan_end(config, state)


def update(config, state, inputs, time, step):
    """Count the step; after a solve keep its input (held until the next), its solution and the plan."""
    if not _due(config, state):
        return (state[HEADER.count] + 1.0,) + state[1:]
    _, rest, messages = _solved(config, state, inputs)
    new = (state[HEADER.count] + 1.0,) + rest
    return Step(new, list(messages)) if messages else new


def report(config):
    """The interval, the horizon and the designs, for ``crane-fmu info``."""
    return {"interval_s": config.interval, "horizon_intervals": config.steps,
            "designs_for_l1_m": [round(d.l1, 6) for d in config.designs]}


VARIABLES = controller_model() + tuple(
    parameter(name, value, "1", f"tracking QP: state weight on {name[2:]} (Q diagonal, SI units)")
    for name, value in DEFAULT_WEIGHTS.items()) + (
    parameter("r", 0.05, "1", "tracking QP: weight on the input's change from the plan"),
    parameter("interval", 0.05, "s", "control interval: the QPs are solved every interval and u is held between "
                                     "(a whole number of communication steps)"),
    parameter("horizon", 2.0, "s", "tracking QP's prediction horizon (the plan sees the whole move)"),
    parameter("margin", 0.05, "1", "share of u_max and v_max the plan leaves to the tracking QP"),
    parameter("max_iterations", 200.0, "1", "QP iteration cap: at the cap u is the best feasible input (warned "
                                            "once)"),
    parameter("h", 1e-3, "s", "communication step (the interval is a whole number of them)"),
    parameter("x_d", 0.0, "m", "target trolley position: the plan's end"),
    parameter("l1_low", 0.0, "m", "designs for cable lengths from l1_low to l1_high (nearest to l1_now used); "
                                  "0 with l1_high = 0: one design for l1"),
    parameter("l1_high", 0.0, "m", "longest main cable designed for"),
    *(v._replace(description=v.description.split(";")[0] + "; a constraint of its QPs: finite")
      for v in limits.parameters()),
) + MEASURED_STATE + (
    input_("l1_now", "m", "measured main cable length, for the designs' schedule; 0: not measured"),
    output("u", "m/s2", "demanded trolley acceleration: the plan's plus the tracking QP's first input, held "
                        "over the interval"),
    output("iterations", "1", "QP iterations of the last solve"),
    output("plan_end", "s", "when the planned move ends (0: no move planned)"),
)
IN = positions(VARIABLES, "input")

COMPONENT = Component(
    "MpcController", "controller",
    "Constrained model-predictive control: the shortest move to x_d within the drive's limits, planned at the "
    "start, tracked by a QP every interval (our own active-set solver); output: trolley acceleration u",
    VARIABLES, configure, _output, feedthrough=True, initial_state=initial_state, update=update, report=report)
