"""Constrained model-predictive control of the crane: the MpcController component.

Two optimisations on the crane linearised about the hanging equilibrium (the LQR's
model, :func:`.lqr.continuous_model`, held over the control interval ``T``):

1. **The plan**, at the first solve (and again when the state leaves it): the shortest move from the measured state
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

The plant may differ from the configured model (S3's unknown cables and payload): the swing's
equations of motion (8)-(9), integrated over each interval, are linear in ``(l1, l2, m2 / (m1 + m2))``;
after ``identify`` seconds of data their least-squares solution (when well posed, plausible and
explaining the data) replaces the model, and the move is planned again with it (:func:`identify`).
The move is planned again too when the measured state leaves the plan by ``replan_x`` (trolley) or
``replan_angle`` (swing, as a modal amplitude; :func:`deviation`), at most every :data:`REPLAN_GAP`. A plan after
the first swings at most :data:`PEAK_ALLOWANCE` more than the first (a longer move when the shortest would).
No move is planned from a swing larger than :data:`LARGEST_SWING` (a hard hit), where the linear model's plan
would be far off: the tracking QP alone takes the swing down, its trolley error left out (the trolley free), and
the move is planned once the swing is below :data:`PLAN_BELOW`.
With ``offset_free`` (1: the load, 2: the trolley at ``x_d``) the estimated horizontal forces ``F2_hat``, ``F1_hat``
(a StateEstimator's) enter the tracking QP as a constant disturbance in its prediction, its initial error taken
from the rest they hold (:func:`force_shift`), and the LQR it hands over to regulates to that rest; the plan and
the deviations are measured without them.

What is claimed is measured, not proven: ``crane-fmu targets`` and the scoreboard
give its figures; the plan is only as good as the linear model (a few tenths of a
degree at the end of a fast move on the nominal plant, degrees on a plant the model
does not know), which the tracking QP then removes.
"""

import dataclasses
import functools
import itertools
import math
from collections import namedtuple

from . import limits, linalg, lqr, planner, qp
from .component import Component, Step
from .lqr import DEFAULT_WEIGHTS, SCHEDULE_RULES, WEIGHTS, continuous_model
from .parameters import PLANT_RULES, plant_parameters
from .rules import check, finite, in_range, non_negative, one_of, positive, rule, whole
from .tables import CRANE_MODEL, MEASURED_STATE, controller_model, input_, output, parameter, positions

RHO = 1e6  # the plan's weight on missing the target state
REACHED = 1e-3  # the plan reaches the target when every state is this close (m, m/s, rad, rad/s)
LONGEST_PLAN = 6.0  # s: a move that needs longer is not planned (the tracking QP regulates alone)
MAX_PLAN = 1200  # the most intervals a plan may have (LONGEST_PLAN of them at least): the interval's rule
SCHEDULE_POINTS = 11
REPLAN_GAP = 0.25  # s: the least time between two plans made because the state left the plan
RETRY_GAP = 6.0  # s: ... after no move within LONGEST_PLAN was found (each attempt costs a bisection of QPs)
LARGEST_SWING = math.radians(17.5)  # rad: no move is planned from a larger swing (as a modal amplitude, deviation)
PLAN_BELOW = math.radians(16.0)  # rad: ... and, once none is held after the first solve, none until below this
# 16 deg: above S1's 10 deg start (15.6 deg), and the hard hits' times monotone in the start angle (issue 51,
# 30-70 deg; not at 17.5 deg): chosen by simulating that grid. A hysteresis: no plan is made above LARGEST_SWING
# (a plan held mid-move is no longer dropped there: see solve)
WELL_POSED = 1e-2  # ... and gives a model when no pivot of its normal equations falls below this share
MISFIT = 1e-5  # ... that explains the data to this share of their squares (0.3 % RMS): clean measurements
PLAUSIBLE = 2.0  # ... within this factor of the configured cable lengths
PLAUSIBLE_PAYLOAD = 3.0  # ... and of the configured payload
STANDARD_ERROR = 0.01  # ... each parameter's standard error at most this share of its value
UNEXPLAINED = 1e-3  # the envelope hands over to the LQR when the data leave this share of their squares (3 % RMS)
# unexplained: the states the MPC is given are not the crane's (an estimator's, noisy, late, a force it does not know).
# With ``estimated`` (the system says its state is a StateEstimator's) data that give no model (beyond MISFIT) are
# already the estimator's, not the crane's: behind an estimator of another crane (S9's #61) the misfit is 3e-5 at
# 0.15 s and past UNEXPLAINED only at 0.2 s, the fast move's 50 ms more leaving 0.15 deg of swing the cautious plan
# cannot take out. Without it a misfit between the two is a force the crane feels (S10's wind): a deviation to plan for
MOST_REPLANS = 2  # the safety envelope: past these plans for a deviation none more is made, the held plan is
# tracked to its end and the LQR takes over there
SWING_MARGIN = math.radians(10.0)  # ... or when the swing exceeds the plan's largest by this (as an amplitude)
TOLERANCE = 0.01  # ... and the controller plans again with it when a swing mode's frequency differs by more
SUSPECT_AFTER = 3  # intervals: the data are judged beyond the crane's equations (UNEXPLAINED) from this many on,
# before a model may be accepted (Config.samples): behind an estimator of another crane (S9) the misfit shows after
# 0.15 s, while a clean crane's data (S1-S3) are explained to 1e-13
# the cautious plan's weights on the fast swing mode left at the end on each crane of SPREAD, tried in turn: the first
# whose plan still reaches the target (its weight RHO) is taken
ROBUST_WEIGHTS = (1e6, 3e5, 1e5, 3e4, 1e4)
SPREAD = (0.1, 0.2, 0.2, 0.5)  # l1, l2, m1, m2: the shares by which the crane may differ from the model (the corners
# a cautious plan is robust to, as a ZVD shaper is to a frequency error): the rigging's uncertainty of the paired
# design (planar_scenarios.FACTORS)
PEAK_ALLOWANCE = math.radians(1.0)  # the safety envelope: a plan after the first (an identified model's, a
# deviation's) swings at most this more than the first (what the move asked for swings on the configured crane);
# past it the first longer move of PEAK_STRETCHES within it is taken (none: the shortest move). Half of the issue's
# 2 deg above the nominal move's peak (issue 51, item 2): the other half for what the linear plan leaves out (the
# crane swings up to 0.08 deg past its plan on S3's plants) and what disturbs the move after it
PEAK_STRETCHES = (1.1, 1.2, 1.3, 1.5, 1.7, 2.0)  # ... its moves' lengths, as shares of the shortest (or cautious)
CAUTIOUS_STRETCH = 1.3  # once the data are unexplained, every plan is this much longer than the shortest move: the
# least-effort move of that length, no longer bang-bang, excites little of the swing a wrong model leaves behind

