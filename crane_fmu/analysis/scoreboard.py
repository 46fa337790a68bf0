"""The controller scoreboard: the scenarios, the metrics, the targets, and how controllers are ranked.

The one place that documents the **controller interface** a scored FMU (FMI 2.0
or 3.0 co-simulation) must have:

- inputs ``x`` [m], ``dx`` [m/s], ``theta1`` [rad], ``dtheta1`` [rad/s],
  ``theta2`` [rad], ``dtheta2`` [rad/s]: the measured crane state;
- output ``u`` [m/s2]: the demanded trolley acceleration;
- for the transport scenarios (:data:`TRANSPORT`), either a parameter ``x_d`` [m]
  (the target position) or the reference inputs ``x_ref`` [m], ``dx_ref`` [m/s],
  ``ddx_ref`` [m/s2] (and optionally ``theta1_ref``, ``dtheta1_ref``,
  ``theta2_ref``, ``dtheta2_ref``) of a ``TrajectoryPlanner``;
- optionally: an input ``l1_now`` [m] (the measured main cable length, when
  the plant hoists), parameters ``m1``, ``m2``, ``l1``, ``l2``, ``g`` (its model
  of the crane: set to the nominal plant), ``h`` [s] (the communication step).

The crane is the Section V plant with a trolley drive limited to 2 m/s2 and
1 m/s; every metric is computed from the plant's true state
(:func:`crane_fmu.analysis.metrics.move_metrics`). The residual swing is measured in a
window the scenario fixes, the same for every controller (:func:`residual_from`).

The scenarios with a plant unknown to the controller (:data:`PAIRED`) run on a paired design: the same
Latin-hypercube cases of the plant's l1, l2, m1, m2 and a seed (:data:`FACTORS`, :func:`design`) for every
controller, so that two controllers' figures pair up case by case (:mod:`crane_fmu.analysis.statistics`).

Every target is a requirement with its reason (``Target.source``), derived from
the physics of this crane where no requirement was given: the time-optimal move
of the drive (:data:`MOVE_S`) and the periods of the two swing modes
(:func:`mode_periods`), i.e. what the classic open-loop answers (Singer and
Seering's zero-vibration shapers) achieve. None is set from a controller's result.
"""

import math
from collections import namedtuple

from crane_fmu.controller_interface import MEASURED, MOVE_NEEDS, misses, told
from crane_fmu.cosim import Connection, System

DRIVE = {"u_max": 2.0, "v_max": 1.0}
DISTANCE = 2.0
RAIL = {"x_min": -1.0, "x_max": DISTANCE + 1.0}  # checked, not enforced: 1 m of track beyond either end of the move
MISMATCH = [{"l1": l1, "l2": l2, "m2": m2}  # a grid of plants unknown to the controller (crane-fmu targets)
            for l1 in (0.9, 1.0, 1.1) for l2 in (0.4, 0.5, 0.6) for m2 in (3.5, 7.0, 10.5)]
STEPS = (1e-3, 1e-2, 5e-2)
TRANSPORT = ("S2", "S3", "S4", "S5", "S7", "S8", "S9", "S10")  # the scenarios that give the controller a target
HOIST = {"from": 2.0, "to": 1.0, "u_max": 0.5, "v_max": 0.5}  # S7's hoist: l1 [m], its drive [m/s2, m/s]
GUST = {"F2_peak": 10.0, "start": 1.5, "duration": 0.5}  # S4's gust on the payload [N, s, s]

# The paired design of the scenarios whose plant the controller does not know: every controller runs the same cases
Factor = namedtuple("Factor", "name low high unit reason")
FACTORS = (
    Factor("l1", 0.9, 1.1, "m", "+-10 %: the hoist knows the main cable's length from its drum; what is left is the "
           "drum's calibration and the rope's stretch under load"),
    Factor("l2", 0.4, 0.6, "m", "+-20 %: the rigging below the hook (slings, a spreader) changes with every load and "
           "is not measured"),
    Factor("m1", 2.4, 3.6, "kg", "+-20 %: the hook block changes with the lifting gear on it (a hook, a grab, a "
           "spreader)"),
    Factor("m2", 3.5, 10.5, "kg", "+-50 %: the payload's mass is not known to the controller: loads of half to one "
           "and a half times the design's"),
)
PAIRED = ("S3", "S9", "S10")
CASES, QUICK_CASES = 64, 16  # cases of the paired design on a board and on a quick board
DESIGN_SEED = 20261201  # the design's draws: the same cases on every board of the same size


def design(n):
    """The ``n`` cases of the paired design: ``[{"l1", "l2", "m1", "m2", "seed"}]``.

    A Latin hypercube (scipy.stats.qmc, :data:`DESIGN_SEED`) over :data:`FACTORS` (values rounded to
    0.1 mm and 0.1 g) and a fifth coordinate that gives each case its seed of the noise or the wind (a
    whole number below 2^31).
    """
    from scipy.stats import qmc

    if not (isinstance(n, int) and n >= 1):
        raise ValueError(f"cases must be a whole number >= 1, got {n!r}")
    cases = []
    for point in qmc.LatinHypercube(d=len(FACTORS) + 1, seed=DESIGN_SEED).random(n):
        case = {f.name: round(float(f.low + u * (f.high - f.low)), 4) for f, u in zip(FACTORS, point)}
        case["seed"] = float(int(point[-1] * 2 ** 31))
        cases.append(case)
    return cases


