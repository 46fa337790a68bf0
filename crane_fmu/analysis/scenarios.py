"""The scoreboard's scenarios as registered data: what each asks of a controller, on which plant, and its targets.

A scenario (:class:`Scenario`) names the plant it runs on (a registered component with crane roles),
the roles it needs of that plant (an axis to move along, a hoist, forces, sensed outputs), the metric it
ranks by, its targets (each a requirement with its reason, :class:`Target`) and how its cases are made
(``runs(contender, cases)``: :class:`ScenarioRun` systems). The planar crane's S1-S10 are registered by
:mod:`.planar_scenarios`; a second plant's scenarios register the same way.

The one place that documents what a scored controller (an FMI 2.0 or 3.0 co-simulation FMU) must have: the
interface of the scenario's plant (:mod:`crane_fmu.controller_interface`): its measured state as inputs,
every axis's demand as outputs; for the scenarios that move the load (``moves``), each axis's target
parameter (``x_d``) or a planner's references (``x_ref``, ``dx_ref``, ``ddx_ref``); optionally the measured
cable length ``l1_now``, its model of the crane (``m1``, ``m2``, ``l1``, ``l2``, ``g``: set to the nominal
plant) and ``h`` [s] (the communication step).

The scenarios with a plant unknown to the controller (``paired``) run on a paired design: the same
Latin-hypercube cases of the plant's parameters (:data:`FACTORS`, :func:`design`) for every controller, so
that two controllers' figures pair up case by case (:mod:`crane_fmu.analysis.statistics`).
"""

import functools
import hashlib
import inspect
import re
from collections import namedtuple
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from crane_fmu import components
from crane_fmu.controller_interface import misses, move_needs, told
from crane_fmu.registry import Registry

Target = namedtuple("Target", "metric limit text source case", defaults=(None,))
Target.__doc__ = ("A requirement: met when the metric (worst case) is <= limit; ``source`` is why the limit is "
                  "what it is; ``case``: the label of the one case it applies to (None: every case).")
ScenarioRun = namedtuple("ScenarioRun", "label system step stop_time x_d residual_from")
ScenarioRun.__doc__ = ("One case of a scenario: its label, the System, the communication step and stop time [s], the "
                       "target [m] (one per axis: a list on a crane of several axes) and the start of the residual "
                       "swing's window [s].")
Contender = namedtuple("Contender", "name source inputs parameters user outputs", defaults=(False, None))
Contender.__doc__ = ("A controller to score: its name, its FMU (a model identifier or an .fmu path), its interface "
                     "(``outputs`` None: it gives whatever the scenario's plant demands), and whether it is the "
                     "user's (an FMU file) rather than a built-in one.")

NEEDS = ("hoist", "forces", "sensed")  # roles beyond the axes that a scenario may need of its plant
STOPPED_DEG = 0.1  # a swing within 0.1 deg counts as stopped (metrics.SETTLED_BAND): every residual target
CASES, QUICK_CASES = 64, 16  # cases of the paired design on a board and on a quick board