Design = namedtuple("Design", "l1 ad bd gain qp omegas shapes")
Design.__doc__ = ("The tracking QP for one model: its cable length, ``(Ad, Bd)`` over the interval, ``F`` (N x 6) "
                  "of the linear term ``f = F e0``, the prepared QP (:func:`.qp.prepare`) and the slow swing "
                  "and the fast swing modes' angular frequencies [rad/s] and shapes (:func:`.planner.modes`).")

Config = namedtuple("Config", "designs x_d u_max v_max margin h every interval steps max_iterations plant weights r "
                              "samples replan_x replan_angle lqr memo estimated")
Config.__doc__ = ("The designs (one, or one per scheduled cable length), the target, the limits, the plan's "
                  "margin, the communication step ``h``, the steps per interval (``every``), the interval, the "
                  "horizon in intervals, the QP's cap, the configured model and weights (for the identified "
                  "model's design), the intervals the identification needs (0: none), the deviations that make "
                  "a new plan, the LQR it hands over to (:class:`.lqr.Config`, the configured model's, scheduled as "
                  "the designs are), ``memo``: the last solve, which the FMU's output and its step share, and the "
                  "identified model's design, and whether the measured state is an estimator's (``estimated``).")

# The state: a header, then the last solution du (N), the rows it held at a bound (2N codes: 0, +1 upper,
# -1 lower), the plan's inputs u* (n) and its states s* ((n + 1) x 6). The header: the step count, the held
# input, the QP's iterations, whether it warned, the plan's length, the interval it starts at, the first interval
# a plan for a deviation may be made at, the cable length of the design it was made with, the identified model
# (l1, l2, m2; 0: the configured one), and the identification's data (see identify): the last step's sample
# (_sample), the integrals since the last solve (integrate), the normal equations (n11 n12 n13 n22 n23 n33, z,
# the data's squares yy) and the intervals in them; the safety envelope's (see solve): whether the LQR has taken
# over (1: for good), the plans made for a deviation, the plan's largest swing (rad, as an amplitude), and whether the
# plans are cautious (1: the data were once unexplained, CAUTIOUS_STRETCH), and whether a swing too large to plan from
# was met with no plan held (1: a hard hit's, its plans dropped past LARGEST_SWING as before), and the first plan's
# largest swing (rad; 0: none made at the first solve), which bounds every later plan's (PEAK_ALLOWANCE).
HEADER = namedtuple("Header", "count u iterations warned plan_steps plan_start plan_after plan_l1 l1 l2 "
                              "m2 w1 w2 cos_d sin_d cos1 sin1 cos2 sin2 d1 d2 a1 a2 c1 c2 s1 s2 "
                              "n11 n12 n13 n22 n23 n33 z1 z2 z3 yy samples handed replans bound "
                              "cautious hit first")(*range(44))


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
    columns = [linalg.transpose(power) for power in powers]
    # Q b_d and b_d' Q b_e: the same numbers for every k but the last (weighted by P), so made once, not per (i, k)
    qb = [[linalg.dot(w, bk) for w in q] for bk in b]
    bqb = [[linalg.dot(wb, bk) for bk in b] for wb in qb]
    hessian = [[0.0] * steps for _ in range(steps)]
    gain = []
    for i in range(steps):
        row_f, row_h = [0.0] * 6, hessian[i]
        for k in range(i, steps):
            last = k == steps - 1
            wb = [linalg.dot(w, b[k - i]) for w in terminal] if last else qb[k - i]
            for c in range(6):
                row_f[c] += linalg.dot(wb, columns[k][c])
            for j in range(i, k + 1):
                row_h[j] += linalg.dot(wb, b[k - j]) if last else bqb[k - i][k - j]
        gain.append(row_f)
    for i in range(steps):
        hessian[i][i] += r
        for j in range(i + 1, steps):
            hessian[j][i] = hessian[i][j]
    return Design(p.l1, ad, bd, gain, qp.prepare(hessian, constraint_rows(steps, interval)),
                  *planner.modes(p)[:2])


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


