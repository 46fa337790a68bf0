"""Input-shaped point-to-point moves: the TrajectoryPlanner component.

The reference is a rest-to-rest move from ``x0`` to ``x_d`` whose acceleration
is a bang-coast-bang profile convolved with an input shaper for each of the two
swing modes of the linearised double pendulum (:func:`crane_fmu.model.plant.linearisation`).
The shapers' impulses are positive and sum to one, so the shaped reference keeps
the base profile's speed and distance; the base acceleration is the largest
whose shaped acceleration stays within ``u_max``. Besides ``x_ref``, ``dx_ref``
and ``ddx_ref``, the planner gives the swing the reference induces in the
linear model while the move lasts (zero after it), so a tracking controller
feeds back only the deviation from the planned motion.

Shapers (Singhose, Seering, Singer, "Residual vibration reduction using vector
diagrams to generate shaped inputs", J. Mech. Des. 116, 1994), for an undamped
mode of period ``T``:

- ``zv``: impulses 1/2, 1/2 at 0, T/2 (zero residual swing at the design frequency);
- ``zvd``: 1/4, 1/2, 1/4 at 0, T/2, T (also zero derivative: robust to frequency errors);
- ``ei``: (1+V)/4, (1-V)/2, (1+V)/4 at 0, T/2, T with V = 5 % (extra insensitive:
  at most 5 % residual over a wider frequency band);
- ``none``: the unshaped time-optimal bang-coast-bang move.

Besides the shapers, ``shortest``: no shaper but the least-time rest-to-rest move of the linear crane itself, the
floor's kind of move (the analysis' floor.py): the MPC's plan (:func:`crane_fmu.model.mpc.plan_move`, the
acceleration held over :data:`PLAN_INTERVAL`, ``|u| <= u_max`` and ``|v| <= v_max``, the fewest intervals that end at
rest), or with ``stretch`` > 1 its least-effort move of ``ceil(stretch n)`` intervals (no longer bang-bang: a smaller
swing, which a tracking controller follows more closely on the nonlinear crane). Its held steps are the jumps of the
same closed form, so its reference and induced swing are exact on the planner's linear model. It may start from a
swing (``theta1_0`` ... ``dtheta2_0``, the linear model's at ``t0``): the plan then takes that swing to rest too
(regulation: ``x_d = x0``), and the reference adds the swing's own motion, each mode ``eta_k'' = -w_k^2 eta_k`` from
its start, to the closed form. With ``plan_from = measured`` that swing is not told but measured: the inputs
``theta1_now`` ... ``dtheta2_now`` (the axis' measured swing, connected from the plant) read at the first
communication step (before it, at ``t0``'s outputs, the inputs then: the output reads them), as the MPC plans from
the measured state at its first solve; the plan is then the one the parameters ``theta1_0`` ... would give, bit for bit.
"""

import math
from collections import namedtuple

from . import limits, linalg
from .component import Component
from .parameters import PLANT_RULES, plant_parameters
from .plant import linearisation
from .rules import check, finite, in_range, one_of, rule
from .tables import CRANE_MODEL, PLANT_MODEL, enumeration, input_, output, parameter, state_variables

EI_TOLERANCE = 0.05
# A time at most this much (relative, of at least 1 s) past a step of the plan counts as at it, before it: the
# rounding of a host that adds up its steps (OMSimulator) then switches where an exact time k h does (the 2 m move's
# first switch is at 0.125 s, which 125 steps of 1 ms add up to 0.12500000000000008).
TIME_ROUNDING = 1e-9
SHAPERS = ("zv", "zvd", "ei", "none", "shortest")
# The Enumeration type Shaper's items in the order of their values 1 to 5 (modelDescription.xml's TypeDefinitions)
SHAPER_ITEMS = ("none", "zv", "zvd", "ei", "shortest")
PLAN_INTERVAL = 0.05  # s: the shortest move's hold, the MpcController's default interval
START = ("theta1_0", "dtheta1_0", "theta2_0", "dtheta2_0")  # the swing the shortest move starts from
PLAN_FROM = ("parameters", "measured")  # where that swing comes from: the parameters START, or the inputs MEASURED
# the inputs of the measured swing, in START's order: named as the controllers' l1_now (measured now), not as the
# plant's outputs, which would connect them by name in every system with a planner (connections are written out)
MEASURED = ("theta1_now", "dtheta1_now", "theta2_now", "dtheta2_now")


