"""The built-in systems by name, and where a command finds the system it is given.

A system is data (``crane_fmu.cosim.System``): instances named by component
model identifiers, connections matched by signal name, parameter values, times.
Every command takes a system by name or as an SSP file; nothing else knows
which instances exist. A built-in system's tags say what else is made of it:

- ``container``: packed as one FMU by ``crane-fmu build`` (fmpy's container, ``container.py``);
- ``one-fmu``: built as one native FMU once its components are all native (``build_scripts/one_fmu.py``);
- ``regulation``: a closed loop regulating from a swing, run by ``crane-fmu targets``.
"""

import contextlib
import json
import math
from dataclasses import replace
from pathlib import Path

from crane_fmu import components, crane_parameters, laws
from crane_fmu.closed_loop import axis_planners, planner_target
from crane_fmu.controller_interface import references, told, tracked
from crane_fmu.cosim import ssp
from crane_fmu.cosim.connections import Connection
from crane_fmu.cosim.ssp import load_system
from crane_fmu.cosim.system import System, is_file, read_fmu
from crane_fmu.registry import Registry

_SYSTEMS = Registry("system", lambda s: s.name, " (or an .ssp/.ssd file)")
register, unregister, get, registered = _SYSTEMS.register, _SYSTEMS.unregister, _SYSTEMS.get, _SYSTEMS.registered


def tagged(tag):
    """The names of the registered systems with ``tag``, in registration order."""
    return [s.name for s in registered() if tag in s.tags]


@contextlib.contextmanager
def open_system(name_or_file):
    """Yield the system of a registered name or of an SSP file (``.ssp`` or ``.ssd``)."""
    text = str(name_or_file)
    if text.endswith((".ssp", ".ssd")):
        with load_system(text) as system:
            yield system
    else:
        yield get(text)


def resolve(system, fmu_dir):
    """``system.resolve(fmu_dir)``, with a hint where a built FMU is missing: the one check of a system's wiring.

    Every connection the system was designed with keeps both ends in the FMUs used, and an FMU that
    replaced an instance's (``--use``) fits its place: a registered component of another role (a plant
    in the controller's place) is refused, and a controller keeps the measured-state inputs (the rest
    of a controller's inputs, the references and ``l1_now``, are its own choice).

    Raises
    ------
    ValueError
        One line naming the instance, the variable and the FMU:
        ``"controller: mine/PdTypo.fmu has no output u, which the system connects to plant.u"``.
    """
    crane_parameters.check_reserved(system)
    for path in system.fmus(fmu_dir).values():
        if laws.is_law(path):
            laws.component(path)  # its file, its import, its component: one line
        elif not path.is_file():
            raise ValueError(f"{path} not found: build the FMUs first (crane-fmu build)")
    fmus, optional, plant = system.fmus(fmu_dir), {}, plant_of(system)
    for name, designed in system.replaced.items():
        place, used = _component(designed), _component(fmus[name])
        if place is None:
            continue
        if used is not None and used.role != place.role:
            raise ValueError(f"{name}: {fmus[name]} is a {used.role} ({used.model_identifier}), where the system "
                             f"has a {place.role} ({place.model_identifier})")
        if place.role == "controller":
            measured = plant.crane.state if plant is not None and plant.crane else ()
            optional[name] = [n for n in place.names("input") if n not in measured]
    return system.resolve(fmu_dir, optional)


def plant_of(system):
    """The registered component of the system's first plant instance (its crane roles), or None."""
    instance = components.by_role(kinds(system)).get("plant")
    return None if instance is None else components.find(kinds(system)[instance])


