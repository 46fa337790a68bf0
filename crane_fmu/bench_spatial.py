"""``crane-fmu bench --spatial``: the crane in three dimensions against the planar crane, per communication step.

Medians of ``repeat`` alternating runs, 20 s at h = 1 ms by default, every step recorded to CSV by our master, each
spatial figure against its planar counterpart of the same run:

1. the LQR pair: the planar CranePlant with the LqrController (the ``lqr`` system: regulation from theta1 = 10 deg)
   against CranePlant3D with the same LqrController on its x axis (x, dx, theta1x, ... to the LQR, its u to ux) and
   a swing out of the plane besides (theta1y = 5 deg, the y axis free): every step takes the spatial equations;
2. the planned pair, no LQR: CranePlant with a TrajectoryPlanner whose ``ddx_ref`` drives ``u`` (a 2 m ZV-shaped
   move, open loop) against CranePlant3D with the same planner driving ``ux``, the same swing out of the plane;
3. the open loop of two axes, no LQR: the ``open-loop-3d`` system (a planner per axis, three FMUs) against the
   planar planned pair of 2.;

each as Python FMUs and as native FMUs, and the two plants' steps in process (the Python models' ``update``,
no FMI), to tell the equations' cost from the FMI calls'. The issue's target: a spatial pair at most twice the
planar pair's cost (Python and native).
"""

import statistics
import tempfile
import time
from pathlib import Path

from crane_fmu import components, systems
from crane_fmu.bench import _timed_run
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.build_scripts.native import build_native_fmu, compilers, native_dir
from crane_fmu.cosim import Connection, System
from crane_fmu.cosim.master import communication_points

PLANAR, SPATIAL = "CranePlant", "CranePlant3D"
TO_THE_LQR = {"x": "x", "dx": "dx", "theta1x": "theta1", "dtheta1x": "dtheta1", "theta2x": "theta2",
              "dtheta2x": "dtheta2"}
SPATIAL_START = {"theta1y_0": 0.08726646259971647}  # 5 deg out of the plane (theta1x_0: 10 deg, the default)


def spatial_pair(step, stop_time):
    """The spatial pair: CranePlant3D with the LqrController on its x axis (``l1_now`` by name)."""
    connections = tuple(Connection("plant", ours, "controller", theirs) for ours, theirs in TO_THE_LQR.items()) + (
        Connection("controller", "u", "plant", "ux"),)
    system = System("spatial-lqr", {"plant": SPATIAL, "controller": "LqrController"}, connections,
                    parameters={"plant": dict(SPATIAL_START)}, stop_time=stop_time, step=step)
    return systems.prepare(system, step, stop_time)


def planned_pair(plant, step, stop_time):
    """A plant moved open loop by a TrajectoryPlanner (2 m, ZV-shaped) along x: its ``ddx_ref`` to the plant's first
    axis's demand; the spatial plant with its swing out of the plane."""
    demand = components.get(plant).crane.axes[0].demand
    system = System(f"planned-{plant}", {"plant": plant, "planner": "TrajectoryPlanner"},
                    (Connection("planner", "ddx_ref", "plant", demand),),
                    parameters={"plant": dict(SPATIAL_START) if plant == SPATIAL else {}, "planner": {"x_d": 2.0}},
                    stop_time=stop_time, step=step)
    return systems.prepare(system, step, stop_time)


def _in_process(name, values, inputs, n, step):
    """Seconds per step of a plant's Python ``update`` alone, ``n`` steps with ``inputs`` held."""
    component = components.get(name)
    config = component.check(values)
    state = component.initial_state(config)
    start = time.perf_counter()
    for k in range(n):
        state = component.update(config, state, inputs, k * step, step)
    return (time.perf_counter() - start) / n


PAIRS = (("lqr", "1. LQR pair, the LqrController on x"),
         ("planned", "2. planned pair, a TrajectoryPlanner on x, no LQR"),
         ("open_loop", "3. open-loop-3d (2 planners) vs planar pair 2., no LQR"))


def run_spatial_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the benchmark, print its figures and return them."""
    n = communication_points(0.0, stop_time, step)
    cases = {"lqr": (systems.prepare(systems.get("lqr"), step, stop_time), spatial_pair(step, stop_time)),
             "planned": (planned_pair(PLANAR, step, stop_time), planned_pair(SPATIAL, step, stop_time)),
             "open_loop": (None, systems.prepare(systems.get("open-loop-3d"), step, stop_time))}
    with tempfile.TemporaryDirectory(prefix="crane_bench_spatial_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        kinds = [PLANAR, SPATIAL, "LqrController", "TrajectoryPlanner"]
        build_all(built, kinds, systems=(), fmi3=False, native=False, log=lambda _: None)
        native = native_dir(built)
        for name in kinds:  # FMI 2.0, the Linux binary: all the benchmark runs
            build_native_fmu(components.get(name), native, 2, {"linux": compilers()["linux"]})
        runs = {f"{case}_{side}_{kind}": (system, folder) for case, pair in cases.items()
                for side, system in zip(("planar", "spatial"), pair) if system is not None
                for kind, folder in (("python", built), ("native", native))}
        times = {name: [] for name in [*runs, "planar_model", "spatial_model"]}
        for _ in range(repeat):  # alternate, so drifts in machine load hit all
            for name, (system, folder) in runs.items():
                times[name].append(_timed_run(system, folder, tmp / f"{name}.csv")[0] / n)
            times["planar_model"].append(_in_process(PLANAR, {}, (0.5, 0.0, 0.0, 0.0), n, step))
            times["spatial_model"].append(_in_process(SPATIAL, SPATIAL_START, (0.5, 0.0) + (0.0,) * 5, n, step))
    us = {name: 1e6 * statistics.median(t) for name, t in times.items()}
    us.update({f"open_loop_planar_{kind}": us[f"planned_planar_{kind}"] for kind in ("python", "native")})
    figures = {"steps": n, **{f"{name}_us": value for name, value in us.items()},
               "model_ratio": us["spatial_model"] / us["planar_model"]}
    for case, _ in PAIRS:
        for kind in ("python", "native"):
            figures[f"{case}_{kind}_ratio"] = us[f"{case}_spatial_{kind}"] / us[f"{case}_planar_{kind}"]
    figures["python_ratio"], figures["native_ratio"] = figures["lqr_python_ratio"], figures["lqr_native_ratio"]
    out(f"{n} steps of h = {step:g} s, medians of {repeat} alternating runs, our master, CSV of every step; us per "
        "step, spatial vs planar (target: ratio <= 2.0)")
    for case, text in PAIRS:
        cells = [f"{kind} {us[f'{case}_spatial_{kind}']:6.2f} vs {us[f'{case}_planar_{kind}']:6.2f} = "
                 f"{figures[f'{case}_{kind}_ratio']:.2f}x" for kind in ("python", "native")]
        out(f"{text:55s} {cells[0]:28s} {cells[1]}")
    out(f"the plants' steps in process (Python update, no FMI): planar {us['planar_model']:.2f} us, spatial "
        f"{us['spatial_model']:.2f} us, ratio {figures['model_ratio']:.2f}")
    return figures