def shaper(kind, period):
    """``[(time, amplitude)]`` of one mode's shaper."""
    if kind == "zv":
        return [(0.0, 0.5), (period / 2, 0.5)]
    if kind == "zvd":
        return [(0.0, 0.25), (period / 2, 0.5), (period, 0.25)]
    if kind == "ei":
        v = EI_TOLERANCE
        return [(0.0, (1 + v) / 4), (period / 2, (1 - v) / 2), (period, (1 + v) / 4)]
    return [(0.0, 1.0)]


def convolve(a, b):
    """The impulse sequence of two shapers applied one after the other."""
    return sorted((ta + tb, aa * ab) for ta, aa in a for tb, ab in b)


def modes(p):
    """``(omegas, shapes, gains)``: the swing modes of ``q'' = -W q - w u``.

    ``q = sum_k shapes[k] eta_k`` with ``eta_k'' = -omegas[k]^2 eta_k - gains[k] u``.
    """
    ((a, b), (c, d)), w = linearisation(p)
    half_trace, det = (a + d) / 2, a * d - b * c
    root = math.sqrt(half_trace * half_trace - det)
    lambdas = (half_trace - root, half_trace + root)
    shapes = [(b, lam - a) if b != 0 else (lam - d, c) for lam in lambdas]  # (W - lam I) v = 0
    (v11, v21), (v12, v22) = shapes
    det_v = v11 * v22 - v12 * v21
    gains = ((v22 * w[0] - v12 * w[1]) / det_v, (-v21 * w[0] + v11 * w[1]) / det_v)
    return tuple(math.sqrt(lam) for lam in lambdas), shapes, gains


def _base(distance, accel, speed):
    """``(t_a, t_c)``: accelerating and cruising times of the bang-coast-bang move."""
    t_a = speed / accel
    if distance < speed * t_a:  # no cruise: a triangle
        return math.sqrt(distance / accel), 0.0
    return t_a, distance / speed - t_a


def _accel_steps(impulses, accel, t_a, t_c):
    """The shaped acceleration as steps ``[(time, jump)]``."""
    steps = []
    for t, amp in impulses:
        steps += [(t, amp * accel), (t + t_a, -amp * accel), (t + t_a + t_c, -amp * accel),
                  (t + 2 * t_a + t_c, amp * accel)]
    return sorted(steps)


def _peak(steps):
    level, peak = 0.0, 0.0
    for _, jump in steps:
        level += jump
        peak = max(peak, abs(level))
    return peak


class _Model(namedtuple("_Model", "ad bd")):
    """The discrete model a plan is made on (:func:`crane_fmu.model.mpc.plan_move` reads ``ad`` and ``bd``)."""