def move_target(system):
    """``{axis position: target}`` of the system's move, by role: each axis's target parameter (``x_d``) of its
    planner (``closed_loop.axis_planners``: a planner per axis in an open loop, whose own ``x_d`` it is), else of
    the first controller, else 0 (regulation at the origin)."""
    found = kinds(system)
    by_role, crane = components.by_role(found), plant_of(system).crane
    planners = axis_planners(crane, found, system.connections)
    controller = system.parameters.get(by_role["controller"], {}) if "controller" in by_role else {}
    target = {}
    for a in crane.axes:
        planned = system.parameters.get(planners[a.position], {}) if a.position in planners else {}
        held = planner_target(a, components.get(found[planners[a.position]]).names("parameter")) \
            if a.position in planners else a.target
        target[a.position] = planned.get(held, controller.get(a.target, 0.0))
    return target


def cable_source(system):
    """The instance whose ``ddx_ref`` drives the plant's hoist (a planner of the cable's length), or None."""
    hoist = plant_of(system).crane.hoist
    plant = components.by_role(kinds(system))["plant"]
    return next((c.source for c in system.connections if c.target == plant and c.input == hoist), None)


def _component(source):
    """The registered component of an instance's source (a model identifier or an ``.fmu`` file), or None."""
    if is_file(source):
        return components.find(read_fmu(source).coSimulation.modelIdentifier)
    return components.find(str(source))


def tell_controllers(system, fmu_dir, values=(), sources=None):
    """``(system, notes)``: each controller told what :func:`crane_fmu.controller_interface.told` gives it.

    ``values``: what the run sets over the system's own after this (``--parameters``, ``--set``), in order: the
    targets are read with them applied (a planner's ``x_d`` set), and the told ones are set on ``system`` without them,
    so that a value the user gives the controller itself still wins. ``sources``: a dict that gets where each told
    value comes from, ``{"controller.x_d": "planner.x_d"}`` (a study's cases that set the planner's set it too).

    A system moves the load when its design feeds a controller's references of an axis (``x_ref``, from a
    planner); the move's target is that planner's target parameter (``x_d``). A controller with the planner's
    inputs gets them (as connected); one with the axes' target parameters instead gets the targets there (a note
    says so); one with neither is refused. A controller is an instance whose place (its component as designed)
    has the role ``controller``; what it is checked against is the system's plant (its crane roles).

    Raises
    ------
    ValueError
        One line naming the instance, the FMU and what it misses.
    """
    plant = plant_of(system)
    if plant is None or plant.crane is None:
        return system, []
    fmus, notes, axes = system.fmus(fmu_dir), [], plant.crane.axes
    given = system
    for overrides in values:
        given = crane_parameters.with_values(given, overrides)
    designed = system.designed(fmu_dir)
    moves = {c.target for c in designed if c.input == axes[0].references[0]}
    # each axis's planner, and its parameter that holds the target (a one-axis planner's x_d plans the y axis too)
    planners = axis_planners(plant.crane, kinds(replace(system, instances={**system.instances, **system.replaced})),
                             designed)
    for name in system.instances:
        place = _component(system.replaced.get(name, system.instances[name]))
        if place is None or place.role != "controller":
            continue
        variables = read_fmu(fmus[name]).modelVariables
        names = {causality: [v.name for v in variables if v.causality == causality]
                 for causality in ("input", "output", "parameter")}
        target, source = None, {}
        if name in moves:  # the planners' targets (a planner without them: only its references can tell the move)
            target = {}
            for a in axes:
                planner = planners.get(a.position)
                starts = {v.name: v.start for v in read_fmu(fmus[planner]).modelVariables} if planner else {}
                parameter = planner_target(a, starts)
                source[a.target] = f"{planner}.{parameter}" if planner else "no planner"
                target[a.position] = float(given.parameters.get(planner, {}).get(parameter,
                                                                                starts.get(parameter, math.inf)))
        try:
            move = told(f"{name} ({fmus[name]})", names["input"], names["output"], names["parameter"], plant, target)
        except ValueError as exc:
            where = f" (system {system.name} moves it to {', '.join(source.values())})" if name in moves else ""
            raise ValueError(f"{exc}{where}") from None
        if move.targets:
            system = system.with_parameters({name: move.targets})
            told_text = ", ".join(f"{name}.{k} = {v:g} m ({source[k]})" for k, v in move.targets.items())
            if sources is not None:
                sources.update({f"{name}.{k}": source[k] for k in move.targets})
            notes.append(f"{name} ({Path(fmus[name]).name}) has no inputs {', '.join(tracked(plant.crane))}: it is "
                         f"told the move's target, {told_text}")
    return system, notes