def mode_periods(m1=3.0, m2=7.0, l1=1.0, l2=0.5, g=9.8):
    """Periods [s] of the slow and the fast swing mode of the double pendulum under a held trolley.

    Notes
    -----
    Eqs (8)-(9) linearised about the hanging equilibrium: ``M q'' + K q = 0`` with
    ``M = [[(m1+m2) l1^2, m2 l1 l2], [m2 l1 l2, m2 l2^2]]`` and
    ``K = diag((m1+m2) g l1, m2 g l2)``; ``det(K - w^2 M) = 0`` is a quadratic in ``w^2``.
    """
    m11, m12, m22, k1, k2 = (m1 + m2) * l1 ** 2, m2 * l1 * l2, m2 * l2 ** 2, (m1 + m2) * g * l1, m2 * g * l2
    a, b, c = m11 * m22 - m12 ** 2, -(k1 * m22 + k2 * m11), k1 * k2
    root = math.sqrt(b * b - 4 * a * c)
    slow, fast = math.sqrt((-b - root) / (2 * a)), math.sqrt((-b + root) / (2 * a))
    return 2 * math.pi / slow, 2 * math.pi / fast


def move_time(distance, u_max, v_max):
    """The time-optimal rest-to-rest move [s] of a drive limited to ``u_max`` and ``v_max``, swing ignored."""
    if distance <= v_max ** 2 / u_max:
        return 2 * math.sqrt(distance / u_max)
    return distance / v_max + v_max / u_max


T_SLOW, T_FAST = mode_periods()  # 2.37 s and 0.66 s for the Section V crane
MOVE_S = move_time(DISTANCE, DRIVE["u_max"], DRIVE["v_max"])  # 2.5 s
# The limits derived from them, rounded to 0.1 s:
ZV_MOVE_S = round(MOVE_S + (T_SLOW + T_FAST) / 2, 1)  # a ZV shaper on each mode: half its period later (4.0 s)
ZVD_SLOWEST_S = round(MOVE_S + max(sum(mode_periods(m1, m2, l1, l2))  # the periods grow towards a corner
                                    for m1 in (2.4, 3.6) for m2 in (3.5, 10.5) for l1 in (0.9, 1.1)
                                    for l2 in (0.4, 0.6)), 1)
HOIST_THEN_MOVE_S = round(move_time(HOIST["from"] - HOIST["to"], HOIST["u_max"], HOIST["v_max"]) + MOVE_S
                          + sum(mode_periods(l1=HOIST["to"])) / 2, 1)  # 3 s + 4.0 s
GUST_S = round(ZV_MOVE_S + T_SLOW, 1)  # one slow period more: 6.4 s
COARSE_S = round(3.0 + T_SLOW, 1)  # 5.4 s

Target = namedtuple("Target", "metric limit text source case", defaults=(None,))
Target.__doc__ = ("A requirement: met when the metric (worst case) is <= limit; ``source`` is why the limit is "
                  "what it is; ``case``: the label of the one case it applies to (None: every case).")
Scenario = namedtuple("Scenario", "id title rank_by targets")
Scenario.__doc__ = "A scenario: its id, what it is, the metric it ranks by (lower is better) and its targets."

_REQUIRED = ("the requirement every built-in controller is held to on the Section V crane (|u| <= 2 m/s2, "
             "1 ms step)")
_ZV = (f"no slower than the classic open-loop swing-free move: the time-optimal move ({MOVE_S:g} s at 2 m/s2 and "
       f"1 m/s) delayed by a ZV shaper on each mode (half of {T_SLOW:.2f} s and of {T_FAST:.2f} s)")
STOPPED_DEG = 0.1  # a swing within 0.1 deg counts as stopped (metrics.SETTLED_BAND): every residual target
_RESIDUAL = (f"the swing left one slow period after the planned move: {STOPPED_DEG:g} deg moves the payload of the "
             f"1.5 m double pendulum by at most {1.5 * math.sin(math.radians(STOPPED_DEG)) * 1e3:.1f} mm, within the "
             f"5 mm positioning band of arrival, and is the band in which a swing counts as stopped; " + _REQUIRED)
_UNKNOWN = (f"as in S2: a plant unknown to the controller does not change what the load must do; on the design's "
            f"longest pendulum (l1 + l2 = 1.7 m) {STOPPED_DEG:g} deg moves the payload by at most "
            f"{1.7 * math.sin(math.radians(STOPPED_DEG)) * 1e3:.1f} mm")
_ONE_SWING = f"one period of the slow mode ({T_SLOW:.2f} s) to remove a disturbance's swing"
_MEASURED = ("the requirement on a crane that measures only the trolley position and the hook angle (1 mm and "
             "0.1 deg noise, one step late)")