def shortest_steps(p, distance, u_max, v_max, stretch, start=(0.0,) * 4):
    """``(steps, duration)`` of the shortest move by ``distance`` to rest from the swing ``start`` (``theta1, dtheta1,
    theta2, dtheta2``; default: rest) (``shortest``): the held
    accelerations of :func:`crane_fmu.model.mpc.plan_move` on the zero-order hold of :func:`.lqr.continuous_model`
    over :data:`PLAN_INTERVAL`, as jumps ``[(time from the start, jump)]`` (none where the input holds its value);
    ``([], 0.0)`` for no move."""
    from . import lqr, mpc  # they import this module

    ad, bd = linalg.zoh(*lqr.continuous_model(p), PLAN_INTERVAL)
    inputs, _ = mpc.plan_move(_Model(ad, bd), (0.0, 0.0, *start), (distance, 0.0, 0.0, 0.0, 0.0, 0.0), u_max, v_max,
                              PLAN_INTERVAL, mpc.MAX_PLAN, stretch)
    if not inputs and max(abs(distance), *map(abs, start)) > mpc.REACHED:
        raise ValueError(f"shaper shortest: no move of x_d - x0 = {distance!r} m to rest within "
                         f"{mpc.MAX_PLAN * PLAN_INTERVAL:g} s")
    steps, level = [], 0.0
    for k, u in enumerate((*inputs, 0.0)):
        if u != level:
            steps.append((k * PLAN_INTERVAL, u - level))
            level = u
    return steps, len(inputs) * PLAN_INTERVAL


Config = namedtuple("Config", "x0 distance t0 steps end omegas shapes gains u_max v_max impulses free measured",
                    defaults=(None, None))
Config.__doc__ = ("The plan; ``free``: the modal swing ``(eta, deta)`` at ``t0`` a shortest move starts from, or None; "
                  "``measured``: with ``plan_from = measured``, the :class:`Measured` plans from the measured swing.")


class Measured:
    """The plans of ``plan_from = measured``: ``plan(start)`` is :func:`configure`'s from the parameters with the swing
    ``start`` (``theta1, dtheta1, theta2, dtheta2``) as ``theta1_0`` ... (a swing that is not finite refused, naming
    the value), made once per swing."""

    def __init__(self, values):
        self.values, self.plans = dict(values), {}

    def plan(self, start):
        start = tuple(start)
        for name, value in zip(MEASURED, start):
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite (the measured swing the plan starts from), got {value!r}")
        if start not in self.plans:
            self.plans[start] = configure({**self.values, **dict(zip(START, start)), "plan_from": "parameters"})
        return self.plans[start]


def configure(values):
    check(RULES, values)
    if values["plan_from"] == "measured":  # planned from the inputs at the first step (:func:`plan`)
        return configure({**values, "plan_from": "parameters"})._replace(measured=Measured(values))
    p = plant_parameters(values)
    u_max, v_max = limits.of(values)
    omegas, shapes, gains = modes(p)
    impulses = convolve(shaper(values["shaper"], 2 * math.pi / omegas[0]),
                        shaper(values["shaper"], 2 * math.pi / omegas[1]))
    distance = values["x_d"] - values["x0"]
    sign, distance_abs = (1.0 if distance >= 0 else -1.0), abs(distance)
    accel, steps, t_a, t_c = u_max, [], 0.0, 0.0
    if values["shaper"] == "shortest":
        start = tuple(values[name] for name in START)
        steps, duration = shortest_steps(p, distance, u_max, v_max, values["stretch"], start)
        steps = [(values["t0"] + t, jump) for t, jump in steps]
        free = None
        if any(start):  # q = S eta: eta = S^-1 q, for the angles and their rates
            (s11, s21), (s12, s22) = shapes
            det = s11 * s22 - s12 * s21
            free = tuple(((s22 * q1 - s12 * q2) / det, (s11 * q2 - s21 * q1) / det)
                         for q1, q2 in ((start[0], start[2]), (start[1], start[3])))
        return Config(x0=values["x0"], distance=distance, t0=values["t0"], steps=steps,
                      end=values["t0"] + duration if steps else values["t0"], omegas=omegas, shapes=shapes,
                      gains=gains, u_max=u_max, v_max=v_max, impulses=impulses, free=free)
    if distance_abs > 0:
        # the largest base acceleration whose shaped acceleration stays within u_max (bisection)
        low, high = u_max, u_max / min(a for _, a in impulses)
        for _ in range(60):
            mid = 0.5 * (low + high)
            if _peak(_accel_steps(impulses, mid, *_base(distance_abs, mid, v_max))) <= u_max * (1 + 1e-12):
                low = mid
            else:
                high = mid
        accel = low
        t_a, t_c = _base(distance_abs, accel, v_max)
        steps = [(values["t0"] + t, sign * jump) for t, jump in _accel_steps(impulses, accel, t_a, t_c)]
    end = values["t0"] + impulses[-1][0] + 2 * t_a + t_c if steps else values["t0"]
    return Config(x0=values["x0"], distance=distance, t0=values["t0"], steps=steps, end=end, omegas=omegas,
                  shapes=shapes, gains=gains, u_max=u_max, v_max=v_max, impulses=impulses)