@dataclass(frozen=True)
class Scenario:
    """One scenario of the board.

    Attributes
    ----------
    id, title : str
        ``S2``; what it is.
    rank_by : str
        The metric it ranks by (lower is better).
    targets : tuple of Target
    plant : str
        The model identifier of the plant it runs on.
    runs : callable
        ``runs(contender, cases) -> [ScenarioRun]`` (``cases``: of the paired design, where it uses it).
    moves : bool
        The controller is told a target (a move), so it needs an axis's target parameter or a planner's inputs.
    needs : tuple of str
        Roles of :data:`NEEDS` it needs of the plant (a hoist to hoist, forces for a gust or wind, sensed outputs
        for a sensor).
    paired : bool
        Its cases are the paired design's (one per plant case).
    steps, variants : int
        Communication steps it runs at, and runs per plant and step (S8: regulation and a move).
    bounds : dict
        What the board checks at every step (:func:`~crane_fmu.analysis.metrics.bounds_check`): ``u_max``,
        ``v_max``, ``x_min``, ``x_max``.
    duration_note : str
        Why its cases run as long as they do, where a reader would expect otherwise (``" (...)"``; the board
        adds it to the line that says how long they run).
    measures : callable, optional
        ``measures(signals, case) -> {figure: value}``: figures of its own beside
        :func:`~crane_fmu.analysis.metrics.move_metrics`', from the case's
        :func:`~crane_fmu.analysis.metrics.crane_signals` with the plant's hook, load and state
        (:func:`measured_outputs`) and the case (its ``x_d``, ``residual_from``): S13's ``path_deviation_m``;
        its targets may name them.
    """

    id: str
    title: str
    rank_by: str
    targets: tuple
    plant: str
    runs: Callable
    moves: bool = False
    needs: tuple = ()
    paired: bool = False
    steps: int = 1
    variants: int = 1
    bounds: dict | None = None
    duration_note: str = ""
    measures: Callable | None = None

    def __post_init__(self):
        crane = components.get(self.plant).crane
        if crane is None:
            raise ValueError(f"scenario {self.id}: {self.plant} has no crane roles")
        for need in self.needs:
            if need not in NEEDS:
                raise ValueError(f"scenario {self.id}: needs must be among {', '.join(NEEDS)}, got {need!r}")
            if not getattr(crane, need):
                raise ValueError(f"scenario {self.id} needs the plant's {need}, which {self.plant} does not have")

    @property
    def crane(self):
        """The roles of the plant it runs on."""
        return components.get(self.plant).crane

    def scope(self, cases=CASES):
        """``{"plants": n, "steps": n, "cases": n}``: how much of it a board of ``cases`` paired cases runs."""
        plants = cases if self.paired else 1
        return {"plants": plants, "steps": self.steps, "cases": plants * self.steps * self.variants}


_SCENARIOS = Registry("scenario", lambda s: s.id)
register, unregister, get = _SCENARIOS.register, _SCENARIOS.unregister, _SCENARIOS.get


def _registered():
    """The registered scenarios in their ids' natural order (S2 before S10), whichever module registered first."""
    def natural(s):
        return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", s.id)]

    return sorted(_SCENARIOS.registered(), key=natural)


def scenarios():
    """``{id: Scenario}`` of every registered scenario, in their ids' natural order."""
    return {s.id: s for s in _registered()}


def paired():
    """The ids of the scenarios on the paired design."""
    return tuple(s.id for s in _registered() if s.paired)


def plants():
    """The model identifiers of the plants that scenarios run on, in order."""
    return list(dict.fromkeys(s.plant for s in _registered()))


_NOTES = {}


def register_notes(plant, about):
    """Register what a board says of a plant's scenarios: ``about(cases) -> {"crane": text, "design": [lines],
    "bounds": text, "seed": int}`` (the crane and its drive; the paired design, Markdown lines; the bounds checked;
    the paired design's seed)."""
    _NOTES[plant] = about


def notes(plant, cases=CASES):
    """What a board says of the scenarios on ``plant`` (:func:`register_notes`)."""
    return _NOTES[plant](cases)


def check_interface(name, inputs, outputs, parameters=()):
    """Raise ValueError (one line) when a controller fits no plant that a scenario runs on, naming what it misses
    of each.

    What only the scenarios that move the load need (a target position) makes those scenarios not applicable
    (:func:`applicable`), not the controller unusable.
    """
    found = []
    for identifier in plants():
        crane = components.get(identifier).crane
        missing, _ = misses(crane, inputs, outputs, parameters)
        if not missing:
            return
        found.append(f"of {identifier}, it misses {', '.join(missing)} (the interface: inputs "
                     f"{', '.join(crane.state)}; outputs {', '.join(crane.demands)}; for a target position "
                     f"{move_needs(crane)})")
    raise ValueError(f"{name} is not a crane controller: " + "; ".join(found))


