"""The floor: the least time the crane needs for a scenario's task under its drive limits.

Method (named wherever a floor is shown, :data:`METHOD`): minimum-time moves on the
crane linearised about the hanging equilibrium (eqs (8)-(9), with the hoist's and the
forces' terms where the scenario has them), the trolley acceleration held over a grid
of :data:`GRID` (zero-order hold), the drive limits ``|u| <= u_max`` and
``|v| <= v_max`` at every grid point and the exact end state as the constraints of a
linear program, whose feasibility scipy's HiGHS decides; bisection on the number of
grid steps gives the least feasible one. A rigid load (no pendulum) needs
``d / v_max + v_max / u_max`` for a long move (the test's known answer).

No controller can do better on the linear model with its input held on that grid; on
the nonlinear plant the floor is a close estimate, not a proof.
"""

import functools
import hashlib
import json
import math
import os
import tempfile
from collections import namedtuple
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.optimize

from crane_fmu.model import disturbances, planner
from crane_fmu.model.parameters import PlantParameters

GRID = 0.01  # s: the hold of the input in the linear programs
METHOD = (f"minimum time to exact rest on the linearised crane, input held over {GRID * 1e3:g} ms (or the "
          "scenario's step, if longer), |u| and |v| within the drive limits: LP feasibility (scipy HiGHS), "
          "bisection on the horizon")

Floor = namedtuple("Floor", "scenario seconds task grid method")
Floor.__doc__ = ("A scenario's floor: the least time [s], the task it is for, the input hold [s] it assumes and "
                 "the method (:data:`METHOD`).")


def crane_model(p, l1=None, dl1=0.0, ddl1=0.0):
    """``(A, B, E)`` of ``s' = A s + B u + E (F1, F2)`` about rest, ``s = (x, dx, theta1, dtheta1, theta2, dtheta2)``.

    Notes
    -----
    The equations of :func:`crane_fmu.model.plant_equations.angular_accelerations` with
    ``sin q = q``, ``cos q = 1`` and products of small quantities dropped::

        mu L th1'' + m2 l2 th2'' = -mu (u + g th1) - 2 mu L' th1' + F1 + F2
        L th1'' + l2 th2''       = -u - g th2 - L'' (th1 - th2) - 2 L' th1' + F2 / m2

    with ``mu = m1 + m2`` and ``L = l1(t)``; without hoisting these are
    :func:`crane_fmu.model.plant_equations.linearisation`.
    """
    big_l = p.l1 if l1 is None else l1
    mu = p.m1 + p.m2
    n_inv = np.linalg.inv(np.array([[mu * big_l, p.m2 * p.l2], [big_l, p.l2]]))
    # right-hand sides as rows over (theta1, dtheta1, theta2, dtheta2), u, (F1, F2)
    stiffness = np.array([[-mu * p.g, -2.0 * mu * dl1, 0.0, 0.0],
                          [-ddl1, -2.0 * dl1, ddl1 - p.g, 0.0]])
    swing = n_inv @ stiffness
    a = np.zeros((6, 6))
    a[0, 1] = a[2, 3] = a[4, 5] = 1.0
    a[3, 2:], a[5, 2:] = swing
    b = np.zeros(6)
    b[1] = 1.0
    b[[3, 5]] = n_inv @ np.array([-mu, -1.0])
    e = np.zeros((6, 2))
    e[[3, 5]] = n_inv @ np.array([[1.0, 1.0], [0.0, 1.0 / p.m2 if p.m2 > 0 else 0.0]])
    return a, b, e


def rigid_model():
    """``(A, B, E)`` of a rigid load: the trolley alone, ``x'' = u``."""
    return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([0.0, 1.0]), np.zeros((2, 2))


def hold(a, b, dt, forcing=None):
    """``(Ad, Bd, cd)``: the exact step of ``s' = A s + B u + c`` over ``dt`` with ``u`` and ``c`` held."""
    n = len(a)
    aug = np.zeros((n + 2, n + 2))
    aug[:n, :n], aug[:n, n], aug[:n, n + 1] = a, b, np.zeros(n) if forcing is None else forcing
    e = scipy.linalg.expm(aug * dt)
    return e[:n, :n], e[:n, n], e[:n, n + 1]