def reference(c, t):
    """``(x_ref, dx_ref, ddx_ref, theta1_ref, dtheta1_ref, theta2_ref, dtheta2_ref)`` at time ``t``.

    Notes
    -----
    The shaped acceleration is a sum of steps ``c_j H(t - tau_j)``; position and
    velocity integrate it exactly, and each mode ``eta_k'' = -w_k^2 eta_k - g_k u``
    answers a step with ``-g_k c_j (1 - cos w_k (t - tau_j)) / w_k^2``.
    """
    x, v, a = c.x0, 0.0, 0.0
    eta = [0.0, 0.0]
    deta = [0.0, 0.0]
    rounding = TIME_ROUNDING * max(1.0, abs(t))
    moving = t < c.end - rounding  # a summed time just short of the end is at it, at rest (OMSimulator's 3000 ms)
    if moving and c.free is not None:  # the swing the move starts from, left to itself: eta_k'' = -w_k^2 eta_k
        since = t - c.t0
        for k in range(2):
            w, e0, d0 = c.omegas[k], c.free[0][k], c.free[1][k]
            eta[k] = e0 * math.cos(w * since) + d0 * math.sin(w * since) / w
            deta[k] = -e0 * w * math.sin(w * since) + d0 * math.cos(w * since)
    for tau, jump in c.steps:
        dt = t - tau
        if dt <= rounding:
            break
        a += jump
        v += jump * dt
        x += 0.5 * jump * dt * dt
        if moving:
            for k in range(2):
                w = c.omegas[k]
                eta[k] -= c.gains[k] * jump * (1.0 - math.cos(w * dt)) / (w * w)
                deta[k] -= c.gains[k] * jump * math.sin(w * dt) / w
    if not moving and c.steps:  # rest at the target: no rounding left in the integrals
        x, v, a = c.x0 + c.distance, 0.0, 0.0
    (s11, s21), (s12, s22) = c.shapes
    return (x, v, a, s11 * eta[0] + s12 * eta[1], s11 * deta[0] + s12 * deta[1],
            s21 * eta[0] + s22 * eta[1], s21 * deta[0] + s22 * deta[1])


def initial_state(c):
    """``(time, planned, theta1, dtheta1, theta2, dtheta2)``: the time of the outputs, then with ``plan_from =
    measured`` whether the swing has been read (1.0) and the swing read, at the first step."""
    return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def plan(c, state, inputs):
    """The plan the outputs follow: ``c`` itself (``plan_from = parameters``), or the plan from the measured swing:
    the one read at the first step, or before it the inputs now."""
    if c.measured is None:
        return c
    return c.measured.plan(state[2:] if state[1] else inputs)


def update(c, state, inputs, time, step):
    """The time of the outputs after the step; with ``plan_from = measured`` the swing read at the first step."""
    if c.measured is not None and not state[1]:
        c.measured.plan(inputs)  # refused here, at the step, when the swing is no start
        return (time + step, 1.0, *inputs)
    return (time + step, *state[1:])


def _output(c, state, inputs):
    return reference(plan(c, state, inputs), state[0])


def report(c):
    """Move time, mode frequencies and the shaper's impulses, for ``crane-fmu info``."""
    return {"move_end_s": c.end, "mode_frequencies_hz": [round(w / (2 * math.pi), 6) for w in c.omegas],
            "impulses": [(round(t, 6), round(a, 6)) for t, a in c.impulses]}