def told_in(contender, scenario, target=None):
    """What the contender is told in the scenario (:func:`crane_fmu.controller_interface.told`, the rule simulate
    applies too), moving the load to ``target`` (``{axis position: value}``; None: the scenario's move, if any, to
    somewhere finite); ValueError when it cannot be told the move or is no controller of the scenario's plant."""
    s = get(scenario)
    plant = components.get(s.plant)
    outputs = plant.crane.demands if contender.outputs is None else contender.outputs
    if target is None and s.moves:
        target = {a.position: 0.0 for a in plant.crane.axes}
    return told(contender.name, contender.inputs, outputs, contender.parameters, plant, target if s.moves else None)


OTHER_PLANT = "n/a (no controller of"  # why a contender of another crane does not run a scenario


def applicable(contender, scenario):
    """None when the contender can run the scenario, else why not: it is no controller of the scenario's plant
    (``n/a (no controller of CranePlant)``), or it cannot be told the scenario's move (``n/a (needs x_d or
    x_ref)``)."""
    s = get(scenario)
    crane = s.crane
    outputs = crane.demands if contender.outputs is None else contender.outputs
    if misses(crane, contender.inputs, outputs, contender.parameters)[0]:
        return f"{OTHER_PLANT} {s.plant})"
    try:
        told_in(contender, scenario)
    except ValueError:
        return (f"n/a (needs {' and '.join(a.target for a in crane.axes)} or "
                f"{' and '.join(a.references[0] for a in crane.axes)})")
    return None


def systems_for(contender, scenario, cases=CASES):
    """The :class:`ScenarioRun` cases of one scenario for a contender (``cases``: of the paired design).

    Raises
    ------
    ValueError
        When the scenario does not apply to the contender (:func:`applicable`), or there is no such scenario.
    """
    s = get(scenario)
    why = applicable(contender, scenario)
    if why:
        raise ValueError(f"{contender.name}: {scenario} {why}")
    return s.runs(contender, cases)


def measured_outputs(scenario):
    """The plant's outputs a scenario's own ``measures`` read beside the metrics' (its hook, load and state), or
    none when it has no measures."""
    s = scenarios().get(scenario)
    if s is None or s.measures is None:
        return ()
    crane = s.crane
    return (*crane.hook, *crane.load, *crane.state)


@functools.cache
def measures_version(scenario):
    """The version of a scenario's own ``measures``: a hash of the file that defines them (its constants with them,
    as :data:`crane_fmu.analysis.metrics.VERSION` is of metrics.py); None when it has none."""
    s = get(scenario)
    if s.measures is None:
        return None
    return hashlib.sha256(Path(inspect.getsourcefile(s.measures)).read_bytes()).hexdigest()[:16]


def measured(case, columns):
    """The figures of a case's scenario's own ``measures`` (empty when it has none) from its recorded columns."""
    names = measured_outputs(case["scenario"])
    if not names:
        return {}
    from crane_fmu.analysis import metrics

    return get(case["scenario"]).measures(metrics.crane_signals(columns, names), case)


def met(row, target):
    """Whether one case meets a target: it ran to the end and its metric is within the limit (a target of
    another case: met)."""
    if target.case is not None and row.get("case") != target.case:
        return True
    value = row.get(target.metric)
    return row.get("status") == "ok" and value is not None and value <= target.limit


@functools.cache
def planned_end(plan):
    """The end [s] of the move the planner plans with the parameters ``plan`` (``((name, value), ...)``): computed once
    per board (S1-S14), not for each of its cases."""
    from crane_fmu.model import planner

    return planner.configure({**planner.COMPONENT.defaults(), **dict(plan)}).end


# the StateEstimator with the force states that gives an offset-free controller the wind's force (S4, S10, S14)
FORCE_ESTIMATOR = {"sigma_force": 50.0, "camera": 1.0, "delay": 0.0}  # 50 N/s: F2 within 2.5 % in 1.23 s (tests)

# the registrations: S1-S10 on the planar crane, S11-S14 on the crane in three dimensions
from crane_fmu.analysis import planar_scenarios, spatial_scenarios  # noqa: E402, F401, I001