def reachable(steps, start, target, u_max, v_max, free=()):
    """Whether the steps ``[(Ad, Bd, cd)]`` can take ``start`` to ``target`` within the limits.

    The end state must equal ``target`` except at the indices in ``free``; the speed
    (state index 1) stays within ``v_max`` at every grid point and ``|u| <= u_max``.
    """
    n, count = len(start), len(steps)
    phi = np.eye(n)
    gamma = np.zeros((n, count))
    drift = np.zeros(n)
    for k, (ad, bd, cd) in enumerate(steps):  # s_{k+1} = Ad s_k + Bd u_k + cd
        gamma = ad @ gamma
        gamma[:, k] = bd
        phi, drift = ad @ phi, ad @ drift + cd
    rows = [i for i in range(n) if i not in free]
    a_eq = gamma[rows]
    b_eq = (np.asarray(target, float) - phi @ np.asarray(start, float) - drift)[rows]
    # speed after k steps: v0 + sum of u_j (dt_j) for j < k; the speed is linear in between
    speeds = np.tril(np.ones((count, count))) * np.array([bd[1] for _, bd, _ in steps])  # x'' = u: Bd[1] = dt
    a_ub = np.vstack([speeds, -speeds]) if math.isfinite(v_max) else None
    b_ub = (np.concatenate([np.full(count, v_max - start[1]), np.full(count, v_max + start[1])])
            if a_ub is not None else None)
    result = scipy.optimize.linprog(np.zeros(count), A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq,
                                    bounds=[(-u_max, u_max)] * count, method="highs")
    return result.status == 0


def minimum_steps(step_at, start, target, u_max, v_max, free=(), longest=4000):
    """The least number of grid steps that reaches ``target`` (bisection), or None beyond ``longest``.

    ``step_at(k)`` gives the ``(Ad, Bd, cd)`` of grid step ``k``. Reaching the target in
    ``n`` steps implies reaching it in more (rest is kept with ``u = 0``) once every
    forcing has ended; the answer's predecessor was found infeasible.
    """
    def feasible(count):
        return reachable([step_at(k) for k in range(count)], start, target, u_max, v_max, free)

    low, high = 0, 64  # low: infeasible (0 steps: unless the start is the target)
    while not feasible(high):
        low, high = high, 2 * high
        if high > longest:
            return None
    while high - low > 1:
        mid = (low + high) // 2
        low, high = (low, mid) if feasible(mid) else (mid, high)
    return high


def crane_floor(p=None, start=(0.0,) * 6, target=(0.0,) * 6, u_max=2.0, v_max=1.0, dt=GRID, free=(), hoist=None,
                gust=None):
    """The least time [s] from ``start`` to rest at ``target`` on the linearised crane, input held over ``dt``.

    Parameters
    ----------
    p : PlantParameters
        The crane (default: Section V).
    free : tuple of int
        State indices left free at the end (``(0,)``: the trolley may stop anywhere).
    hoist : dict, optional
        A ``TrajectoryPlanner``'s parameters for the main cable's length (``x0`` and
        ``x_d`` are lengths): the hoist's planned motion, known in advance.
    gust : dict, optional
        A ``Gust``'s parameters: its forces, known in advance.
    """
    p = p or PlantParameters()
    hoisting = hoist and planner.configure({**planner.COMPONENT.defaults(), **hoist})
    pushing = gust and disturbances.GUST.check(gust)
    if not hoisting:
        a, b, e = crane_model(p)
        still = hold(a, b, dt)

    @functools.cache
    def step_at(k):
        middle = (k + 0.5) * dt
        if hoisting:
            l1, dl1, ddl1 = planner.reference(hoisting, middle)[:3]
            a_k, b_k, e_k = crane_model(p, l1, dl1, ddl1)
        else:
            a_k, b_k, e_k = a, b, e
        if pushing and pushing.start < (k + 1) * dt and k * dt < pushing.start + pushing.duration:
            return hold(a_k, b_k, dt, e_k @ np.array(disturbances.gust(pushing, middle)))
        return hold(a_k, b_k, dt) if hoisting else still

    steps = minimum_steps(step_at, start, target, u_max, v_max, free)
    return None if steps is None else round(steps * dt, 9)


