"""``crane-fmu bench --spatial``: the crane in three dimensions against the planar crane, per communication step.

Medians of ``repeat`` alternating runs, 20 s at h = 1 ms by default, every step recorded to CSV by our master:

1. the planar pair: CranePlant with the LqrController (the ``lqr`` system: regulation from theta1 = 10 deg);
2. the spatial pair: CranePlant3D with the same LqrController on its x axis (x, dx, theta1x, ... to the LQR, its
   u to ux) and a swing out of the plane besides (theta1y = 5 deg, the y axis free): every step takes the
   spatial equations. No controller for two axes exists yet; one FMU per axis would add an FMU call per step;

each as Python FMUs and as native FMUs, and the two plants' steps in process (the Python models' ``update``,
no FMI), to tell the equations' cost from the FMI calls'. The issue's target: the spatial pair at most twice
the planar pair's cost (Python and native).
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


def _in_process(name, values, inputs, n, step):
    """Seconds per step of a plant's Python ``update`` alone, ``n`` steps with ``inputs`` held."""
    component = components.get(name)
    config = component.check(values)
    state = component.initial_state(config)
    start = time.perf_counter()
    for k in range(n):
        state = component.update(config, state, inputs, k * step, step)
    return (time.perf_counter() - start) / n


def run_spatial_bench(stop_time=20.0, step=1e-3, repeat=5, out=print):
    """Run the benchmark, print its figures and return them."""
    n = communication_points(0.0, stop_time, step)
    planar = systems.prepare(systems.get("lqr"), step, stop_time)
    spatial = spatial_pair(step, stop_time)
    with tempfile.TemporaryDirectory(prefix="crane_bench_spatial_") as tmp:
        tmp = Path(tmp)
        built = tmp / "fmus"
        kinds = [PLANAR, SPATIAL, "LqrController"]
        build_all(built, kinds, systems=(), fmi3=False, native=False, log=lambda _: None)
        native = native_dir(built)
        for name in kinds:  # FMI 2.0, the Linux binary: all the benchmark runs
            build_native_fmu(components.get(name), native, 2, {"linux": compilers()["linux"]})
        runs = {"planar_python": (planar, built), "spatial_python": (spatial, built),
                "planar_native": (planar, native), "spatial_native": (spatial, native)}
        times = {name: [] for name in [*runs, "planar_model", "spatial_model"]}
        for _ in range(repeat):  # alternate, so drifts in machine load hit all
            for name, (system, folder) in runs.items():
                times[name].append(_timed_run(system, folder, tmp / f"{name}.csv")[0] / n)
            times["planar_model"].append(_in_process(PLANAR, {}, (0.5, 0.0, 0.0, 0.0), n, step))
            times["spatial_model"].append(_in_process(SPATIAL, SPATIAL_START, (0.5, 0.0) + (0.0,) * 5, n, step))
    us = {name: 1e6 * statistics.median(t) for name, t in times.items()}
    figures = {"steps": n, **{f"{name}_us": value for name, value in us.items()},
               "python_ratio": us["spatial_python"] / us["planar_python"],
               "native_ratio": us["spatial_native"] / us["planar_native"],
               "model_ratio": us["spatial_model"] / us["planar_model"]}
    out(f"{n} steps of h = {step:g} s, medians of {repeat} alternating runs, our master, CSV of every step")
    out(f"1. planar pair (CranePlant + LqrController), Python FMUs:     {us['planar_python']:7.2f} us/step")
    out(f"2. spatial pair (CranePlant3D + LqrController), Python FMUs:  {us['spatial_python']:7.2f} us/step, "
        f"ratio {figures['python_ratio']:.2f}  (target <= 2.0)")
    out(f"3. planar pair, native FMUs:                                  {us['planar_native']:7.2f} us/step")
    out(f"4. spatial pair, native FMUs:                                 {us['spatial_native']:7.2f} us/step, "
        f"ratio {figures['native_ratio']:.2f}  (target <= 2.0)")
    out(f"5. the plants' steps in process (Python update, no FMI): planar {us['planar_model']:.2f} us, spatial "
        f"{us['spatial_model']:.2f} us, ratio {figures['model_ratio']:.2f}")
    return figures