def kinds(system):
    """``{instance: model identifier}``; an instance given as an ``.fmu`` file is named by its modelDescription."""
    return {name: read_fmu(source).coSimulation.modelIdentifier if is_file(source) else source
            for name, source in system.instances.items()}


def prepare(system, step=None, stop_time=None, values=(), check=True):
    """The system as it runs, prepared in one place for every run (simulate, compare, sweep, targets, the
    reproduction, the benchmarks, the one-FMU generator): what a command gives over the system's own.

    Parameters
    ----------
    system : System
    step, stop_time : float, optional
        The communication step and stop time [s] (default: the system's).
    values : sequence of dict
        ``{instance: {variable: value}}`` set over the system's values, in order (a parameter file's,
        then ``--set``'s); the crane's values under ``crane`` (:mod:`crane_fmu.crane_parameters`).
    check : bool
        Check the values by the components' rules (:func:`check_parameters`); a command that reports a
        refused case as a row of its table checks later.

    Returns
    -------
    System
        With that step and stop time, those values, the crane's set on the instances they bind (:func:`bind`),
        and ``h`` set to the step on every instance whose
        component has that parameter (the communication step it is designed for: the LQR's discrete
        design, the speed guards) where nothing set it; every value checked by its component's rules.

    Raises
    ------
    ValueError
        One line: an unknown instance, a value a component's rules refuse (``"plant: l1 must be > 0 and
        finite, got -1.0"``). Whether the step divides the interval is the run's check (the master's).
    """
    step = system.step if step is None else step
    system = replace(system, step=step, stop_time=system.stop_time if stop_time is None else stop_time)
    for overrides in values:
        system = crane_parameters.with_values(system, overrides)
    system = bind(system)
    designed = {}
    for name, kind in kinds(system).items():
        component = components.find(kind)
        if component and "h" in component.names("parameter") and "h" not in system.parameters.get(name, {}):
            designed[name] = {"h": step}
    system = named_items(system.with_parameters(designed))
    if check:
        check_parameters(system)
    return system


def named_items(system):
    """The system with each Enumeration value given as its item's value (an SSP or OSP file's Integer, 3) given by
    the item's name (``zvd``), as the components' rules and their Python models read it; any other value kept (the
    rules refuse it)."""
    from crane_fmu.model.tables import enumeration_name

    named = {}
    for name, kind in kinds(system).items():
        component = components.find(kind)
        rows = {v.name: v for v in component.variables if v.type == "Enumeration"} if component else {}
        for variable, value in system.parameters.get(name, {}).items():
            if variable in rows and isinstance(value, (int, float)) and not isinstance(value, bool) and \
                    value in range(1, len(rows[variable].items) + 1):
                named.setdefault(name, {})[variable] = enumeration_name(rows[variable], int(value))
    return system.with_parameters(named) if named else system


def modelled(system):
    """``{instance: crane parameters it models}`` (:func:`crane_fmu.crane_parameters.modelled`): a registered
    component's as it declares, an FMU file of another's by its parameters of those names."""
    def parameters(name):
        source = system.instances[name]
        return [v.name for v in read_fmu(source).modelVariables if v.causality == "parameter"] \
            if is_file(source) else ()
    return crane_parameters.modelled(kinds(system), parameters)


def bind(system):
    """The system with the crane's values (``crane.l2``) set on every instance that models the crane and has
    no value of its own (:func:`crane_fmu.crane_parameters.bind`): as the master runs it."""
    return crane_parameters.bind(system, modelled(system))


