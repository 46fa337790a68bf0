"""The ``open-loop-3d`` system by behaviour: a ZV-shaped planner per axis moves the crane in three dimensions, open
loop, and the trolley ends at each axis's target, as the system (Python FMUs), as its SSP file and as its one native
FMU (``CraneOpenLoop3d``: ``x_d`` and ``y_d`` as parameters), at the system's targets (2 m, 1.5 m) and at changed
ones; a target that reached the other axis's planner leaves the trolley elsewhere. The shaping leaves the load
within the arrival's 0.5 deg of the vertical after the planned move, where the unshaped move swings by more than
5 deg (the nonlinear coupling of the axes is what the per-axis ZV design does not know: about 0.1 deg is left)."""

import math

import numpy as np
import pytest
from fmpy import simulate_fmu
from helpers import one_fmu

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import systems_dir
from crane_fmu.cli import main
from crane_fmu.cosim import ArrayRecorder, read_csv, run

NAME = "open-loop-3d"
POSITION = 0.005  # m: the arrival band
TARGETS = [None, (1.2, -0.8)]  # None: the system's own (2 m, 1.5 m)


def _targets(targets):
    return (2.0, 1.5) if targets is None else targets


def _check_end(x, dx, y, dy, targets):
    for name, position, speed, target in (("x", x, dx, targets[0]), ("y", y, dy, targets[1])):
        assert abs(position[-1] - target) <= POSITION, f"{name} ended at {position[-1]:.6g} m, not at {target} m"
        assert abs(speed[-1]) <= 0.01, f"the trolley still moves along {name} at {speed[-1]:.3g} m/s"


@pytest.mark.parametrize("targets", TARGETS)
def test_the_system_ends_at_each_axis_target(fmu_dir, targets):
    system = systems.get(NAME)
    if targets is not None:
        system = system.with_parameters({"planner_x": {"x_d": targets[0]}, "planner_y": {"x_d": targets[1]}})
    c = run(systems.bind(system), fmu_dir, recorder=ArrayRecorder()).columns()
    _check_end(c["plant.x"], c["plant.dx"], c["plant.y"], c["plant.dy"], _targets(targets))


@pytest.mark.parametrize("targets", TARGETS)
def test_its_ssp_file_ends_at_each_axis_target(fmu_dir, targets, tmp_path, capsys):
    ssp = systems_dir(fmu_dir) / f"{NAME}.ssp"
    extra = [] if targets is None else ["--set", f"planner_x.x_d={targets[0]!r}", "--set",
                                        f"planner_y.x_d={targets[1]!r}"]
    assert main(["simulate", "--system", str(ssp), "--out", str(tmp_path / "run.csv"), *extra]) == 0, \
        capsys.readouterr().err
    c = read_csv(tmp_path / "run.csv")
    _check_end(c["plant.x"], c["plant.dx"], c["plant.y"], c["plant.dy"], _targets(targets))


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("targets", TARGETS)
def test_the_one_fmu_ends_at_its_parameters_x_d_and_y_d(native, targets, version):
    start = {} if targets is None else {"x_d": targets[0], "y_d": targets[1]}
    result = simulate_fmu(str(one_fmu(native, NAME, version)), stop_time=systems.get(NAME).stop_time,
                          output_interval=0.01, start_values=start, output=["x", "dx", "y", "dy"])
    _check_end(result["x"], result["dx"], result["y"], result["dy"], _targets(targets))


def test_the_zv_shaping_leaves_the_load_within_the_arrival_band(fmu_dir):
    """After the planned move (the later axis's end, +0.5 s), both cables within 0.5 deg of the vertical in space;
    unshaped (shaper none on both planners), more than 5 deg."""
    late = {}
    for shaper in ("zv", "none"):
        system = systems.get(NAME).with_parameters({"planner_x": {"shaper": shaper}, "planner_y": {"shaper": shaper}})
        c = run(systems.bind(system), fmu_dir, recorder=ArrayRecorder()).columns()
        moving = (c["planner_x.ddx_ref"] != 0) | (c["planner_y.ddx_ref"] != 0)  # the planned accelerations
        after = c["time"] > c["time"][np.nonzero(moving)[0][-1]] + 0.5
        late[shaper] = max(math.degrees(np.abs(c[f"plant.{n}"][after]).max()) for n in ("swing1", "swing2"))
    assert late["zv"] < 0.5 < 5.0 < late["none"], late