def fast_mode_rows(d):
    """The rows that take a state to the fast swing mode's amplitude ``(eta, eta' / w)`` on the angle it moves most
    (as :func:`deviation`): what a plan robust to another crane must leave at rest."""
    (s11, s21), (s12, s22) = d.shapes
    det = s11 * s22 - s12 * s21
    a, b = -s21 / det, s11 / det
    scale = max(abs(s) for s in d.shapes[1])
    w = d.omegas[1]
    return ([0.0, 0.0, a * scale, 0.0, b * scale, 0.0], [0.0, 0.0, 0.0, a * scale / w, 0.0, b * scale / w])


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


def plan_move(d, s0, target, u_max, v_max, interval, max_intervals, stretch=1.0, others=()):
    """The shortest move ``(u*, s*)`` from ``s0`` to rest at ``target`` within the limits, or ``((), ())``; with
    ``stretch`` > 1 the move of ``ceil(stretch n)`` intervals (at most ``max_intervals``) instead, when it reaches
    the target (the cautious plan of the safety envelope, :data:`CAUTIOUS_STRETCH`). With ``others``
    (:func:`robust_ends`: other cranes' ``(Ad, Bd, rows)``) that longer move is first made robust to them: it minimises
    ``RHO |s_n - target|^2 + w sum_m |R_m (s_n^m - target)|^2 + |U|^2``, each other crane's fast swing mode left at
    rest at the end as well (as a ZVD shaper is robust to a frequency error), with the first weight ``w`` of
    :data:`ROBUST_WEIGHTS` whose move still reaches the target; none: the move without them.

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

    def ends(ad, bd, n):
        """Each input's effect on the end state and what the inputs must add to reach the target."""
        b = predict_rows(ad, bd, n)
        free = list(s0)
        for _ in range(n):
            free = [linalg.dot(row, free) for row in ad]
        return [b[n - 1 - j] for j in range(n)], [t - f for t, f in zip(target, free)]

    def attempt(n, robust=(), weight=0.0):
        nonlocal previous
        if n < 1:  # no move of no interval (the bisection's low end may reach 0: all() of no state is no answer)
            return False, []
        columns, miss = ends(d.ad, d.bd, n)
        hessian = [[RHO * linalg.dot(columns[i], columns[j]) + (1.0 if i == j else 0.0) for j in range(n)]
                   for i in range(n)]
        f = [-RHO * linalg.dot(columns[i], miss) for i in range(n)]
        for ad, bd, rows in robust:  # another crane's end: its rows (a swing mode's amplitude) near the target's
            other, other_miss = ends(ad, bd, n)
            other = [[linalg.dot(row, c) for row in rows] for c in other]
            other_miss = [linalg.dot(row, other_miss) for row in rows]
            for i in range(n):
                row = hessian[i]
                for j in range(n):
                    row[j] += weight * linalg.dot(other[i], other[j])
                f[i] -= weight * linalg.dot(other[i], other_miss)
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

    high = min(max(8, low + 1 + int(0.15 * low) + 4), max_intervals)
    ok, inputs = attempt(high)
    while not ok:
        if high >= max_intervals:
            return (), ()
        low, high = high, min(2 * high, max_intervals)
        ok, inputs = attempt(high)
    while high - low > 1:
        mid = (low + high) // 2
        ok, found = attempt(mid)
        if ok:
            high, inputs = mid, found
        else:
            low = mid
    if stretch > 1.0:  # the cautious plan: the least-effort move of more intervals (its |U|^2, no longer bang-bang)
        longer = min(int(math.ceil(high * stretch)), max_intervals)
        if longer > high:
            # robust to the other cranes with the largest weight that still reaches the target, else not robust
            tries = [(others, weight) for weight in ROBUST_WEIGHTS] if others else []
            for robust, weight in tries + [((), 0.0)]:
                ok, found = attempt(longer, robust, weight)
                if ok:
                    inputs = found
                    break
    states, s = [tuple(s0)], list(s0)
    for value in inputs:
        s = [linalg.dot(row, s) + bk[0] * value for row, bk in zip(d.ad, d.bd)]
        states.append(tuple(s))
    return tuple(inputs), tuple(states)


def configure(values):
    """Validated parameters and the tracking designs (one, or one per scheduled cable length).

    After :data:`RULES`, the rules that need the interval and the horizon counted in steps (code).
    """
    check(RULES, values)
    p = plant_parameters(values)
    margin, cap, identify = values["margin"], values["max_iterations"], values["identify"]
    u_max, v_max = limits.of(values)
    h = values["h"]
    every = max(1, round(values["interval"] / h))
    interval = every * h
    steps = max(1, round(values["horizon"] / interval))
    if steps > 200:
        raise ValueError(f"horizon must be at most 200 intervals, got {values['horizon']!r} s = {steps} intervals "
                         f"of {interval!r} s")
    if int(LONGEST_PLAN / interval) > MAX_PLAN:
        raise ValueError(f"interval must be at least {LONGEST_PLAN / MAX_PLAN!r} s (a plan of at most {MAX_PLAN} "
                         f"intervals), got {interval!r} s")
    weights = [values[name] for name in WEIGHTS]
    low, high = values["l1_low"], values["l1_high"]
    if (low, high) == (0.0, 0.0):
        lengths = [p.l1]
    else:
        lengths = [low + (high - low) * i / (SCHEDULE_POINTS - 1) for i in range(SCHEDULE_POINTS)]
    designs = tuple(design(dataclasses.replace(p, l1=length), weights, values["r"], interval, steps)
                    for length in lengths)
    samples = max(1, round(identify / interval)) if identify > 0 and len(designs) == 1 else 0
    gains = lqr.design(p, weights, values["r"], h)  # the LQR it hands over to: the LqrController's law (lqr.control)
    schedule = None if len(lengths) == 1 else \
        (lengths, [lqr.design(dataclasses.replace(p, l1=length), weights, values["r"], h) for length in lengths])
    own_lqr = lqr.Config(gains=gains, x_d=values["x_d"], u_max=u_max, v_max=v_max, h=h, schedule=schedule,
                         offset_free=values["offset_free"], plant=p)
    return Config(designs=designs, x_d=values["x_d"], u_max=u_max, v_max=v_max, margin=margin, h=h, every=every,
                  interval=interval, steps=steps, max_iterations=int(cap), plant=p, weights=weights, r=values["r"],
                  samples=samples, replan_x=values["replan_x"], replan_angle=values["replan_angle"], lqr=own_lqr,
                  memo={}, estimated=values["estimated"])