def settable(system, fmus):
    """:func:`crane_fmu.cosim.system.settable` of ``fmus`` and the crane's parameters (``crane.l2``): what
    ``--set``, a parameter file and a study may name."""
    from crane_fmu.cosim.system import settable as instances

    return {**instances(fmus), **crane_parameters.settable(modelled(system))}


def write_ssp(system, fmu_dir, path):
    """Write the system as an SSP package (:func:`crane_fmu.cosim.ssp.write_ssp`): the crane's parameters once, as
    values of the system's own (``crane.l2``) mapped to the instances each binds, which carry it too."""
    fmus = system.fmus(fmu_dir)

    def start(instance, name):
        return next(float(v.start) for v in read_fmu(fmus[instance]).modelVariables if v.name == name)

    shared = crane_parameters.shared(system, modelled(system), start)
    return ssp.write_ssp(bind(system), fmu_dir, path, {f"{crane_parameters.CRANE}.{name}": (value, [
        (instance, name) for instance in instances]) for name, (value, instances) in shared.items()})


def check_parameters(system, checked=None):
    """Apply each instance's component rules (by model identifier, never by instance name).

    ``checked``: a dict that keeps each (model identifier, values) checked and its message (None: valid), for
    many systems of the same components (a study's cases, a board's): a component that designs itself from
    its parameters (the LQR, the MPC, the estimator) then does so once for its values, not once a case.

    Raises
    ------
    ValueError
        ``"plant: l1 must be > 0 and finite, got -1.0"``.
    """
    checked = {} if checked is None else checked
    for name, identifier in kinds(system).items():
        values = system.parameters.get(name, {})
        key = (str(system.instances[name]) if laws.is_law(system.instances[name]) else identifier,
               json.dumps(values, sort_keys=True))
        if key not in checked:
            try:
                source = system.instances[name]
                if laws.is_law(source):  # a law file's own rules, as its FMU would check them
                    laws.check(source, values)
                else:
                    components.check_parameters(identifier, values)
                checked[key] = None
            except ValueError as exc:
                checked[key] = str(exc)
        if checked[key] is not None:
            raise ValueError(f"{name}: {checked[key]}")


LOOP = ("container", "one-fmu")  # a closed loop packed as one FMU both ways


def measuring(crane):
    """What a crane measures, as connections: the plant's sensed outputs (``crane.sensed``) to the sensor (which
    gives ``<name>_meas`` to the estimator by name), the estimator's state (``crane.state``) to the controller
    (written out: the plant has outputs of those names too); the demands and the cable's length connect by name."""
    return tuple(Connection("plant", name, "sensor", name) for name in crane.sensed) + tuple(
        Connection("estimator", name, "controller", name) for name in crane.state)


def _planar():
    """The planar crane's roles, and its settings of the built-in systems: from rest, drive limits, a move."""
    crane = components.get("CranePlant").crane
    return crane, {crane.start_swing: 0.0}, {"u_max": 2.0, "v_max": 1.0}, {crane.axes[0].target: 2.0}


CRANE, REST, DRIVE, MOVE = _planar()
register(System("paper", {"plant": "CranePlant", "controller": "BacksteppingController"},
                description="Section V: the plant and the paper's backstepping controller (eq 21, derived b3), "
                            "theta1(0) = 10 deg", tags=(*LOOP, "regulation")))
register(System("free", {"plant": "CranePlant"}, parameters={"plant": {"u": 0.0}},  # u = 0 on purpose, not unfed
                description="the plant alone, u = 0: free swing from 10 deg"))
register(System("lqr", {"plant": "CranePlant", "controller": "LqrController"},
                description="Section V regulation from theta1(0) = 10 deg by the discrete LQR, |u| <= 2 m/s2, "
                            "|v| <= 1 m/s", tags=(*LOOP, "regulation")))
register(System("energy", {"plant": "CranePlant", "controller": "EnergyController"},
                description="Section V regulation from theta1(0) = 10 deg by the energy-coupling law (proof in "
                            "crane_fmu/model/energy.py)", tags=(*LOOP, "regulation")))