def spatial_floor(tasks, **kwargs):
    """The least time [s] of a task on both axes of the crane in three dimensions: the larger of the axes' planar
    floors (:func:`crane_floor` of each ``{start, target}`` in ``tasks``), as its linearisation at rest is a planar
    crane per axis, uncoupled, each with its own drive limits."""
    floors = [crane_floor(**task, **kwargs) for task in tasks]
    return None if None in floors else max(floors)


def rigid_floor(distance, u_max, v_max, dt=GRID):
    """The least time [s] of a rest-to-rest move of a rigid load, by the same linear programs."""
    a, b, _ = rigid_model()
    step = hold(a, b, dt)
    steps = minimum_steps(lambda k: step, (0.0, 0.0), (distance, 0.0), u_max, v_max)
    return round(steps * dt, 9)


def planar_tasks():
    """``{scenario: (task, crane_floor's arguments, grid)}``: the planar floors' tasks (:func:`scenario_floors`)."""
    from .planar_scenarios import DISTANCE, DRIVE, GUST, HOIST, STEPS

    swing = (0.0, 0.0, math.radians(10.0), 0.0, 0.0, 0.0)
    moved = (DISTANCE, 0.0, 0.0, 0.0, 0.0, 0.0)
    hoist = {"x0": HOIST["from"], "x_d": HOIST["to"], "shaper": "none", "u_max": HOIST["u_max"],
             "v_max": HOIST["v_max"]}
    coarse = max(STEPS)
    limits = {"u_max": DRIVE["u_max"], "v_max": DRIVE["v_max"]}
    return {
        "S1": ("theta1 = 10 deg to rest, trolley back at x_d", dict(start=swing, **limits), GRID),
        "S2": (f"{DISTANCE:g} m from rest to rest", dict(target=moved, **limits), GRID),
        "S4": (f"{DISTANCE:g} m from rest to rest, the gust known in advance", dict(target=moved, gust=GUST, **limits),
               GRID),
        "S6": (f"S1's task, the input held over {coarse * 1e3:g} ms", dict(start=swing, dt=coarse, **limits), coarse),
        "S7": (f"{DISTANCE:g} m from rest to rest while hoisting, the hoist's motion known in advance",
               dict(target=moved, hoist=hoist, p=PlantParameters(l1=HOIST["from"]), **limits), GRID),
    }


@functools.cache
def scenario_floors():
    """``{scenario: Floor}`` for the scoreboard's scenarios on the nominal plant (S1, S2, S4, S6, S7; S11, S12 of
    the crane in three dimensions, :func:`spatial_scenario_floors`).

    Each is the task its ranking figure measures, under the scenario's limits: S1 and S6
    end at rest with the trolley back at ``x_d = 0`` (S6 with the input held over its
    longest step, 50 ms); S2, S4 and S7 end at rest at the target, S4 with the gust and
    S7 with the hoist's motion known in advance.
    """
    floors = {sid: Floor(sid, crane_floor(**kwargs), task, grid, METHOD)
              for sid, (task, kwargs, grid) in planar_tasks().items()}
    return {**floors, **spatial_scenario_floors()}


def spatial_tasks():
    """``{scenario: (task, [crane_floor's arguments of each axis])}`` of the spatial scenarios' floors
    (:func:`spatial_scenario_floors`)."""
    from crane_fmu.systems import DIAGONAL, ELLIPTIC

    from .spatial_scenarios import DRIVE

    limits = {"u_max": DRIVE["u_max"], "v_max": DRIVE["v_max"]}
    diagonal = [dict(target=(DIAGONAL[a], 0.0, 0.0, 0.0, 0.0, 0.0), **limits) for a in "xy"]
    elliptic = [dict(start=(0.0, 0.0, ELLIPTIC.get(f"theta1{a}_0", 0.0), ELLIPTIC.get(f"dtheta1{a}_0", 0.0), 0.0,
                            0.0), **limits) for a in "xy"]
    return {"S11": (f"({DIAGONAL['x']:g} m, {DIAGONAL['y']:g} m) from rest to rest, each axis' planar floor",
                    diagonal),
            "S12": ("the elliptic swing (10 deg along x, 5 deg along y a quarter period later) to rest, trolley back "
                    "where it started: each axis' planar floor", elliptic)}