VARIABLES = tuple(v._replace(description="planner's model: " + v.description) for v in PLANT_MODEL) + (
    parameter("x0", 0.0, "m", "start position of the move"),
    parameter("x_d", 0.0, "m", "target position of the move"),
    parameter("t0", 0.0, "s", "start time of the move"),
    enumeration("shaper", "zv", SHAPER_ITEMS, "input shaper for both swing modes: none (1), zv (2), zvd (3) or ei (4); "
                "or shortest (5): the least-time move of the linear crane, no shaper"),
    parameter("stretch", 1.0, "1", "shortest only: the least-effort move of this many times the shortest move's "
              "intervals (1: the shortest)"),
    *(parameter(name, 0.0, unit, f"shortest only: the {what} the move starts from at t0 (the linear model's)")
      for name, unit, what in (("theta1_0", "rad", "hook swing"), ("dtheta1_0", "rad/s", "hook swing rate"),
                               ("theta2_0", "rad", "payload swing"), ("dtheta2_0", "rad/s", "payload swing rate"))),
    enumeration("plan_from", "parameters", PLAN_FROM, "shortest only: the swing the move starts from: the parameters "
                "theta1_0 ... (1), or measured (2): the inputs theta1_now ... read at the first step (the parameters "
                "then 0)"),
    *limits.parameters(what="ddx_ref"),
    *(v._replace(name=v.name + "_now", description=v.description + ", read at the first step (plan_from measured "
                 "only); unconnected: 0, a move from rest")
      for v in state_variables(input_, "measured ", tuple(name[:-4] for name in MEASURED))),
    output("x_ref", "m", "reference trolley position"),
    output("dx_ref", "m/s", "reference trolley velocity"),
    output("ddx_ref", "m/s2", "reference trolley acceleration"),
    output("theta1_ref", "rad", "hook swing the reference induces in the linear model, during the move"),
    output("dtheta1_ref", "rad/s", "hook swing rate the reference induces, during the move"),
    output("theta2_ref", "rad", "payload swing the reference induces in the linear model, during the move"),
    output("dtheta2_ref", "rad/s", "payload swing rate the reference induces, during the move"),
)
RULES = (*PLANT_RULES, *limits.RULES, one_of("shaper", SHAPERS), *finite("x0", "x_d", "t0", *START),
         in_range("stretch", 1.0), one_of("plan_from", PLAN_FROM),
         *(rule(f"{name} == 0",
                f"{name} must be 0 when plan_from is measured (the swing is the inputs'), got {{{name}}}",
                when="plan_from == 'measured'") for name in START),
         rule("shaper == 'shortest'", "shaper must be shortest when plan_from is measured, got {shaper}",
              when="plan_from == 'measured'"),
         rule("finite(unlimited(u_max)) and finite(unlimited(v_max))",
              "u_max and v_max must be finite for a planned move, got {unlimited(u_max)}, {unlimited(v_max)}"))

# What the outputs read at the same instant (plan_from measured, before the first step): the swing references start
# at the measured swing, or at rest when all of it is a swing at rest (no plan); the trolley's reference starts at
# rest (the plan's first step acts just after t0)
DEPENDS_ON = {f"{name[:-4]}_ref": MEASURED for name in MEASURED}

COMPONENT = Component(
    "TrajectoryPlanner", "planner",
    "Input-shaped rest-to-rest trolley moves (ZV, ZVD, EI on both swing modes) within u_max and v_max; "
    "outputs: the reference x_ref, dx_ref, ddx_ref and the swing it induces",
    VARIABLES, configure, _output, feedthrough=True, depends_on=DEPENDS_ON, initial_state=initial_state, update=update,
    report=report, default_experiment=(0.0, 10.0, 1e-3),
    crane_model=CRANE_MODEL, native="planner.c", rules=RULES)  # the transport system's move