def nearest_design(config, l1):
    """The design for the cable length nearest the measured ``l1`` (the only one without a schedule)."""
    designs = config.designs
    if len(designs) == 1 or not l1 > 0:
        return designs[0] if len(designs) == 1 else designs[len(designs) // 2]
    return min(designs, key=lambda d: abs(d.l1 - l1))


def identified_design(config, model):
    """The design for the identified model ``(l1, l2, m2)`` (the configured ``m1 + m2`` kept), made once."""
    cache = config.memo.setdefault("designs", {})
    if model not in cache:
        mu = config.plant.m1 + config.plant.m2
        p = dataclasses.replace(config.plant, l1=model[0], l2=model[1], m2=model[2], m1=mu - model[2])
        cache[model] = design(p, config.weights, config.r, config.interval, config.steps)
    return cache[model]


def robust_ends(config, known):
    """``[(Ad, Bd, rows)]`` of the cranes at the corners of :data:`SPREAD` about the model ``known`` (``(l1, l2, m2)``,
    the configured ``m1 + m2`` kept; zeros: the configured crane), each with its :func:`fast_mode_rows`: the ends a
    cautious plan leaves at rest besides its own (made once)."""
    cache = config.memo.setdefault("corners", {})
    if known not in cache:
        p = config.plant
        if known[0] > 0.0:
            mu = p.m1 + p.m2
            p = dataclasses.replace(p, l1=known[0], l2=known[1], m2=known[2], m1=mu - known[2])
        ends = []
        for a, b, c, e in itertools.product(*((1.0 - share, 1.0 + share) for share in SPREAD)):
            corner = dataclasses.replace(p, l1=p.l1 * a, l2=p.l2 * b, m1=p.m1 * c, m2=p.m2 * e)
            ad, bd = linalg.zoh(*continuous_model(corner), config.interval)
            omegas, shapes = planner.modes(corner)[:2]
            ends.append((ad, bd, fast_mode_rows(Design(corner.l1, ad, bd, None, None, omegas, shapes))))
        cache[known] = ends
    return cache[known]


def initial_state(config):
    n = config.steps
    return (0.0,) * len(HEADER) + (0.0,) * n + (0.0,) * (2 * n)


def _plan_of(config, state):
    """``(u*, s*)`` stored in ``state``."""
    n, start = int(state[HEADER.plan_steps]), len(HEADER) + 3 * config.steps
    inputs = state[start:start + n]
    flat = state[start + n:]
    return inputs, [flat[6 * k:6 * k + 6] for k in range(len(flat) // 6)]


def _sample(measured):
    """What the identification keeps of a measured state: ``w1, w2, cos d, sin d, cos th1, sin th1, cos th2, sin th2``
    with ``d = th1 - th2``."""
    theta1, w1, theta2, w2 = measured[2:6]
    d = theta1 - theta2
    return (w1, w2, math.cos(d), math.sin(d), math.cos(theta1), math.sin(theta1), math.cos(theta2), math.sin(theta2))


def integrate(h, integrals, before, now):
    """The identification's integrals over an interval, one communication step further (trapezoidal rule).

    ``integrals``: ``(D1, D2, A1, A2, C1, C2, S1, S2)``, see :func:`identify`; ``before`` and
    ``now``: :func:`_sample` of the step's two ends.
    """
    w1a, w2a, cda, sda, c1a, s1a, c2a, s2a = before
    w1b, w2b, cdb, sdb, c1b, s1b, c2b, s2b = now
    half = 0.5 * h
    cd = 0.5 * (cda + cdb)
    d1, d2, a1, a2, c1, c2, s1, s2 = integrals
    return (d1 + (w1b - w1a), d2 + (w2b - w2a),
            a1 + (cd * (w1b - w1a) - half * (w1a * w1a * sda + w1b * w1b * sdb)),
            a2 + (cd * (w2b - w2a) + half * (w2a * w2a * sda + w2b * w2b * sdb)),
            c1 + half * (c1a + c1b), c2 + half * (c2a + c2b), s1 + half * (s1a + s1b), s2 + half * (s2a + s2b))


def _identifying(config, state):
    """Whether the model is still to be identified (identification on, no model found yet)."""
    return config.samples > 0 and state[HEADER.l1] == 0.0


def identify(config, state, measured):
    """The identification's normal equations with the interval that ends now, the model they give (or None), and
    whether the data are beyond any crane's equations (their least-squares residual above :data:`UNEXPLAINED`; with
    :attr:`Config.estimated`, above :data:`MISFIT`: data that give no model are the estimator's).

    Notes
    -----
    Eqs (8)-(9) (eq (8) divided by ``m1 + m2``) are linear in ``(l1, l2, k)``, ``k = l2 m2 / (m1 + m2)``::

        l1 w1' + k (cos d w2' + w2^2 sin d) = -u cos th1 - g sin th1
        l1 (cos d w1' - w1^2 sin d) + l2 w2' = -u cos th2 - g sin th2,    d = th1 - th2

    Integrated over an interval, in which ``u`` is held, with ``D1``, ``D2`` the rates' changes,
    ``A1 = int (cos d w1' - w1^2 sin d) dt``, ``A2 = int (cos d w2' + w2^2 sin d) dt``,
    ``C_i = int cos th_i dt`` and ``S_i = int sin th_i dt`` (trapezoidal sums over the
    communication steps, :func:`integrate`), each interval gives two rows::

        (D1, 0, A2) (l1, l2, k)' = -u C1 - g S1,     (A1, D2, 0) (l1, l2, k)' = -u C2 - g S2

    Whether the data are unexplained is judged from :data:`SUSPECT_AFTER` intervals on (or
    :attr:`Config.samples`, when fewer). The model is the least-squares solution of the intervals so far, given once
    :attr:`Config.samples` intervals are in and no pivot of the normal equations' Cholesky
    factor falls below :data:`WELL_POSED` of its diagonal, when consistent (the safety envelope): each
    length within a factor :data:`PLAUSIBLE` of the configured one, ``0 < k < l2``, the payload within
    :data:`PLAUSIBLE_PAYLOAD` of the configured one, the residual within :data:`MISFIT` of the data and
    each parameter's standard error within :data:`STANDARD_ERROR` of it (:func:`precise`). Otherwise
    the model stays the last good one (the configured one) and the data go on being gathered.
    """
    c, s = config, state
    first = HEADER.n11
    sums = list(s[first:first + 11])
    if not _identifying(c, s):  # off, or done: nothing more to add
        return sums, None, False
    if s[HEADER.count] > 0:
        d1, d2, a1, a2, c1, c2, s1, s2 = integrate(c.h, s[HEADER.d1:HEADER.s2 + 1], s[HEADER.w1:HEADER.sin2 + 1],
                                                   _sample(measured))
        u, g = s[HEADER.u], c.plant.g
        y1, y2 = -u * c1 - g * s1, -u * c2 - g * s2
        sums[0] += d1 * d1 + a1 * a1
        sums[1] += a1 * d2
        sums[2] += d1 * a2
        sums[3] += d2 * d2
        sums[5] += a2 * a2
        sums[6] += d1 * y1 + a1 * y2
        sums[7] += d2 * y2
        sums[8] += a2 * y1
        sums[9] += y1 * y1 + y2 * y2
        sums[10] += 1.0
    model, unexplained = None, False
    if sums[10] >= min(c.samples, SUSPECT_AFTER):
        n11, n12, n13, n22, n23, n33, z1, z2, z3, yy, _ = sums
        normal = [[n11, n12, n13], [n12, n22, n23], [n13, n23, n33]]
        try:
            factor = qp.cholesky(normal)
        except ArithmeticError:
            factor = None
        if factor is not None and min(factor[i][i] * factor[i][i] / normal[i][i] for i in range(3)) >= WELL_POSED:
            l1, l2, k = qp.cholesky_solve(factor, [z1, z2, z3])
            misfit = (yy - (l1 * z1 + l2 * z2 + k * z3)) / yy  # the residual's share of the data's squares
            unexplained = misfit > (MISFIT if c.estimated else UNEXPLAINED)
            p = c.plant
            plausible = all(b / PLAUSIBLE <= a <= b * PLAUSIBLE for a, b in ((l1, p.l1), (l2, p.l2)))
            if sums[10] >= c.samples and misfit <= MISFIT and plausible and 0.0 < k < l2:
                m2 = (p.m1 + p.m2) * k / l2
                residual = yy - (l1 * z1 + l2 * z2 + k * z3)
                if p.m2 / PLAUSIBLE_PAYLOAD <= m2 <= p.m2 * PLAUSIBLE_PAYLOAD and \
                        precise(factor, (l1, l2, k), residual, 2.0 * sums[10]):
                    model = (l1, l2, m2)
    return sums, model, unexplained


def precise(factor, values, residual, rows):
    """Whether each of the least-squares ``values`` has a standard error within :data:`STANDARD_ERROR` of itself.

    The variance of ``values[i]`` is ``sigma^2 (N^-1)_ii`` with ``sigma^2 = residual / (rows - 3)``, ``N`` the
    normal equations (``factor``: their Cholesky factor) and ``residual`` the least-squares residual's square.
    """
    variance = residual / max(rows - 3.0, 1.0)
    for i, value in enumerate(values):
        inverse = qp.cholesky_solve(factor, [1.0 if j == i else 0.0 for j in range(3)])[i]
        bound = STANDARD_ERROR * value
        if variance * inverse > bound * bound:
            return False
    return True


def deviation(d, measured, ref):
    """How far the measured state is from the plan's: ``(trolley [m], swing [rad])``.

    The trolley's: the amplitude ``sqrt(e^2 + (e' / w)^2)`` of its position and speed errors
    taken as a swing of the slow mode's frequency ``w``. The swing's: the angles' and rates'
    errors split into the design's two swing modes, each mode's amplitude on the angle it moves
    most, added: the largest swing the deviation would make left alone (linear model).
    """
    e = [a - b for a, b in zip(measured, ref)]
    w = d.omegas[0]
    trolley = math.sqrt(e[0] * e[0] + (e[1] / w) * (e[1] / w))
    (s11, s21), (s12, s22) = d.shapes
    det = s11 * s22 - s12 * s21
    swing = 0.0
    for k, (a, b) in enumerate(((s22, -s12), (-s21, s11))):  # rows of the shapes' inverse
        eta, rate = (a * e[2] + b * e[4]) / det, (a * e[3] + b * e[5]) / det
        swing += math.sqrt(eta * eta + (rate / d.omegas[k]) * (rate / d.omegas[k])) * max(abs(s) for s in d.shapes[k])
    return trolley, swing


def force_shift(config, forces):
    """What the estimated forces ``(F2_hat, F1_hat)`` take off the tracking QP's initial error: the rest they hold
    (:func:`.lqr.force_target` on the configured model, as the LQR's target moves), or nothing (``offset_free`` 0 or
    no force).

    A constant force ``F`` adds ``E F`` to the linear model's ``s' = A s + B u``; its rest ``s_F`` (``u = 0``) has
    ``A s_F + E F = 0`` (and any trolley position), so ``e - s_F`` obeys the model without the force: the initial
    error shifted by ``s_F`` is the prediction with the constant disturbance in it.
    """
    mode = config.lqr.offset_free
    if mode == 0.0 or (forces[0] == 0.0 and forces[1] == 0.0):
        return None
    dx, theta1, theta2 = lqr.force_target(config.plant, *forces)
    return (dx if mode == 1.0 else 0.0, 0.0, theta1, 0.0, theta2, 0.0)


def solve(config, state, measured, l1_now, forces=(0.0, 0.0)):
    """One solve: ``(u, new state without the count, messages)`` from the measured state and the estimated forces
    (``F2_hat``, ``F1_hat``: :func:`force_shift`; the LQR handed over to gets them too)."""
    c, n = config, config.steps
    count = int(state[HEADER.count])
    at = count // c.every  # this interval's number
    sums, model, unexplained = identify(c, state, measured)
    known = (state[HEADER.l1], state[HEADER.l2], state[HEADER.m2])
    d = identified_design(c, known) if known[0] > 0.0 else nearest_design(c, l1_now)
    if model is not None:  # identified: a new design and plan when a swing mode's frequency moved
        found = identified_design(c, model)
        known = model
        if max(abs(a - b) / b for a, b in zip(found.omegas, d.omegas)) <= TOLERANCE:
            model = None
        d = found
    target = (c.x_d, 0.0, 0.0, 0.0, 0.0, 0.0)
    plan_u, plan_s = _plan_of(c, state)
    plan_start, plan_after = int(state[HEADER.plan_start]), int(state[HEADER.plan_after])
    step = at - plan_start
    ref_s = plan_s[step] if count and step < len(plan_s) else target
    trolley, swing = deviation(d, measured, ref_s)
    rescheduled = len(c.designs) > 1 and d.l1 != state[HEADER.plan_l1]  # the schedule's design changed
    moved = trolley > c.replan_x or swing > c.replan_angle or rescheduled
    replan = count == 0 or model is not None or (moved and at >= plan_after)
    # the safety envelope: data the crane's equations do not explain (an estimator of another crane, noise) make
    # every plan from now on cautious, the first at once (it is no plan for a deviation)
    cautious = state[HEADER.cautious]
    warned_now = unexplained and not cautious
    if warned_now:
        cautious, replan = 1.0, True
    to_trolley, to_rest = deviation(d, measured, target)
    over = step >= len(plan_u)
    # too far from rest for the linear model's plan; with none held after the first solve (the large swing's
    # phase), planned again only below PLAN_BELOW. A plan held mid-move is not dropped for it: its own swing comes
    # near LARGEST_SWING (S2's 15.8 deg), a gust or a wrong model's few degrees more are a deviation to plan again
    # for, and beyond its largest by SWING_MARGIN the LQR takes over (dropped, the tracking QP alone with the
    # trolley free swung S10's case #57 to 26 deg). After a hard hit's large swing (hit) its plans are dropped there
    # as before: the hard hits' times stay monotone in the start angle
    hit = state[HEADER.hit]
    large = not (count and plan_u and not over and not hit) and \
        to_rest > (PLAN_BELOW if count and not plan_u else LARGEST_SWING)
    # the safety envelope: the LQR takes over, for good, when the plan is over and the identification's data are
    # beyond the crane's equations or the plans for a deviation have run out (mid-move the LQR's kick would swing
    # more than the plan's end), the swing grows past the plan's largest by SWING_MARGIN, or the crane is at rest on
    # the target
    replans = state[HEADER.replans]
    # a plan for a deviation needs a plan to deviate from: the first after the large swing's phase is none
    if replan and count and model is None and not warned_now and not large and plan_u and \
            (trolley > c.replan_x or swing > c.replan_angle):
        replans += 1.0
    at_rest = over and to_trolley <= c.replan_x and to_rest <= c.replan_angle
    swung = bool(plan_u) and to_rest > state[HEADER.bound] + SWING_MARGIN  # past the plan's largest (a plan made)
    spent = replans > MOST_REPLANS
    if spent and not over and not swung:  # the plans for a deviation run out mid-move: the held plan is tracked to
        # its end, no other made (an identified model's aside); the LQR's kick at speed had left S10's cases #24 and
        # #54 swinging more than the LQR alone, 5 s later
        replan, replans = model is not None, float(MOST_REPLANS + 1)
    elif count and ((unexplained and over) or spent or swung or at_rest):
        return handover(c, state, measured, l1_now, replans, forces, cautious)
    bound, first = state[HEADER.bound], state[HEADER.first]
    if replan and large:  # none made: the tracking QP takes the swing down alone, a plan is tried at the next interval
        replan = bool(plan_u) or model is not None  # the last solve's warm start holds unless a plan or model changed
        plan_u, plan_s = (), ()
        plan_start, step, plan_after = at, 0, at
        bound, hit = to_rest, 1.0
    elif replan:
        shrink = 1.0 - c.margin
        stretch, corners = (CAUTIOUS_STRETCH, robust_ends(c, known)) if cautious else (1.0, ())
        plan = functools.partial(plan_move, d, measured, target, c.u_max * shrink, c.v_max * shrink, c.interval,
                                 int(LONGEST_PLAN / c.interval), others=corners)
        plan_u, plan_s = plan(stretch)
        if not count:  # the first plan's largest swing: what the move asked for swings on the configured crane
            first = _largest(plan_s)
        elif first > 0.0 and _largest(plan_s) > first + PEAK_ALLOWANCE:
            for longer in PEAK_STRETCHES:  # the first longer move within the first plan's swing
                found = plan(stretch * longer)
                if found[0] and _largest(found[1]) <= first + PEAK_ALLOWANCE:
                    plan_u, plan_s = found
                    break
        plan_start, step = at, 0
        bound = max(to_rest, _largest(plan_s))
        if plan_u:  # a move: the next one (for a deviation) waits REPLAN_GAP
            plan_after = at + round(REPLAN_GAP / c.interval)
        elif max(abs(a - b) for a, b in zip(measured, target)) > REACHED:  # none within LONGEST_PLAN:
            plan_after = at + round(RETRY_GAP / c.interval)  # the tracking QP regulates alone a while
    ref_u = [plan_u[step + k] if step + k < len(plan_u) else 0.0 for k in range(n)]
    ref_s = plan_s[step] if step < len(plan_s) else target
    e0 = [a - b for a, b in zip(measured, ref_s)]
    shift = force_shift(c, forces)
    if shift is not None:  # offset-free: the error from the rest the forces hold (the disturbance in the prediction)
        e0 = [e - s for e, s in zip(e0, shift)]
    if large and not plan_u:  # the trolley left free while the swing is taken down
        e0[0] = 0.0
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
    shifted = count and not replan
    guess = [ref_u[k] + (previous[k + 1] if k + 1 < n else 0.0) for k in range(n)] if shifted else ref_u
    absolute = feasible_start(guess, v0, [-c.u_max] * n, [c.u_max] * n, c.v_max, c.u_max, c.interval)
    start = [a - b for a, b in zip(absolute, ref_u)]
    hint = []
    if shifted:
        codes = state[len(HEADER) + n:len(HEADER) + 3 * n]
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
    plan_part = (tuple(plan_u) + tuple(v for s in plan_s for v in s)) if replan else \
        state[len(HEADER) + 3 * n:]
    header = (u, float(solution.iterations), warned, float(len(plan_u)), float(plan_start), float(plan_after),
              d.l1 if replan else state[HEADER.plan_l1], *known, *_sample(measured), *(0.0,) * 8, *sums, 0.0,
              replans, bound, cautious, hit, first)
    return u, header + tuple(solution.x) + tuple(new_codes) + plan_part, messages


def _largest(plan_s):
    """A plan's largest swing [rad]: the largest of its angles (0: no plan)."""
    return max((max(abs(s[2]), abs(s[4])) for s in plan_s), default=0.0)


def handover(config, state, measured, l1_now, replans, forces=(0.0, 0.0), cautious=None):
    """The solve that hands over to the LQR: its input (:func:`.lqr.control`, the forces given), the state kept but
    marked (and whether it had turned cautious; None: as the state holds)."""
    u = lqr.control(config.lqr, measured, l1=l1_now, forces=forces)
    header = list(state[1:len(HEADER)])
    header[HEADER.u - 1], header[HEADER.iterations - 1] = u, 0.0
    header[HEADER.handed - 1], header[HEADER.replans - 1] = 1.0, replans
    if cautious is not None:
        header[HEADER.cautious - 1] = cautious
    return u, tuple(header) + state[len(HEADER):], ()


def _solved(config, state, inputs):
    """The solve at this state and these inputs (shared by the output and the step through ``memo``)."""
    memo = config.memo
    if memo.get("state") is not state or memo.get("inputs") != inputs:
        memo["state"], memo["inputs"] = state, inputs
        memo["value"] = solve(config, state, inputs[IN.x:IN.dtheta2 + 1], inputs[IN.l1_now],
                              (inputs[IN.F2_hat], inputs[IN.F1_hat]))
    return memo["value"]


def _due(config, state):
    return int(state[HEADER.count]) % config.every == 0


def _plan_end(config, state):
    return (state[HEADER.plan_start] + state[HEADER.plan_steps]) * config.interval if state[HEADER.plan_steps] \
        else 0.0


def _output(config, state, inputs):
    if state[HEADER.handed]:  # the LQR's, every step
        u = lqr.control(config.lqr, inputs[IN.x:IN.dtheta2 + 1], l1=inputs[IN.l1_now],
                        forces=(inputs[IN.F2_hat], inputs[IN.F1_hat]))
        return u, 0.0, _plan_end(config, state)
    if _due(config, state):
        _, rest, _ = _solved(config, state, inputs)
        state = (state[HEADER.count],) + rest
    return state[HEADER.u], state[HEADER.iterations], _plan_end(config, state)


def update(config, state, inputs, time, step):
    """Count the step and add it to the identification's integrals; after a solve keep its input (held until the
    next), its solution, the plan and the identification's sums. Once the LQR has taken over: the count alone."""
    if not _due(config, state) or state[HEADER.handed]:
        if state[HEADER.handed] or not _identifying(config, state):
            return (state[HEADER.count] + 1.0,) + state[1:]
        now = _sample(inputs[IN.x:IN.dtheta2 + 1])
        integrals = integrate(config.h, state[HEADER.d1:HEADER.s2 + 1], state[HEADER.w1:HEADER.sin2 + 1], now)
        return (state[HEADER.count] + 1.0,) + state[1:HEADER.w1] + now + integrals + state[HEADER.s2 + 1:]
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
    parameter("identify", 0.3, "s", "swing data the plant's model is identified from (then planned again with "
                                    "it); 0: never (nor with a schedule of l1)"),
    parameter("replan_x", 0.03, "m", "the trolley's deviation from the plan (as a swing amplitude) that makes a "
                                     "new plan"),
    parameter("replan_angle", math.radians(2.0), "rad", "a swing angle's deviation from the plan (as an amplitude) "
                                                       "that makes a new plan"),
    parameter("max_iterations", 200.0, "1", "QP iteration cap: at the cap u is the best feasible input (warned "
                                            "once)"),
    parameter("h", 1e-3, "s", "communication step (the interval is a whole number of them)"),
    parameter("x_d", 0.0, "m", "target trolley position: the plan's end"),
    parameter("l1_low", 0.0, "m", "designs for cable lengths from l1_low to l1_high (nearest to l1_now used); "
                                  "0 with l1_high = 0: one design for l1"),
    parameter("l1_high", 0.0, "m", "longest main cable designed for"),
    parameter("estimated", 0.0, "1", "1: the measured state is a StateEstimator's (part of it not measured): data the "
                                      "identification cannot fit to a model make the plans cautious at once; 0: only "
                                      "data far beyond any crane's"),
    parameter("offset_free", 0.0, "1", "the estimated forces F2_hat, F1_hat: 0 ignored; 1 the load, 2 the trolley "
                                       "held at x_d: the tracking QP's error from the rest they hold (the constant "
                                       "force in its prediction), and its LQR's target (offset-free)"),
    *(v._replace(description=v.description.split(";")[0] + "; a constraint of its QPs: finite")
      for v in limits.parameters()),
) + MEASURED_STATE + (
    input_("l1_now", "m", "measured main cable length, for the designs' schedule; 0: not measured"),
    input_("F2_hat", "N", "estimated horizontal force on the payload (a StateEstimator's); unconnected: 0, none"),
    input_("F1_hat", "N", "estimated horizontal force on the hook (a StateEstimator's); unconnected: 0, none"),
    output("u", "m/s2", "demanded trolley acceleration: the plan's plus the tracking QP's first input, held "
                        "over the interval"),
    output("iterations", "1", "QP iterations of the last solve"),
    output("plan_end", "s", "when the planned move ends (0: no move planned)"),
)
IN = positions(VARIABLES, "input")
RULES = (*PLANT_RULES, *non_negative(*WEIGHTS), *positive("r", "h", "interval", "horizon", "replan_x", "replan_angle"),
         in_range("margin", 0, 1, high_open=True),
         whole("max_iterations", "max_iterations >= 1", "a whole number >= 1"),
         *non_negative("identify"), *finite("x_d"), *limits.RULES,
         rule("finite(unlimited(u_max)) and finite(unlimited(v_max))",
              "u_max and v_max must be finite (the MPC's constraints), got {unlimited(u_max)}, {unlimited(v_max)}"),
         *SCHEDULE_RULES, one_of("estimated", (0.0, 1.0), "0 (a measured state) or 1 (a StateEstimator's)"),
         one_of("offset_free", tuple(lqr.OFFSET_FREE),
                "0 (the forces ignored), 1 (the load at x_d) or 2 (the trolley at x_d)"),
         rule("m2 > 0", "m2 must be > 0 when offset_free != 0 (a force on a payload of no mass), got {m2}",
              when="offset_free != 0"))  # checked in this order (rules.py), then configure()'s own

COMPONENT = Component(
    "MpcController", "controller",
    "Constrained model-predictive control: the shortest move to x_d within the drive's limits, planned at the "
    "start, tracked by a QP every interval (our own active-set solver); output: trolley acceleration u",
    VARIABLES, configure, _output, feedthrough=True, initial_state=initial_state, update=update, report=report,
    crane_model=CRANE_MODEL, native="mpc.c", rules=RULES)