# Every target, in one place: a case meets a target when its metric is not None and <= the limit.
SCENARIOS = {
    "S1": Scenario("S1", "Section V regulation from theta1 = 10 deg", "settling_0.1deg_s",
                   (Target("settling_0.5deg_s", 3.0, "both angles within 0.5 deg by 3.0 s",
                           _REQUIRED + "; the linear minimum-time floor is 1.7-2.0 s"),
                    Target("settling_0.1deg_s", 4.0, "within 0.1 deg by 4.0 s", _REQUIRED),
                    Target("position_1cm_s", 4.0, "trolley within 1 cm of x_d by 4.0 s", _REQUIRED))),
    "S2": Scenario("S2", f"{DISTANCE:g} m transport from rest", "arrival_s",
                   (Target("arrival_s", ZV_MOVE_S, f"within 5 mm and 0.5 deg from {ZV_MOVE_S:.1f} s",
                           _ZV),
                    Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg", _RESIDUAL))),
    "S3": Scenario("S3", "S2 on plants of the paired design (l1 +-10 %, l2 +-20 %, m1 +-20 %, m2 +-50 %) unknown to "
                   "the controller", "residual_deg",
                   (Target("residual_deg", STOPPED_DEG, "worst residual swing <= 0.1 deg", _UNKNOWN),
                    Target("arrival_s", ZVD_SLOWEST_S, f"every plant arrives by {ZVD_SLOWEST_S:.1f} s",
                           "no slower than the classic robust open-loop move: the time-optimal move delayed by a ZVD "
                           "shaper (a full period of each mode) on the slowest plant of the design"))),
    "S4": Scenario("S4", "S2 with a gust: a 10 N half-sine push on the payload at 1.5-2.0 s", "arrival_s",
                   (Target("arrival_s", GUST_S,
                           f"within 5 mm and 0.5 deg from {GUST_S:.1f} s",
                           f"S2's target plus {_ONE_SWING} (a port-crane tender asks a container spreader's sway "
                           "stopped within 5 s of a halt from full speed)"),
                    Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg", "as in S2: " + _RESIDUAL))),
    "S5": Scenario("S5", "S2 measured with noise (seed 1) one communication step late", "arrival_s",
                   (Target("arrival_s", ZV_MOVE_S, f"within 5 mm and 0.5 deg from {ZV_MOVE_S:.1f} s",
                           "as in S2: a 1 ms delay and the sensor's noise are small against the swing; the "
                           "requirement stays"),
                    Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg",
                           "as in S2: the residual is the plant's true swing; the sensor's noise (0.05 deg standard "
                           "deviation) is on the measurement, and a load left swinging by more has not stopped"))),
    "S6": Scenario("S6", "S1 at communication steps of 1, 10 and 50 ms", "settling_0.5deg_s",
                   (Target("settling_0.5deg_s", COARSE_S,
                           f"within 0.5 deg by {COARSE_S:.1f} s at every step",
                           f"S1's 3.0 s plus {_ONE_SWING}: a 50 ms step is 1/47 of that period"),
                    Target("residual_deg", STOPPED_DEG, "swing within 0.1 deg over the last quarter at every step",
                           "the swing stopped by the end of the run (the band in which a swing counts as stopped): "
                           "S1 asks it by 4.0 s, the last quarter (7.5-10 s) leaves a coarse step twice as long"))),
    "S7": Scenario("S7", f"{DISTANCE:g} m transport while hoisting from l1 = 2 m to 1 m", "arrival_s",
                   (Target("arrival_s", HOIST_THEN_MOVE_S,
                           f"within 5 mm and 0.5 deg from {HOIST_THEN_MOVE_S:.1f} s",
                           "no slower than hoisting first (1 m at 0.5 m/s2 and 0.5 m/s: 3 s), then the ZV-shaped "
                           "move on the 1 m cable: moving while hoisting is done to save time"),
                    Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg", "as in S2: " + _RESIDUAL))),
    "S8": Scenario("S8", "S1 and S2 with only x and theta1 measured (1 mm, 0.1 deg noise, one step late), a "
                   "StateEstimator in front of the controller", "arrival_s",
                   (Target("settling_0.5deg_s", 3.5, "S1: both true angles within 0.5 deg by 3.5 s",
                           _MEASURED + ": S1's 3.0 s plus 0.5 s for the estimate of the unmeasured payload angle to "
                           "converge", "S1"),
                    Target("settling_0.1deg_s", 5.0, "S1: within 0.1 deg by 5.0 s",
                           _MEASURED + ": S1's 4.0 s plus 1 s, as 0.1 deg is the sensor's noise", "S1"),
                    Target("arrival_s", ZV_MOVE_S, f"S2: within 5 mm and 0.5 deg from {ZV_MOVE_S:.1f} s",
                           "as in S2 (" + _ZV + "); " + _MEASURED, "S2"),
                    Target("residual_deg", STOPPED_DEG, "S2: residual swing <= 0.1 deg",
                           "as in S2: " + _RESIDUAL + "; " + _MEASURED, "S2"))),
    "S9": Scenario("S9", "S3 with only x and theta1 measured (the noise seeded by the case): plants unknown to the "
                   "estimator and the controller", "residual_deg",
                   (Target("residual_deg", STOPPED_DEG, "worst residual swing <= 0.1 deg",
                           "as in S3 (" + _UNKNOWN + "); " + _MEASURED),)),
    "S10": Scenario("S10", "S2 in turbulent wind (10 m/s mean, moderate Dryden turbulence seeded by the case, drag on "
                    "hook and payload) on plants of the paired design unknown to the controller", "residual_deg",
                    (Target("arrival_s", GUST_S, f"within 5 mm and 0.5 deg from {GUST_S:.1f} s",
                            "as in S4: the wind is a disturbance like the gust, and the requirement on the load "
                            "stays"),
                     Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg",
                            "as in S4; the mean wind alone deflects the load by about half a degree (its drag "
                            "over the weight), which no trolley acceleration takes away: this wind keeps the load "
                            "from meeting the requirement, and the ranking compares what is left"))),
}
MEASURING = ("S8", "S9")  # the scenarios with a sensor and a StateEstimator in front of the controller
SENSED = ("x", "theta1", "theta2")  # what the CraneSensor takes of the plant

RULES = ("a controller's rank is 1 + the number of controllers better than it in the scenario. A is better than B "
         "when B failed in a case and A did not; else when A meets more targets (in every case); else, on the paired "
         "design (" + ", ".join(PAIRED) + "), when the two-sided Wilcoxon signed-rank test of their paired ranking "
         "figures gives p < 0.05 with A's figures lower (cases with equal figures left out); elsewhere when A's "
         "ranking figure (its worst case) is lower, *never* after every finite value, or, equal, when A leaves less "
         "swing over the last quarter of the run (a law that keeps swinging below one that converges slowly). "
         "Controllers of one rank tie and the board says so; they are listed by name")
NOT_APPLICABLE = "n/a (needs x_d or x_ref)"

Contender = namedtuple("Contender", "name source inputs parameters user", defaults=(False,))
Contender.__doc__ = ("A controller to score: its name, its FMU (a model identifier or an .fmu path), its interface, "
                     "and whether it is the user's (an FMU file) rather than a built-in one.")


def check_interface(name, inputs, outputs, parameters=()):
    """Raise ValueError (one line) naming what a controller misses of what every scenario needs.

    What only the transport scenarios need (a target position) makes those scenarios not applicable
    (:func:`applicable`), not the controller unusable.
    """
    missing, _ = misses(inputs, outputs, parameters)
    if missing:
        raise ValueError(f"{name} is not a crane controller: it misses {', '.join(missing)} (every scenario; the "
                         f"interface: inputs {', '.join(MEASURED)}; output u; for a target position {MOVE_NEEDS})")


def _told(contender, scenario):
    """What the contender is told in the scenario (:func:`crane_fmu.controller_interface.told`, the rule simulate
    applies too); ValueError when it cannot be told the move."""
    target = DISTANCE if scenario in TRANSPORT else None
    return told(contender.name, contender.inputs, ["u"], contender.parameters, target)


def applicable(contender, scenario):
    """None when the contender can run the scenario, else why not (:data:`NOT_APPLICABLE`): it cannot be told the
    scenario's move."""
    try:
        _told(contender, scenario)
    except ValueError:
        return NOT_APPLICABLE
    return None


def scope(scenario, cases=CASES):
    """``{"plants": n, "steps": n, "cases": n}``: how much of the scenario a board of ``cases`` paired cases runs."""
    plants = cases if scenario in PAIRED else 1
    steps = len(STEPS) if scenario == "S6" else 1
    moves = 2 if scenario == "S8" else 1
    return {"plants": plants, "steps": steps, "cases": plants * steps * moves}


ScenarioRun = namedtuple("ScenarioRun", "label system step stop_time x_d residual_from")
ScenarioRun.__doc__ = ("One case of a scenario: its label, the System, the communication step and stop time [s], the "
                       "target position [m] and the start of the residual swing's window [s] (:func:`residual_from`).")
PLAN = {"x_d": DISTANCE, "shaper": "zv"}  # the planned move of the transport scenarios
HOIST_PLAN = {**PLAN, "shaper": "zvd", "l1": 1.5}  # S7's: robust to the cable's length between 2 m and 1 m


def residual_from(stop_time, plan=None, plant=None):
    """Start [s] of the window of the residual swing, which the scenario fixes for every controller alike.

    For a move: the end of the planned move (``plan``: the planner's parameters, whether or not the
    controller follows a planner) plus one period of the slow swing mode of the plant as it is at the end
    of the run (``plant``: its m1, m2, l1, l2, g where they differ from Section V); the swing from then on is
    what the controller left. For regulation (``plan`` None): the last quarter of the run.
    """
    if plan is None:
        return 0.75 * stop_time
    from crane_fmu.model import planner

    end = planner.configure({**planner.COMPONENT.defaults(), **plan}).end
    return end + mode_periods(**{k: v for k, v in (plant or {}).items() if k in ("m1", "m2", "l1", "l2", "g")})[0]


def systems_for(contender, scenario, cases=CASES):
    """The :class:`ScenarioRun` cases of one scenario for a contender (``cases``: of the paired design).

    Raises
    ------
    ValueError
        When the scenario does not apply to the contender (:func:`applicable`), or there is no such scenario.
    """
    c = contender
    if scenario not in SCENARIOS:
        raise ValueError(f"no scenario {scenario!r}; scenarios: {', '.join(SCENARIOS)}")
    if applicable(c, scenario):
        raise ValueError(f"{c.name}: {scenario} {applicable(c, scenario)}")

    def regulation(step, extra=None, connections=()):
        instances, parameters = {"plant": "CranePlant", "controller": c.source}, {"plant": dict(DRIVE)}
        for name, (kind, values) in (extra or {}).items():
            instances[name] = kind
            parameters[name] = values
        return System(f"{c.name}-regulation", instances, connections, parameters=parameters, stop_time=10.0,
                      step=step)

    # S8, S9: the plant's true x, theta1, theta2 to the sensor, its x_meas, theta1_meas to the estimator (by name),
    # the estimate to the controller; u and l1_now by name
    measuring = {"sensor": ("CraneSensor", {}), "estimator": ("StateEstimator", {})}
    measured = tuple(Connection("plant", n, "sensor", n) for n in SENSED) + tuple(
        Connection("estimator", n, "controller", n) for n in MEASURED)

    def transport(plant=None, extra=None, connections=(), l1=None, hoist=False):
        instances = {"plant": "CranePlant", "controller": c.source}
        parameters = {"plant": {**DRIVE, "theta1_0": 0.0, **(plant or {})}, "controller": {}}
        if l1 is not None and "l1" in c.parameters:
            parameters["controller"]["l1"] = l1
        move = _told(c, scenario)
        if move.references:
            instances["planner"] = "TrajectoryPlanner"
            parameters["planner"] = dict(HOIST_PLAN if hoist else PLAN)
            if hoist:
                connections = connections + tuple(Connection("planner", n, "controller", n) for n in move.references)
        else:
            parameters["controller"]["x_d"] = move.x_d
        for name, (kind, values) in (extra or {}).items():
            instances[name] = kind
            parameters[name] = values
        return System(f"{c.name}-transport", instances, connections, parameters=parameters,
                      stop_time=12.0 if hoist else 10.0)

    def moved(label, system, plant=None, plan=PLAN):
        return ScenarioRun(label, system, 1e-3, system.stop_time, DISTANCE,
                           residual_from(system.stop_time, plan, plant))

    def regulated(label, system, step=1e-3):
        return ScenarioRun(label, system, step, system.stop_time, 0.0, residual_from(system.stop_time))

    def label(n, case, seeded):
        return f"#{n:02d} " + ", ".join(f"{k}={v:g}" for k, v in case.items() if k != "seed") + (
            f", seed {int(case['seed'])}" if seeded else "")

    def paired(make, seeded=True):  # one run per case of the design, on its plant, with its seed
        return [moved(label(n, case, seeded), make({k: case[k] for k in ("l1", "l2", "m1", "m2")}, case["seed"]),
                      {k: case[k] for k in ("l1", "l2", "m1", "m2")}) for n, case in enumerate(design(cases), 1)]

    if scenario == "S1":
        return [regulated("nominal", regulation(1e-3))]
    if scenario == "S6":
        return [regulated(f"h={h * 1e3:g}ms", regulation(h), h) for h in STEPS]
    if scenario == "S2":
        return [moved("nominal", transport())]
    if scenario == "S3":
        return paired(lambda plant, seed: transport(plant), seeded=False)
    if scenario == "S4":
        gust = {"gust": ("Gust", dict(GUST))}
        return [moved("F2 10 N at 1.5 s", transport(extra=gust))]
    if scenario == "S5":
        sensor = {"sensor": ("Sensor", {"seed": 1.0, "delay": 1.0})}
        wiring = tuple(Connection("sensor", n + "_m", "controller", n) for n in MEASURED)
        return [moved("seed 1, one step late", transport(extra=sensor, connections=wiring))]
    if scenario == "S7":
        hoist = {"hoist": ("TrajectoryPlanner", {"x0": HOIST["from"], "x_d": HOIST["to"], "shaper": "none",
                                                  "u_max": HOIST["u_max"], "v_max": HOIST["v_max"]})}
        plant = {"l1": HOIST["from"], "l1_min": HOIST["to"], "l1_max": HOIST["from"]}
        system = transport(plant, hoist, (Connection("hoist", "ddx_ref", "plant", "hoist"),), l1=HOIST["from"],
                           hoist=True)
        if "l1_low" in c.parameters:
            system = system.with_parameters({"controller": {"l1_low": HOIST["to"], "l1_high": HOIST["from"]}})
        return [moved("l1 2 m -> 1 m", system, {"l1": HOIST["to"]}, HOIST_PLAN)]
    if scenario == "S8":
        return [regulated("S1", regulation(1e-3, measuring, measured)),
                moved("S2", transport(extra=measuring, connections=measured))]
    if scenario == "S9":
        return paired(lambda plant, seed: transport(plant, {**measuring, "sensor": ("CraneSensor", {"seed": seed})},
                                                    measured))
    # S10: the wind's drag by name to the plant's F1, F2, the plant's state by name to the wind
    return paired(lambda plant, seed: transport(plant, {"wind": ("Wind", {"seed": seed, "l1": plant["l1"],
                                                                          "l2": plant["l2"]})}))


def met(row, target):
    """Whether one case meets a target: it ran to the end and its metric is within the limit (a target of
    another case: met)."""
    if target.case is not None and row.get("case") != target.case:
        return True
    value = row.get(target.metric)
    return row.get("status") == "ok" and value is not None and value <= target.limit


def _figure_key(line, metric):
    value, swing = line[metric], line["end_swing_deg"]
    return (value is None, 0.0 if value is None else value, math.inf if swing is None else swing)


def rank_key(line, metric):
    """A line's place in a sort (see :data:`RULES`): failed, targets met, worst figure, never, swing left, name."""
    return (line["failed"] > 0, -sum(line["targets"])) + _figure_key(line, metric) + (line["controller"],)


# The figures of a board row: (column header, metric, digits, unit); lower is better, a row shows the worst case.
FIGURES = (("0.5 deg from", "settling_0.5deg_s", 2, " s"), ("0.1 deg from", "settling_0.1deg_s", 2, " s"),
           ("arrival", "arrival_s", 2, " s"), ("residual", "residual_deg", 3, " deg"),
           ("peak swing", "peak_swing_deg", 2, " deg"), ("RMS swing", "rms_swing_deg", 3, " deg"),
           ("ISE of swing", "ise_swing_deg2s", 2, " deg2 s"), ("overshoot", "overshoot_m", 3, " m"),
           ("final error", "final_error_m", 4, " m"), ("peak abs u", "peak_abs_u", 1, " m/s2"),
           ("peak abs v", "peak_abs_v", 2, " m/s"), ("effort", "effort", 1, " m2/s3"),
           ("u total variation", "u_total_variation", 1, " m/s2"))
WORST = tuple(metric for _, metric, _, _ in FIGURES) + ("position_1cm_s", "end_swing_deg")
FORMAT = {metric: (digits, unit) for _, metric, digits, unit in FIGURES}


def not_applicable(rows, scenario):
    """``{controller: why}`` of the contenders the scenario does not apply to."""
    return {r["controller"]: r["error"] for r in rows if r["scenario"] == scenario and r["status"] == "n/a"}


def _pairs(line_a, line_b):
    """The paired ranking figures of two lines over the cases both ran, by case label."""
    common = sorted(set(line_a["values"]) & set(line_b["values"]))
    return [line_a["values"][c] for c in common], [line_b["values"][c] for c in common]


def _better(a, b, scenario, verdicts):
    """Whether line ``a`` is better than line ``b`` by :data:`RULES`."""
    key_a, key_b = (a["failed"] > 0, -sum(a["targets"])), (b["failed"] > 0, -sum(b["targets"]))
    if key_a != key_b:
        return key_a < key_b
    if scenario in PAIRED and not a["failed"] and not b["failed"]:
        pair = (a["controller"], b["controller"])
        if pair not in verdicts:
            from crane_fmu.analysis import statistics

            verdicts[pair] = statistics.wilcoxon(*_pairs(a, b))[1]
        return verdicts[pair] < 0
    metric = SCENARIOS[scenario].rank_by
    return _figure_key(a, metric) < _figure_key(b, metric)


def summarise(rows, scenario):
    """One line per contender for a scenario: the worst case of each metric, the targets met, the ranking figure
    of every case (``values``), its ``rank`` by :data:`RULES` and whether it ties (``tie``); by rank, then name.

    Contenders the scenario does not apply to have no line (:func:`not_applicable`).
    """
    s = SCENARIOS[scenario]
    by = {}
    for r in rows:
        if r["scenario"] == scenario and r["status"] != "n/a":
            by.setdefault(r["controller"], []).append(r)
    lines = []
    for name, cases in by.items():
        failed = [r for r in cases if r["status"] != "ok"]
        worst = {}
        for metric in WORST:
            values = [r.get(metric) for r in cases]
            worst[metric] = None if any(v is None for v in values) else max(values)
        held = [r.get("bounds_held") for r in cases]
        broken = sorted({b for r in cases for b in (r.get("bounds_broken") or "").split(", ") if b})
        targets = [all(met(r, t) for r in cases) for t in s.targets]
        lines.append({"controller": name, "cases": len(cases), "failed": len(failed),
                      "error": min(r["error"] or "" for r in failed) if failed else None, **worst,
                      "bounds_held": None if None in held else all(held), "bounds_broken": ", ".join(broken),
                      "targets": targets, "values": {r["case"]: r.get(s.rank_by) for r in cases}})
    verdicts = {}
    for line in lines:
        line["rank"] = 1 + sum(_better(other, line, scenario, verdicts) for other in lines if other is not line)
    for line in lines:
        line["tie"] = any(other["rank"] == line["rank"] for other in lines if other is not line)
    return sorted(lines, key=lambda line: (line["rank"], line["controller"]))


def board_statistics(rows, scenarios=PAIRED):
    """The statistics of the paired scenarios: ``{scenario: {"describe": {controller: {metric: Description}},
    "pairs": [(a, b, Paired)]}}`` over the cases of each (:mod:`crane_fmu.analysis.statistics`)."""
    from crane_fmu.analysis import statistics

    result = {}
    for sid in scenarios:
        lines = summarise(rows, sid)
        if not lines:
            continue
        metrics = [metric for _, metric, _, _ in FIGURES]
        describe = {}
        for line in lines:
            cases = sorted((r for r in rows if r["scenario"] == sid and r["controller"] == line["controller"]),
                           key=lambda r: r["case"])
            found = statistics.describe_all([[r.get(m) for r in cases] for m in metrics])
            describe[line["controller"]] = dict(zip(metrics, found))
        pairs = [(a["controller"], b["controller"], statistics.compare_paired(*_pairs(a, b)))
                 for i, a in enumerate(lines) for b in lines[i + 1:]]
        result[sid] = {"describe": describe, "pairs": pairs}
    return result


def _cell(value, digits=2, unit=""):
    if value is None or value == math.inf:
        return "never" if unit == " s" else "-"  # a time not reached; a figure of a run that ended early
    return f"{value:.{digits}f}{unit}"


def _interval(low, high, digits):
    return f"[{_cell(low, digits)}, {_cell(high, digits)}]".replace("-, ", "never, ").replace(", -]", ", never]")


def _bounds(line):
    if line["bounds_held"] is None:
        return "-"
    return "held" if line["bounds_held"] else f"**broken**: {line['bounds_broken']}"


def _name(name, users):
    return f"`{name}`" + (" (yours)" if name in users else "")


def _scenario_label(sid, cases=CASES, quick=False):
    """``S3 (64 cases): S2 on plants ...``; on a quick board every scenario says so: ``S1 (QUICK: 1 case): ...``."""
    n = scope(sid, cases)["cases"]
    if sid not in PAIRED and not quick:
        return f"{sid}: {SCENARIOS[sid].title}"
    return f"{sid} ({'QUICK: ' if quick else ''}{n} case{'s' if n > 1 else ''}): {SCENARIOS[sid].title}"


def _ranked_by(sid):
    s = SCENARIOS[sid]
    return f"{s.rank_by}, median, paired Wilcoxon" if sid in PAIRED else s.rank_by


def floor_ratio(value, floor):
    """`` (1.32x floor)``: a time as a multiple of the scenario's floor (:mod:`.floor`), or nothing."""
    return "" if floor is None or value is None else f" ({value / floor.seconds:.2f}x floor)"


def render_summary(rows, users=(), quick=False, cases=CASES, stats=None, floors=None):
    """One table: per scenario the controllers by rank, with their ranking figure (the worst case, and its ratio to
    the scenario's floor where ``floors`` gives one; on the paired design the median with its 95 % interval), the
    targets they met and ties; then those it does not apply to."""
    stats = board_statistics(rows) if stats is None else stats
    floors = floors or {}
    lines = []
    for sid, s in SCENARIOS.items():
        ranked, absent = summarise(rows, sid), not_applicable(rows, sid)
        if not ranked and not absent:
            continue
        digits, unit = FORMAT.get(s.rank_by, (2, " s"))
        digits = max(digits, 3) if unit == " deg" else digits
        cells = []
        for line in ranked:
            if line["failed"]:
                figure = "failed"
            elif sid in stats:
                d = stats[sid]["describe"][line["controller"]][s.rank_by]
                figure = f"median {_cell(d.median, digits, unit)} {_interval(d.median_low, d.median_high, digits)}"
            else:
                figure = _cell(line[s.rank_by], digits, unit) + floor_ratio(line[s.rank_by], floors.get(sid))
            verdict = "all targets met" if all(line["targets"]) and not line["failed"] else (
                f"{sum(line['targets'])} of {len(line['targets'])} targets met")
            cells.append(f"{line['rank']}. {_name(line['controller'], users)}: {figure}, {verdict}"
                         + (", tie" if line["tie"] else ""))
        cells += [f"{_name(name, users)}: {why}" for name, why in sorted(absent.items())]
        lines.append((sid, cells))
    width = max(len(cells) for _, cells in lines)
    out = ["| scenario | ranked by | " + " | ".join(["controllers by rank"] + [""] * (width - 1)) + " |",
           "|---|---|" + "---|" * width]
    for sid, cells in lines:
        out.append(f"| {_scenario_label(sid, cases, quick)} | {_ranked_by(sid)} | "
                   + " | ".join(cells + [""] * (width - len(cells))) + " |")
    return "\n".join(out)


def _statistics_section(sid, stats, users):
    """Markdown of a paired scenario's statistics: each figure's median and 90th percentile per contender with
    their intervals, and each pair's paired difference of the ranking figure with the test."""
    describe, pairs = stats["describe"], stats["pairs"]
    names = list(describe)
    out = ["Over the cases: median [95 % interval]; 90th percentile [95 % interval] (bootstrap):", "",
           "| figure | " + " | ".join(_name(n, users) for n in names) + " |", "|---|" + "---|" * len(names)]
    for header, metric, digits, unit in FIGURES:
        cells = []
        for n in names:
            d = describe[n][metric]
            cells.append(f"{_cell(d.median, digits)} {_interval(d.median_low, d.median_high, digits)}; "
                         f"{_cell(d.p90, digits)} {_interval(d.p90_low, d.p90_high, digits)}")
        out.append(f"| {header} [{unit.strip()}] | " + " | ".join(cells) + " |")
    metric = SCENARIOS[sid].rank_by
    digits, unit = FORMAT[metric]
    digits = max(digits, 3)
    out += ["", f"Pairs, on {metric} case by case (A - B):", "",
            "| A | B | median difference [95 % interval] | Wilcoxon p | verdict |", "|---|---|---|---|---|"]
    for a, b, paired in pairs:
        verdict = "tie" if paired.better == 0 else f"{_name(a if paired.better < 0 else b, users)} lower"
        out.append(f"| {_name(a, users)} | {_name(b, users)} | {_cell(paired.difference, digits, unit)} "
                   f"{_interval(paired.low, paired.high, digits)} | {paired.p:.3g} | {verdict} |")
    return out + [""]


def render(rows, contenders, quick=False, cases=CASES, provenance=None, stats=None, floors=None):
    """scoreboard.md: per scenario a table ranked by :data:`RULES`, with each target met or missed and its source;
    on the paired design the statistics (``stats``: :func:`board_statistics`, computed when not given); the
    provenance of the figures.

    ``floors``: ``{scenario: floor.Floor}``, the least time the crane needs there, shown with its method and as
    each ranking figure's ratio to it.
    """
    from crane_fmu.analysis import metrics, statistics

    users = {c.name for c in contenders if c.user}
    stats = board_statistics(rows) if stats is None else stats
    floors = floors or {}
    title = "# Controller scoreboard" + (" (QUICK: fewer cases of the paired design, not the full board)"
                                         if quick else "")
    out = [title, "",
           "Every controller on the same crane (Section V plant, trolley drive limited to 2 m/s2 and 1 m/s), through "
           "the same master, on the same scenarios (`crane_fmu/analysis/scoreboard.py` defines them and their "
           "targets). Times are from the start of the run; *never* means not within the run. A row's figure is the "
           "worst over the scenario's cases.", "",
           f"Paired design ({', '.join(PAIRED)}): {cases} cases of a Latin hypercube (scipy.stats.qmc, seed "
           f"{DESIGN_SEED}) over the plant, the same for every controller, each with a seed of its own for the noise "
           "(S9) and the wind (S10); the controller knows the Section V plant. The ranges:", ""]
    out += [f"- {f.name} from {f.low:g} to {f.high:g} {f.unit}: {f.reason}" for f in FACTORS] + [""]
    out += [f"Ranking: {RULES}.", "",
            f"Statistics: medians and 90th percentiles are figures some case had (the smallest with at least half, "
            f"nine tenths, of the cases at or below it); their 95 % intervals are percentile bootstraps "
            f"(scipy.stats.bootstrap, {statistics.RESAMPLES} resamples, seed {statistics.SEED}); {statistics.RULE} "
            "(scipy.stats.wilcoxon; each pair on its own, at 5 %).", "",
           "Controllers: " + ", ".join(_name(c.name, users) for c in sorted(contenders, key=lambda c: c.name)), "",
           render_summary(rows, users, quick, cases, stats, floors), ""]
    if floors:
        method = next(iter(floors.values())).method
        out += [f"The floor of a scenario is the least time the crane needs for its task: {method}.", ""]
    for sid, s in SCENARIOS.items():
        lines, absent = summarise(rows, sid), not_applicable(rows, sid)
        if not lines and not absent:
            continue
        out += [f"## {_scenario_label(sid, cases, quick)}", "", "Targets:", ""]
        out += [f"- {t.text} ({t.source})" for t in s.targets] + [""]
        if sid in floors:
            out += [f"Floor: {floors[sid].seconds:.2f} s ({floors[sid].task})", ""]
        if lines:
            out.append("| rank | controller | " + " | ".join(header for header, _, _, _ in FIGURES)
                       + " | bounds | targets |")
            out.append("|---|---|" + "---|" * (len(FIGURES) + 2))
        for line in lines:
            verdict = ", ".join(("met" if ok else "**missed**") for ok in line["targets"])
            if line["failed"]:
                verdict = f"**failed** in {line['failed']} of {line['cases']}: {line['error']}"[:300]
            out.append(f"| {line['rank']}{' (tie)' if line['tie'] else ''} | {_name(line['controller'], users)} | "
                       + " | ".join(_cell(line[metric], digits, unit) for _, metric, digits, unit in FIGURES)
                       + f" | {_bounds(line)} | {verdict.replace('|', '/')} |")
        out.append("")
        out += [f"- {_name(name, users)}: {why}" for name, why in sorted(absent.items())] + ([""] if absent else [])
        if sid in stats:
            out += _statistics_section(sid, stats[sid], users)
    out += [f"Metrics (`crane_fmu/analysis/metrics.py`, version {metrics.VERSION}): settling times are from when both "
            "angles stay within the band; arrival is from when the trolley also stays within 5 mm of the target; the "
            "residual swing is the largest angle (either) in a window the scenario fixes, as measured: for a move "
            "from the planned move's end plus one period of the plant's slow swing mode, for regulation the last "
            "quarter of the run; peak, RMS and ISE of the swing are over the whole run (RMS and ISE of theta1 and "
            "theta2 together); overshoot is how far the trolley went past the target; effort is the integral of "
            "u^2; peak |u| is what the controller demanded (the drive gives at most 2 m/s2); the total variation "
            "of u is the sum of |u_k - u_(k-1)| over the communication steps (how much the command chatters); "
            f"bounds: the demanded |u| <= {DRIVE['u_max']:g} m/s2, |v| <= {DRIVE['v_max']:g} m/s and the trolley on "
            f"the rail from {RAIL['x_min']:g} to {RAIL['x_max']:g} m, at every step (checked, not enforced).", ""]
    if provenance:
        out += ["## Provenance", ""] + [f"- {key}: {value}" for key, value in provenance.items()] + [""]
    return "\n".join(out)
