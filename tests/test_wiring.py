"""Every built-in move's wiring, by behaviour rather than by names: the trolley ends at x_d, and at a changed x_d.

The systems ``transport`` and ``hoist-transport`` (x_d is the planner's), ``lqr`` (x_d is the controller's:
regulation from 10 deg), their SSP files and the transport and LQR container FMUs each run to the end, with
x_d as built (2 m for the moves, 0 for the regulation) and changed (1.2 m, and -0.8 m: a move the other
way). A connection or parameter mapping to the wrong instance leaves the trolley elsewhere: the container
mapping x_d to the controller, say, leaves the planner's reference at its own x_d.

Tolerance: 5 mm, the position band of an arrival (crane_fmu.analysis.metrics.move_metrics); both moves
arrive within it seconds before their runs end (the transport targets arrival by 3.8 s of a 10 s run).
"""

import numpy as np
import pytest
from fmpy import simulate_fmu

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import container_name, containers_dir, systems_dir
from crane_fmu.cli import main
from crane_fmu.cosim import ArrayRecorder, read_csv, run
from crane_fmu.cosim.ssp import write_ssp

POSITION = 0.005  # m: the arrival band
TARGETS = [None, 1.2, -0.8]  # None: the system's own x_d
HOLDER = {"transport": "planner", "hoist-transport": "planner", "lqr": "controller"}  # whose x_d it is


def _target(name, x_d):
    return systems.get(name).parameters.get(HOLDER[name], {}).get("x_d", 0.0) if x_d is None else x_d


def _check_end(x, dx, target):
    assert abs(x[-1] - target) <= POSITION, f"the trolley ended at x = {x[-1]:.6g} m, not at x_d = {target} m"
    assert abs(dx[-1]) <= 0.01, f"the trolley still moves at {dx[-1]:.3g} m/s"  # 1 cm/s, far below the 1 m/s


@pytest.mark.parametrize("x_d", TARGETS)
@pytest.mark.parametrize("name", list(HOLDER))
def test_a_built_in_move_ends_at_x_d(fmu_dir, name, x_d):
    system = systems.get(name)
    target = _target(name, x_d)
    if x_d is not None:
        system = system.with_parameters({HOLDER[name]: {"x_d": x_d}})
    c = run(systems.bind(system), fmu_dir, recorder=ArrayRecorder()).columns()
    _check_end(c["plant.x"], c["plant.dx"], target)
    if name == "hoist-transport":  # the hoist's planner drives the cable from 2 m to its x_d = 1 m
        hoist = system.parameters["hoist"]["x_d"]
        assert abs(c["plant.l1_now"][-1] - hoist) <= 1e-3, c["plant.l1_now"][-1]


@pytest.mark.parametrize("x_d", TARGETS)
@pytest.mark.parametrize("name", list(HOLDER))
def test_the_system_files_of_the_moves_end_at_x_d(fmu_dir, name, x_d, tmp_path, capsys):
    """The SSP file `crane-fmu build` writes for the system, run by `crane-fmu simulate --system FILE.ssp`."""
    system = systems.get(name)
    ssp = write_ssp(system, fmu_dir, systems_dir(tmp_path / "fmus") / f"{name}.ssp")
    extra = [] if x_d is None else ["--set", f"{HOLDER[name]}.x_d={x_d!r}"]
    assert main(["simulate", "--system", str(ssp), "--out", str(tmp_path / "run.csv"), *extra]) == 0, \
        capsys.readouterr().err
    c = read_csv(tmp_path / "run.csv")
    _check_end(c["plant.x"], c["plant.dx"], _target(name, x_d))


@pytest.fixture(scope="module")
def containers(fmu_dir):
    """The container FMUs of ``crane-fmu build`` (the session's build)."""
    return {name: containers_dir(fmu_dir) / f"{container_name(name)}.fmu" for name in ("transport", "lqr")}


@pytest.mark.parametrize("x_d", TARGETS)
@pytest.mark.parametrize("name", ["transport", "lqr"])
def test_the_containers_end_at_x_d(containers, name, x_d):
    """fmpy simulates the one-FMU closed loop; its parameter x_d must reach the planner (transport), or the
    controller where there is no planner (lqr)."""
    start = {} if x_d is None else {"x_d": x_d}
    result = simulate_fmu(str(containers[name]), stop_time=systems.get(name).stop_time, output_interval=0.01,
                          start_values=start, output=["x", "dx"])
    _check_end(result["x"], result["dx"], _target(name, x_d))


@pytest.mark.parametrize("x_d", TARGETS)
@pytest.mark.parametrize("name", ["transport", "lqr"])
def test_the_containers_run_is_our_masters_with_x_d_set_on_its_holder(containers, fmu_dir, name, x_d):
    """The container with x_d set is our master (Jacobi without the initial exchange, as the container steps:
    test_container.py) with x_d set on the instance that holds it (HOLDER, written here, not read from the
    container): the whole run to 1e-9, so an x_d that reaches another instance shows, even where the loop ends
    at the same place (the LQR regulates to its own x_d)."""
    system = systems.get(name)
    start = {} if x_d is None else {"x_d": x_d}
    if x_d is not None:
        system = system.with_parameters({HOLDER[name]: {"x_d": x_d}})
    step, stop_time = system.step, 5.0  # the move and the regulation are under way
    result = simulate_fmu(str(containers[name]), stop_time=stop_time, step_size=step, output_interval=step,
                          start_values=start, output=["x", "theta1"])
    ours = run(system, fmu_dir, algorithm="jacobi", initial_exchange=False, stop_time=stop_time).columns()
    for signal in ("x", "theta1"):
        assert np.abs(result[signal] - ours["plant." + signal]).max() <= 1e-9, signal
    assert np.abs(ours["plant.x"]).max() > 0.05  # the trolley moved: x_d acted
