"""The crane in three dimensions: its scenarios S11-S12 and their targets, registered as data (:mod:`.scenarios`).

The crane is ``CranePlant3D`` with the Section V masses and lengths and the planar crane's drive on each axis
(2 m/s2 and 1 m/s). Linearised at rest it is two planar cranes, one per axis, so every target comes from the
planar physics axis by axis: the floor of a task on both axes is the larger of the axes' planar floors
(:func:`crane_fmu.analysis.floor.spatial_floor`), the residual swing's window as the planar one
(:func:`.planar_scenarios.residual_from`): one slow period after the axis whose planned move ends last. Every metric is
:func:`crane_fmu.analysis.metrics.move_metrics` of the plant's roles: the position error is the distance in the
plane, the swing both cables' angles from the vertical in space (``swing1``, ``swing2``).
"""

import math

import numpy as np

from crane_fmu import components
from crane_fmu.cosim import Connection, System
from crane_fmu.model.parameters import plant_parameters
from crane_fmu.model.planner import modes
from crane_fmu.systems import CORRIDOR, DIAGONAL, DRIVE3D, ELLIPTIC, L_PATH, PATH_PLAN, REST3D, measured_swing, planned

from .scenarios import (
    CASES,
    FORCE_ESTIMATOR,
    STOPPED_DEG,
    Scenario,
    ScenarioRun,
    Target,
    planned_end,
    register,
    register_notes,
    told_in,
)
from .spatial_plots import distance_to_path
from .wind_equilibrium import wind_deflection

PLANT = "CranePlant3D"
CRANE = components.get(PLANT).crane
DRIVE = {"u_max": 2.0, "v_max": 1.0}  # each axis' (DRIVE3D on the plant), as the planar crane's
PLANNERS = {"x": "planner", "y": "planner_y"}
T_SLOW, T_FAST = (2 * math.pi / w for w in modes(plant_parameters(components.get(PLANT).defaults()))[0])  # 2.37, 0.66 s
MOVE_S = 2.0 / DRIVE["v_max"] + DRIVE["v_max"] / DRIVE["u_max"]  # S2's 2 m, swing ignored: 2.5 s
WIND_S = round(round(MOVE_S + (T_SLOW + T_FAST) / 2, 1) + T_SLOW, 1)  # S10's (and S4's) arrival target: 6.4 s
WIND_SEED = 1.0  # the Wind's seed of S14's one case
EQUILIBRIUM = wind_deflection()  # (theta1, theta2) [rad]: the mean wind's static deflection, about 0.56 deg
# S10's rule on S14's one crane: the swing a stopped crane keeps (its smaller deflection, 0.54 deg) cut, not met
WIND_CUT_DEG = math.floor(math.degrees(min(EQUILIBRIUM)) * 100) / 100
L1, L2 = (components.get(PLANT).defaults()[name] for name in ("l1", "l2"))
LOAD_BAND_M = round(0.005 + L1 * math.sin(EQUILIBRIUM[0]) + L2 * math.sin(EQUILIBRIUM[1]), 4)  # 5 + 14.5 mm
# S11's reference for a tracking controller: per axis the least-time move of the linear crane (the floor's kind), the
# least-effort one 6 % longer (x: 2.90 s for 2.70 s), whose smaller swing (18 deg, not 23) the LQR follows on the
# nonlinear crane closely enough to arrive before the shortest plan ends (2.82 s; the shortest itself: 4.5 s, its
# error after the plan on the band's edge); the ZV-shaped move ends at 3.64 s, past the target (2.97 s)
DIAGONAL_PLAN = {"shaper": "shortest", "stretch": 1.06}
# S12's for a tracking controller: per axis the shortest move to rest where the trolley started from the swing the
# planner measures at its first step (the plant's outputs, connected by role: measured_swing), as the MPC plans from
# the measured state at its first solve; the swing is not told (no theta*_0 of the planners); none for a controller
# without references (the MPC plans its own)
ELLIPTIC_PLAN = {a: {"shaper": "shortest", "plan_from": "measured"} for a in "xy"}
RAIL = 1.0  # m of track beyond either end of a move: checked, not enforced (as the planar scenarios')