def spatial_scenario_floors():
    """``{scenario: Floor}`` of the crane in three dimensions (S11, S12): each the larger of its axes' planar
    floors (:func:`spatial_floor`) under the drive limits of each axis."""
    return {sid: Floor(sid, spatial_floor(axes), task, GRID, METHOD) for sid, (task, axes) in spatial_tasks().items()}


def code_key():
    """A hash of what the floors are computed by: this package's sources and numpy's and scipy's versions."""
    digest = hashlib.sha256(f"numpy {np.__version__} scipy {scipy.__version__}".encode())
    package = Path(__file__).resolve().parents[1]
    for path in sorted(package.rglob("*.py")):
        digest.update(str(path.relative_to(package)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:20]


SHIPPED = Path(__file__).with_name("floors.json")  # the floors as the package ships them, under their inputs_key()


def inputs_key():
    """A hash of the code the floors are made of: the tasks (:func:`planar_tasks`, :func:`spatial_tasks`, by
    value), the grid and the method, this module's and the crane model's sources (``crane_fmu/model``). Narrower than
    :func:`code_key`: an edit elsewhere in the package leaves it unchanged. The libraries' versions are kept beside
    it (:func:`.planar_scenarios.library_versions`): a test tells stale floors from another machine's libraries."""
    digest = hashlib.sha256()
    here = Path(__file__).resolve()
    for path in [here, *sorted((here.parents[1] / "model").glob("*.py"))]:
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    digest.update(repr((planar_tasks(), spatial_tasks(), GRID, METHOD)).encode())
    return digest.hexdigest()[:20]


def shipped_floors(path=SHIPPED):
    """The floors the package ships (``path``) when they were computed from what :func:`inputs_key` hashes now, with
    the libraries of now; else None (none shipped, torn, or made of other tasks or code: then they are computed)."""
    try:
        stored = json.loads(Path(path).read_text())
        from .planar_scenarios import library_versions

        if stored["key"] == inputs_key() and stored["versions"] == library_versions():
            return {sid: Floor(*row) for sid, row in stored["floors"].items()}
    except (OSError, ValueError, TypeError, KeyError):
        pass
    return None


def write_shipped(path=SHIPPED):
    """Compute the floors and write them as the package ships them (``python -m crane_fmu.analysis.floor``)."""
    from .planar_scenarios import library_versions

    floors = {sid: list(f) for sid, f in scenario_floors().items()}
    text = json.dumps({"key": inputs_key(), "versions": library_versions(), "floors": floors}, indent=1)
    Path(path).write_text(text + "\n")
    return path


def stored_scenario_floors(folder=None, shipped=SHIPPED):
    """:func:`scenario_floors`: those the package ships (``shipped``: :func:`shipped_floors`) when they are of the
    code and tasks of now, else kept on disk (``folder``, default the temporary folder's ``crane_fmu_floors``)
    under :func:`code_key`: the linear programs (about 7 CPU-s) run once per machine and version of the code, not on
    every board."""
    floors = shipped_floors(shipped) if shipped else None
    if floors is not None:
        return floors
    path = Path(folder or Path(tempfile.gettempdir()) / "crane_fmu_floors") / f"{code_key()}.json"
    try:
        return {sid: Floor(*row) for sid, row in json.loads(path.read_text()).items()}
    except (OSError, ValueError, TypeError):  # none yet, or torn: computed again
        pass
    floors = scenario_floors()
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    partial.write_text(json.dumps({sid: list(floor) for sid, floor in floors.items()}))
    os.replace(partial, path)
    return floors


if __name__ == "__main__":
    print(f"wrote {write_shipped()}")