register(System("transport", {"plant": "CranePlant", "planner": "TrajectoryPlanner", "controller": "LqrController"},
                parameters={"plant": REST, "planner": MOVE}, stop_time=10.0,
                description="a 2 m move from rest: ZV-shaped reference (planner.x_d) tracked by the LQR",
                tags=LOOP))
register(System("hoist-transport",
                {"plant": "CranePlant", "planner": "TrajectoryPlanner", "hoist": "TrajectoryPlanner",
                 "controller": "LqrController"},
                connections=tuple(Connection("planner", name, "controller", name) for name in references(CRANE))
                + (Connection("hoist", "ddx_ref", "plant", CRANE.hoist),),
                # the crane's l1 is 2 m; the planner shapes the move for l1 = 1.5 m (its own, on purpose: half way
                # while the hoist lifts); the hoist's planner plans the cable, not a swing: its swing references,
                # which nothing reads, keep its own model's l1 = 1 m
                parameters={"crane": {"l1": 2.0}, "plant": {**REST, "l1_min": 1.0, "l1_max": 2.0},
                            "planner": {**MOVE, "l1": 1.5, "shaper": "zvd"},
                            "hoist": {"x0": 2.0, "x_d": 1.0, "shaper": "none", "u_max": 0.5, "v_max": 0.5, "l1": 1.0},
                            "controller": {"l1_low": 1.0, "l1_high": 2.0}},
                stop_time=12.0,
                description="a 2 m move while the hoist lifts the load from l1 = 2 m to 1 m; the LQR's gains "
                            "follow the measured cable length", tags=("one-fmu",)))
register(System("lqg", {"plant": "CranePlant", "controller": "LqrController", "sensor": "CraneSensor",
                        "estimator": "StateEstimator"},
                connections=measuring(CRANE), parameters={"plant": DRIVE},
                description="Section V regulation from theta1(0) = 10 deg with only x and theta1 measured (1 mm, "
                            "0.1 deg noise, one step late): a Kalman filter in front of the LQR, |u| <= 2 m/s2, "
                            "|v| <= 1 m/s", tags=("one-fmu",)))
register(System("lqg-transport", {"plant": "CranePlant", "planner": "TrajectoryPlanner", "controller": "LqrController",
                                  "sensor": "CraneSensor", "estimator": "StateEstimator"},
                connections=measuring(CRANE), parameters={"plant": {**REST, **DRIVE}, "planner": MOVE},
                stop_time=10.0,
                description="the 2 m move of transport with only x and theta1 measured: a Kalman filter in front of "
                            "the LQR", tags=("one-fmu",)))
register(System("hard-hit", {"plant": "CranePlant", "controller": "HardHitController"},
                parameters={"plant": {CRANE.start_swing: 1.0471975511965976, **DRIVE}},
                description="a hard hit: regulation from theta1(0) = 60 deg by LQR gains scheduled on the swing "
                            "energy, |u| <= 2 m/s2, |v| <= 1 m/s", tags=("one-fmu",)))
register(System("mpc", {"plant": "CranePlant", "controller": "MpcController"},
                parameters={"plant": DRIVE},
                description="Section V regulation from theta1(0) = 10 deg by the constrained MPC: the shortest move "
                            "to rest within |u| <= 2 m/s2, |v| <= 1 m/s, tracked by a QP every 50 ms",
                tags=("one-fmu",)))
register(System("mpc-transport", {"plant": "CranePlant", "controller": "MpcController"},
                parameters={"plant": {**REST, **DRIVE}, "controller": MOVE},
                stop_time=10.0,
                description="a 2 m move from rest by the constrained MPC: its own shortest move within the drive's "
                            "limits, tracked by a QP every 50 ms", tags=("one-fmu",)))