# the floors (crane_fmu.analysis.floor.scenario_floors), rounded as the planar ones are; the figures
S11_FLOOR_S, S12_FLOOR_S = 2.70, 2.02
# S13: the planar floors of its legs one after the other (3 m: 4.27 s, then 2 m: 2.70 s), the time to beat
S13_LEGS_S = (4.27, 2.70)
S13_SEQUENTIAL_S = round(sum(S13_LEGS_S), 2)

_REQUIRED = ("the requirement on the Section V crane in three dimensions (|u| <= 2 m/s2 and |v| <= 1 m/s on each "
             "axis, 1 ms step)")
_RESIDUAL = (f"the swing left one slow period ({T_SLOW:.2f} s) after the planned move: {STOPPED_DEG:g} deg moves the "
             f"load of the 1.5 m double pendulum by at most {1.5 * math.sin(math.radians(STOPPED_DEG)) * 1e3:.1f} mm, "
             "as in S2")

SPECS = {
    "S11": ("S11", f"diagonal move ({DIAGONAL['x']:g} m, {DIAGONAL['y']:g} m) from rest", "arrival_s",
            (Target("arrival_s", round(1.10 * S11_FLOOR_S, 2),
                    f"within 5 mm (in the plane) and both cables within 0.5 deg from {1.10 * S11_FLOOR_S:.2f} s",
                    f"1.10 times the floor, {S11_FLOOR_S:.2f} s: the larger of the axes' planar floors (2 m: "
                    f"{S11_FLOOR_S:.2f} s, 1.5 m: 2.44 s), as the linearised crane is a planar crane per axis; "
                    + _REQUIRED),
             Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg", _RESIDUAL))),
    "S12": ("S12", "regulation from an elliptic swing: the hook 10 deg along x, 5 deg along y a quarter of the slow "
                   "period later", "settling_0.1deg_s",
            (Target("settling_0.1deg_s", 3.0, "both cables within 0.1 deg of the vertical by 3.0 s",
                    f"the issue's target, 1.5 times the floor ({S12_FLOOR_S:.2f} s, the x axis': the planar S1 "
                    f"task; the y axis' 5 deg at its fastest needs 1.37 s); " + _REQUIRED),)),
    "S13": ("S13", f"L path: {L_PATH[1][0]:g} m along x, then {L_PATH[2][1] - L_PATH[1][1]:g} m along y, the load "
                   f"within {CORRIDOR:g} m of the path's centre line (a corridor between racks)", "arrival_s",
            (Target("path_deviation_m", CORRIDOR, f"the load within {CORRIDOR:g} m of the path's centre line at every "
                                                  "step", "the corridor between racks: never left"),
             Target("arrival_s", S13_SEQUENTIAL_S, f"within 5 mm and 0.5 deg from {S13_SEQUENTIAL_S:.2f} s",
                    f"no slower than the legs one after the other, each at its planar floor ({S13_LEGS_S[0]:.2f} s "
                    f"and {S13_LEGS_S[1]:.2f} s): a path is planned to overlap them"),
             Target("residual_deg", STOPPED_DEG, "residual swing <= 0.1 deg", _RESIDUAL))),
    "S14": ("S14", "S2's move (2 m along x) in S10's turbulent wind (10 m/s mean, moderate Dryden turbulence, seed 1) "
                   "blowing across it, along y; the swing measured about the mean wind's equilibrium",
            "residual_eq_deg",
            (Target("arrival_eq_s", WIND_S, f"within 5 mm and 0.5 deg of the wind's equilibrium from {WIND_S:.1f} s",
                    "the angles taken from where the mean wind holds the cables (about "
                    f"{math.degrees(EQUILIBRIUM[0]):.2f} and {math.degrees(EQUILIBRIUM[1]):.2f} deg, "
                    "crane_fmu/analysis/wind_equilibrium.py), which no trolley motion along x takes away; the "
                    "trolley within S2's 5 mm, which S14's one case allows (S10's 64 cases do not: there the load's "
                    "position is taken, crane_fmu/analysis/wind_floor.py)"),
             Target("residual_eq_deg", WIND_CUT_DEG,
                    f"residual swing about the equilibrium <= {WIND_CUT_DEG:.2f} deg",
                    "as S10's: the swing a stopped crane keeps (its trolley held at the target, the load hanging "
                    "still from the vertical when the wind sets in swings about the equilibrium by the deflection "
                    f"itself, undamped), S14's crane's smaller deflection ({WIND_CUT_DEG:.2f} deg) the anchor a "
                    "controller must cut"),
             Target("load_error_m", LOAD_BAND_M, f"the load within {LOAD_BAND_M * 1e3:.1f} mm of the target in the "
                    "residual window",
                    "the 5 mm band of arrival plus the load's static offset downwind of a trolley at the target in "
                    f"the mean wind (l1 sin theta1 + l2 sin theta2 at the equilibrium: "
                    f"{(LOAD_BAND_M - 0.005) * 1e3:.1f} mm), what a crane that holds its trolley at the target and "
                    "its load still shows (S10 takes the offset in the design gust, which its 64 cases need)"))),
}
MOVES = ("S11", "S13", "S14")


def cable_angle(a, b, a_eq, b_eq):
    """The angle [rad] between a cable of angles ``(a, b)`` (:mod:`crane_fmu.model.plant3d`'s) and one of
    ``(a_eq, b_eq)``: from the unit vectors ``(sin a cos b, sin b, -cos a cos b)``."""
    u = np.array([np.sin(a) * np.cos(b), np.sin(b), -np.cos(a) * np.cos(b)])
    e = np.array([np.sin(a_eq) * np.cos(b_eq), np.sin(b_eq), -np.cos(a_eq) * np.cos(b_eq)])
    e = np.broadcast_to(e.reshape(3, *([1] * np.ndim(a))), u.shape)
    return np.arctan2(np.linalg.norm(np.cross(u, e, axis=0), axis=0), np.sum(u * e, axis=0))


def _about_equilibrium(signals, case):
    """S14's own figures: :func:`~crane_fmu.analysis.metrics.move_metrics`' arrival and residual swing with both
    cables' angles taken from the mean wind's equilibrium (across the move: along y) instead of the vertical; and
    ``load_error_m``, the load's largest distance in the plane from the target in the residual window (S10's)."""
    from crane_fmu.analysis import metrics

    swing = [cable_angle(signals[f"theta{i}x"], signals[f"theta{i}y"], 0.0, EQUILIBRIUM[i - 1]) for i in (1, 2)]
    figures = metrics.move_metrics(signals["time"], signals["position"], signals["velocity"], swing,
                                   signals["demand"], case["x_d"], case["residual_from"])
    window = np.asarray(signals["time"]) >= case["residual_from"]
    load = [np.asarray(signals[name])[window] - target for name, target in zip(CRANE.load, case["x_d"])]
    error = np.hypot(*load[:2])
    return {"arrival_eq_s": figures["arrival_s"], "residual_eq_deg": figures["residual_deg"],
            "load_error_m": float(np.max(error)) if error.size else None}


def path_deviation(x, y, waypoints=L_PATH):
    """The largest distance [m] of the points ``(x[k], y[k])`` from the polyline through ``waypoints``."""
    return float(np.max(distance_to_path(waypoints, x, y)))


def _path_measures(signals, case):
    """S13's own figure: ``path_deviation_m``, the load's largest distance from the path's centre line."""
    crane = signals["crane"]
    return {"path_deviation_m": path_deviation(signals[crane.load[0]], signals[crane.load[1]])}


def plan_end(axes_plan):
    """The end [s] of the latest of the axes' planned moves (``{axis: planner parameters}``)."""
    return max(planned_end(tuple(sorted(p.items()))) for p in axes_plan.values())


def _runs(sid):
    def runs(c, cases=CASES):
        instances = {"plant": PLANT, "controller": c.source}
        if sid == "S12":
            parameters, connections = {"plant": {**DRIVE3D, **ELLIPTIC}}, ()
            if all(r in c.inputs for a in CRANE.axes for r in a.references):  # a tracking controller: the plan
                for axis, planner in PLANNERS.items():
                    instances[planner], parameters[planner] = "TrajectoryPlanner", dict(ELLIPTIC_PLAN[axis])
                connections = planned(CRANE, PLANNERS) + measured_swing(CRANE, PLANNERS)
            system = System(f"{c.name}-elliptic", instances, connections, parameters=parameters, stop_time=10.0)
            # regulation: the residual swing over the last quarter, as S1's
            return [ScenarioRun("nominal", system, 1e-3, system.stop_time, [0.0, 0.0], 0.75 * system.stop_time)]
        extra = {}
        if sid == "S13":
            targets = dict(zip((a.position for a in CRANE.axes), L_PATH[-1]))
            axes_plan = PATH_PLAN
        elif sid == "S14":  # S2's move; the wind across it, its drag on the y axis' swing
            targets, axes_plan = {"x": 2.0, "y": 0.0}, {"x": {"x_d": 2.0}, "y": {"x_d": 0.0}}
            extra = {"wind": ("Wind", {"seed": WIND_SEED})}
        else:
            targets = {a.position: DIAGONAL[a.position] for a in CRANE.axes}
            axes_plan = {a: {"x_d": v, **DIAGONAL_PLAN} for a, v in targets.items()}
        move = told_in(c, sid, targets)
        parameters, connections = {"plant": {**REST3D, **DRIVE3D}, "controller": {}}, ()
        if move.references:
            for axis, planner in PLANNERS.items():
                instances[planner] = "TrajectoryPlanner"
                parameters[planner] = dict(axes_plan[axis])
            connections = planned(CRANE, PLANNERS)
        else:
            parameters["controller"].update(move.targets)
            if sid == "S13" and {"x_via", "y_via", "corridor"} <= set(c.parameters):  # a controller told the path
                parameters["controller"].update(x_via=L_PATH[1][0], y_via=L_PATH[1][1], corridor=CORRIDOR)
        for name, (kind, values) in extra.items():
            instances[name], parameters[name] = kind, values
            connections = connections + WIND_ACROSS
        if sid == "S14" and OFFSET_FREE and {"F2x_hat", "F2y_hat"} <= set(c.inputs) and "offset_free" in c.parameters:
            for estimator in FORCE_ESTIMATORS.values():
                instances[estimator], parameters[estimator] = "StateEstimator", dict(FORCE_ESTIMATOR_3D)
            connections = connections + estimated_forces(CRANE)
            parameters["controller"]["offset_free"] = OFFSET_FREE
        system = System(f"{c.name}-{ {'S13': 'path', 'S14': 'wind'}.get(sid, 'diagonal')}", instances, connections,
                        parameters=parameters, stop_time=15.0 if sid == "S13" else 10.0)
        return [ScenarioRun("nominal", system, 1e-3, system.stop_time, list(targets.values()),
                            plan_end(axes_plan) + T_SLOW)]
    return runs


# the Wind reads the y axis' swing (the hook's and the load's velocities along y, exactly: y1' = y' + l1 cos b1 b1')
# and pushes along y
WIND_ACROSS = tuple(Connection("plant", ours, "wind", theirs) for ours, theirs in (
    ("dy", "dx"), ("theta1y", "theta1"), ("dtheta1y", "dtheta1"), ("theta2y", "theta2"), ("dtheta2y", "dtheta2"))) + (
    Connection("wind", "F1", "plant", "F1y"), Connection("wind", "F2", "plant", "F2y"))
# S14's wind force estimated per axis (issue 52, item 3): linearised at rest the crane is the planar crane per axis,
# forces included (tests/test_lqr3d.py), so a planar StateEstimator with the force states (the planar S10's
# FORCE_ESTIMATOR: x, theta1, theta2 measured, no noise and no delay, as the controller takes the true state) on each
# axis' signals estimates the forces on its load and hook; a controller that takes them (F2x_hat .. F1y_hat) and has
# offset_free regulates offset-free: 2, the trolley at the target and the cables at the forces' rest, which is what
# S14's arrival (the trolley within 5 mm of the target, the cables about the wind's equilibrium) and its load band
# (the load's static offset downwind of a trolley at the target) measure; 1 (the load at the target) would hold the
# trolley 14.5 mm upwind of it and never arrive. 0: no estimators, the board as before. The filter is S10's with a
# faster force state: no sensor noise here, so a faster estimate costs nothing in noise, and it lets the cables'
# target follow the turbulence's drag instead of the trolley chasing its lean; LqrController3D's load error with
# sigma_force 10, 50 (FORCE_ESTIMATOR's), 200, 500 N/s: 26.9, 20.2, 17.9, 17.5 mm (docs/guide/controllers.md).
OFFSET_FREE = 2.0
FORCE_ESTIMATOR_3D = {**FORCE_ESTIMATOR, "sigma_force": 200.0}
FORCE_ESTIMATORS = {"x": "force_x", "y": "force_y"}


def estimated_forces(crane, estimators=FORCE_ESTIMATORS, controller="controller"):
    """The connections of one planar ``StateEstimator`` per axis (``{axis position: instance}``): the plant's
    position and cable angles of that axis measured (``theta1y`` to ``theta1_meas``, ...), the controller's demand
    on that axis as the applied ``u``, the estimated forces to the controller's inputs of that axis (``F2_hat`` to
    ``F2y_hat``, ...); the plant's state written out to the controller (the estimators' outputs share its names)."""
    connections = [Connection("plant", name, controller, name) for name in crane.state]
    for axis in crane.axes:
        a, estimator = axis.position, estimators[axis.position]
        connections += [Connection("plant", ours, estimator, theirs) for ours, theirs in (
            (a, "x_meas"), (f"theta1{a}", "theta1_meas"), (f"theta2{a}", "theta2_meas"))]
        connections += [Connection(controller, axis.demand, estimator, "u"),
                        Connection(estimator, "F2_hat", controller, f"F2{a}_hat"),
                        Connection(estimator, "F1_hat", controller, f"F1{a}_hat")]
    return tuple(connections)


BOUNDS = {**DRIVE, "x_min": -RAIL, "x_max": max(max(DIAGONAL.values()), *map(max, L_PATH)) + RAIL}
MEASURES = {"S13": _path_measures, "S14": _about_equilibrium}
for _spec in SPECS.values():
    register(Scenario(*_spec, plant=PLANT, runs=_runs(_spec[0]), moves=_spec[0] in MOVES, bounds=BOUNDS,
                      measures=MEASURES.get(_spec[0]), needs=("forces",) if _spec[0] == "S14" else ()))


def _notes(cases):
    return {"crane": "Section V crane in three dimensions (CranePlant3D), each axis' drive limited to 2 m/s2 and 1 m/s",
            "design": [], "bounds": f"the demanded |u| <= {DRIVE['u_max']:g} m/s2 and |v| <= {DRIVE['v_max']:g} m/s on "
                                    f"each axis, the trolley within {-RAIL:g} to {BOUNDS['x_max']:g} m on each",
            "seed": 0}


register_notes(PLANT, _notes)