# ---- the crane in three dimensions (CranePlant3D, issue 52): open loop, the LQR and the MPC of two axes --------------
def _spatial():
    """The spatial crane's roles; its drive on each axis (the planar crane's limits); the elliptic start swing (S12:
    the hook 10 deg along x, 5 deg along y a quarter of the slow mode's period later: at its fastest now)."""
    from crane_fmu.model.parameters import plant_parameters
    from crane_fmu.model.planner import modes
    from crane_fmu.model.plant3d import COMPONENT

    crane = COMPONENT.crane
    slow = modes(plant_parameters(COMPONENT.defaults()))[0][0]
    drive = {f"{k}{a}_max": v for a in "xy" for k, v in (("u", 2.0), ("v", 1.0))}
    swing = {"theta1x_0": math.radians(10.0), "dtheta1y_0": math.radians(5.0) * slow}
    return crane, drive, swing


CRANE3D, DRIVE3D, ELLIPTIC = _spatial()
REST3D = {CRANE3D.start_swing: 0.0}
DIAGONAL = {"x": 2.0, "y": 1.5}  # S11's move [m]
L_PATH = ((0.0, 0.0), (3.0, 0.0), (3.0, 2.0))  # S13's path [m]
CORRIDOR = 0.3  # S13: the load within this of the path's centre line [m]


# the diagonal move (2 m, 1.5 m); each planner keeps its default ZV shaper and plans along its own x for the
# axis its ddx_ref drives
register(System("open-loop-3d", {"plant": "CranePlant3D", "planner_x": "TrajectoryPlanner",
                                 "planner_y": "TrajectoryPlanner"},
                connections=tuple(Connection(f"planner_{a.position}", "ddx_ref", "plant", a.demand)
                                  for a in CRANE3D.axes),
                parameters={"plant": {**REST3D, **DRIVE3D}, "planner_x": {"x_d": DIAGONAL["x"]},
                            "planner_y": {"x_d": DIAGONAL["y"]}},
                stop_time=10.0,
                description="the crane in three dimensions moved open loop from rest by (2 m, 1.5 m): a ZV-shaped "
                            "planner per axis drives its trolley acceleration, |u| <= 2 m/s2, |v| <= 1 m/s on each "
                            "axis", tags=("one-fmu",)))


def planned(crane, planners, controller="controller"):
    """Connections from one TrajectoryPlanner per axis (``{axis position: instance}``) to the controller's references
    of that axis: the planner's ``x_ref``, ``dx_ref``, ``ddx_ref`` to the axis' (``y_ref``, ...), its swing
    references to the axis' (``theta1_ref`` to ``theta1y_ref``, ...)."""
    connections = []
    for axis in crane.axes:
        ours = (*axis.references, *(f"{name}{axis.position}_ref" for name in ("theta1", "dtheta1", "theta2",
                                                                                  "dtheta2")))
        theirs = ("x_ref", "dx_ref", "ddx_ref", "theta1_ref", "dtheta1_ref", "theta2_ref", "dtheta2_ref")
        connections += [Connection(planners[axis.position], out, controller, into) for out, into in zip(theirs, ours)]
    return tuple(connections)


def measured_swing(crane, planners, plant="plant"):
    """Connections from the plant's swing state of each axis (its roles ``crane.state``: ``theta1y``, ``dtheta1y``,
    ``theta2y``, ``dtheta2y`` for ``y``) to that axis' TrajectoryPlanner (``{axis position: instance}``), its inputs
    ``theta1_now`` ... that a plan from the measured swing (``plan_from = measured``) starts from."""
    from crane_fmu.model.planner import MEASURED

    connections = []
    for axis in crane.axes:
        ours = tuple(f"{name[:-4]}{axis.position}" for name in MEASURED)  # theta1_now: the plant's theta1x
        missing = [name for name in ours if name not in crane.state]
        if missing:
            raise ValueError(f"measured_swing: the crane's state has no {', '.join(missing)} (axis {axis.position})")
        connections += [Connection(plant, out, planners[axis.position], into) for out, into in zip(ours, MEASURED)]
    return tuple(connections)


def _path_plan():
    """Each axis' planner parameters along S13's L path, the load's planned position (the trolley's reference and
    the swing the planner's linear model gives the load) kept within half the corridor (the other half is what the
    crane does beyond its plan: the tracking error, the nonlinear coupling): :func:`crane_fmu.model.path.plan`."""
    from crane_fmu.model import path

    return path.plan(L_PATH, CORRIDOR / 2, load=True)


PATH_PLAN = _path_plan()
_PLANNERS = {"x": "planner", "y": "planner_y"}
_MOVE3D = {"planner": {"x_d": DIAGONAL["x"]}, "planner_y": {"x_d": DIAGONAL["y"]}}
_PATH3D = {_PLANNERS[a]: {k: v for k, v in plan.items() if v != 0.0} for a, plan in PATH_PLAN.items()}
register(System("lqr3d", {"plant": "CranePlant3D", "controller": "LqrController3D"},
                parameters={"plant": {**DRIVE3D, **ELLIPTIC}},
                description="the crane in three dimensions regulated from an elliptic swing (hook 10 deg along x, 5 "
                            "deg along y a quarter period later) by the LQR of each axis, |u| <= 2 m/s2, |v| <= 1 m/s "
                            "per axis", stop_time=10.0, tags=("one-fmu",)))
register(System("lqr3d-move", {"plant": "CranePlant3D", "planner": "TrajectoryPlanner",
                                "planner_y": "TrajectoryPlanner", "controller": "LqrController3D"},
                connections=planned(CRANE3D, _PLANNERS), parameters={"plant": {**REST3D, **DRIVE3D}, **_MOVE3D},
                description="a diagonal move from rest (2 m along x, 1.5 m along y): a ZV-shaped reference per "
                            "axis (planner.x_d, planner_y.x_d) tracked by the LQR of each axis", stop_time=10.0,
                tags=("one-fmu",)))
register(System("lqr3d-path", {"plant": "CranePlant3D", "planner": "TrajectoryPlanner",
                                "planner_y": "TrajectoryPlanner", "controller": "LqrController3D"},
                connections=planned(CRANE3D, _PLANNERS), parameters={"plant": {**REST3D, **DRIVE3D}, **_PATH3D},
                description="an L path from rest (3 m along x, then 2 m along y): ZV-shaped references per axis, the "
                            "y leg started as early as keeps the load's planned position within 0.15 m of the path "
                            "(crane_fmu.model.path), tracked by the LQR of each axis", stop_time=15.0,
                tags=("one-fmu",)))
register(System("mpc3d", {"plant": "CranePlant3D", "controller": "MpcController3D"},
                parameters={"plant": {**DRIVE3D, **ELLIPTIC}},
                description="the crane in three dimensions regulated from the elliptic swing of lqr3d by the "
                            "constrained MPC of each axis, |u| <= 2 m/s2, |v| <= 1 m/s per axis",
                stop_time=10.0, tags=("one-fmu",)))
register(System("mpc3d-move", {"plant": "CranePlant3D", "controller": "MpcController3D"},
                parameters={"plant": {**REST3D, **DRIVE3D}, "controller": {"x_d": DIAGONAL["x"], "y_d": DIAGONAL["y"]}},
                description="lqr3d-move's diagonal move by the constrained MPC of each axis: its own "
                            "shortest move per axis within the drive's limits", stop_time=10.0, tags=("one-fmu",)))
register(System("mpc3d-path", {"plant": "CranePlant3D", "controller": "MpcController3D"},
                parameters={"plant": {**REST3D, **DRIVE3D}, "controller": {
                    "x_d": L_PATH[-1][0], "y_d": L_PATH[-1][1], "x_via": L_PATH[1][0], "y_via": L_PATH[1][1],
                    "corridor": CORRIDOR}},
                description="lqr3d-path's L path by the constrained MPC of each axis, the y leg started "
                            "as early as the corridor lets a time-optimal move", stop_time=15.0, tags=("one-fmu",)))
