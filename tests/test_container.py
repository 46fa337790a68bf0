"""The closed loop as one FMU (fmpy's container FMU): built, validated, simulated by fmpy, equal to our master."""

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import container_name, containers_dir, systems_dir
from crane_fmu.cli import main
from crane_fmu.container import build_container
from crane_fmu.cosim import run


@pytest.fixture(scope="module")
def paper_container(fmu_dir):
    """The paper system's container, as ``crane-fmu build`` (the session's build) writes it."""
    return containers_dir(fmu_dir) / "CranePaper.fmu"


def test_the_container_is_a_valid_fmi3_fmu_with_the_crane_interface(paper_container):
    assert validate_fmu(str(paper_container)) == []
    md = read_model_description(str(paper_container))
    assert md.fmiVersion == "3.0" and float(md.coSimulation.fixedInternalStepSize) == 1e-3
    causality = {v.name: v.causality for v in md.modelVariables}
    for name in ("m1", "m2", "l1", "l2", "x_d", "theta1_0"):
        assert causality[name] == "parameter"
    for name in ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2", "energy", "u"):
        assert causality[name] == "output"
    assert causality["F1"] == causality["F2"] == causality["hoist"] == "input"
    assert "u" not in [v.name for v in md.modelVariables if v.causality == "input"]  # fed inside


def test_section5_from_the_container_equals_our_master(paper_container, fmu_dir):
    """fmpy simulates the container; our master in Jacobi mode without the initial exchange: bit for bit."""
    result = simulate_fmu(str(paper_container), stop_time=20.0, output_interval=1e-3)
    ours = run(systems.get("paper"), fmu_dir, algorithm="jacobi", initial_exchange=False).columns()
    for name in ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"):
        assert np.abs(result[name] - ours["plant." + name]).max() <= 1e-9, name  # measured: 0.0
    # the container reports u after its exchange, our master before the next one: one step apart
    assert np.abs(result["u"][:-1] - ours["controller.u"][1:]).max() <= 1e-9
    gauss_seidel = run(systems.get("paper"), fmu_dir, stop_time=2.0).columns()
    assert np.abs(result["theta1"][:2001] - gauss_seidel["plant.theta1"]).max() > 1e-4  # a different master


def test_a_container_parameter_reaches_plant_and_controller(fmu_dir):
    container = containers_dir(fmu_dir) / "CraneLqr.fmu"
    result = simulate_fmu(str(container), stop_time=3.0, output_interval=1e-3, start_values={"l1": 1.5})
    both = systems.get("lqr").with_parameters({"plant": {"l1": 1.5}, "controller": {"l1": 1.5}})
    ours = run(both, fmu_dir, algorithm="jacobi", initial_exchange=False, stop_time=3.0).columns()
    assert np.array_equal(result["theta1"], ours["plant.theta1"])


@pytest.mark.parametrize("x_d", [None, 1.2, -0.8])  # None: the container's own x_d (the system's 2 m)
def test_the_transport_container_follows_the_move_planned_to_the_x_d_set_on_it(fmu_dir, x_d):
    """x_d set on the transport container is the planner's: the trolley follows the reference that the planner's
    model (crane_fmu.model.planner, called here, no FMU and no master) plans from 0 to that x_d, within 2 % of the
    move all along (the LQR tracks it with the feedforward). An x_d that reached the controller instead leaves the
    planner at its own start (no move planned) and makes the LQR jump to x_d: it ends there too, so the end cannot
    tell (test_wiring.py's end-position test), the path can (12-24 % of the move off the plan)."""
    from crane_fmu import components
    from crane_fmu.model import planner

    system = systems.get("transport")
    target = system.parameters["planner"]["x_d"] if x_d is None else x_d
    result = simulate_fmu(str(containers_dir(fmu_dir) / "CraneTransport.fmu"), stop_time=5.0, output_interval=0.01,
                          start_values={} if x_d is None else {"x_d": x_d}, output=["x"])
    model = components.get("TrajectoryPlanner")
    values = {v.name: v.start for v in model.variables if v.causality == "parameter"}
    plan = model.configure({**values, **system.parameters["planner"], "x_d": target})
    assert plan.end < 4.0  # the move is over before the run ends
    x_ref = np.array([planner.reference(plan, t)[0] for t in result["time"]])
    assert x_ref[-1] == pytest.approx(target, abs=1e-12)
    assert np.abs(result["x"] - x_ref).max() <= 0.02 * abs(target)


def test_build_container_command(fmu_dir, tmp_path, capsys):
    out = tmp_path / "build" / "fmus"
    out.parent.mkdir()
    out.symlink_to(fmu_dir)
    assert main(["build", "--out", str(out), "--container", "transport"]) == 0
    assert (tmp_path / "build" / "containers" / "CraneTransport.fmu").is_file()
    assert main(["build", "--out", str(out), "--container", "nowhere"]) == 2
    assert "no system 'nowhere'" in capsys.readouterr().err


def test_setting_every_parameter_to_its_start_value_changes_nothing(fmu_dir, tmp_path):
    """What many tools do (Simulink sets every parameter): the container's run must be the system's own. With
    the plant's l1 at 1.2 m and the LQR's at its 1 m, the shared l1 (start 1.2) goes to the plant only, as in the
    one-FMU (closed_loop.py): set on both, it would redesign the LQR."""
    system = systems.get("lqr").with_parameters({"plant": {"l1": 1.2}})
    container = build_container(system, fmu_dir, tmp_path / "CraneLqr.fmu")
    starts = {v.name: float(v.start) for v in read_model_description(str(container)).modelVariables
              if v.causality == "parameter"}
    assert starts["l1"] == 1.2
    result = simulate_fmu(str(container), stop_time=3.0, output_interval=1e-3, start_values=starts)
    ours = run(system, fmu_dir, algorithm="jacobi", initial_exchange=False, stop_time=3.0).columns()
    for name in ("x", "theta1"):
        assert np.array_equal(result[name], ours["plant." + name]), name


def test_a_system_with_values_the_container_cannot_set_is_refused(fmu_dir, tmp_path):
    """hoist-transport's planners have values of their own (the hoist's move, the shaper): fmpy's container could
    not set them and would run another system."""
    with pytest.raises(ValueError, match="hoist.x0") as refused:
        build_container(systems.get("hoist-transport"), fmu_dir, tmp_path / "CraneHoistTransport.fmu")
    assert "\n" not in str(refused.value) and not (tmp_path / "CraneHoistTransport.fmu").exists()


@pytest.mark.parametrize("name", ["lqr", "paper", "energy", "transport"])  # the systems `crane-fmu build` packs
def test_the_projects_own_ssp_file_packs_as_the_system_it_was_written_from(fmu_dir, tmp_path, capsys, name):
    """`build --container build/systems/lqr.ssp`: the file holds every parameter's value, also those equal to the
    FMUs' own start values, which need no setting (transport's LQR keeps its own x_d = 0 beside the planner's
    references: the container's x_d is the planner's alone). Its container is the system's (`build --container
    lqr`): the same variables and start values, the same run bit for bit, which is our Jacobi master's without the
    initial exchange."""
    assert main(["build", "--container", str(systems_dir(fmu_dir) / f"{name}.ssp"), "--out",
                 str(tmp_path / "fmus")]) == 0
    packed = tmp_path / "containers" / f"{container_name(name)}.fmu"
    assert capsys.readouterr().out.splitlines() == [str(packed)]
    built_in = containers_dir(fmu_dir) / f"{container_name(name)}.fmu"

    def interface(path):
        return [(v.name, v.causality, v.start) for v in read_model_description(str(path)).modelVariables]

    assert interface(packed) == interface(built_in)
    theirs = simulate_fmu(str(packed), stop_time=3.0, output_interval=1e-3)
    ours = simulate_fmu(str(built_in), stop_time=3.0, output_interval=1e-3)
    assert theirs.dtype.names == ours.dtype.names
    for column in ours.dtype.names:
        assert np.array_equal(theirs[column], ours[column]), column
    master = run(systems.get(name), fmu_dir, algorithm="jacobi", initial_exchange=False, stop_time=3.0).columns()
    for column in ("x", "theta1", "theta2"):
        assert np.array_equal(theirs[column], master["plant." + column]), column


@pytest.mark.parametrize("system, instance, name, value, packs", [
    ("transport", "planner", "shaper", 2, True),  # the FMU's start item (zv) by its value, as an SSP file holds it
    ("transport", "planner", "shaper", "zv", True),  # by its name (SSP 1.0's ssv:Enumeration)
    ("transport", "planner", "shaper", 3, False),  # zvd
    ("paper", "controller", "b3_form", "derived", True),  # a String at the FMU's start value
    ("paper", "controller", "b3_form", "printed", False),
    ("lqr", "controller", "q_x", 50.0, True),  # a Real at it: the SSP file's case
    ("lqr", "controller", "q_x", 50.000000001, False),
])
def test_a_value_the_container_does_not_expose_must_be_the_fmus_start_value(fmu_dir, tmp_path, system, instance,
                                                                            name, value, packs):
    """A value equal to the FMU's start value, compared as the FMU's model description gives it (an Enumeration
    by its item, a String as text, a number exactly), needs no setting; any other is refused in one line naming
    it, and no container is written."""
    given = systems.get(system).with_parameters({instance: {name: value}})
    path = tmp_path / "X.fmu"
    if packs:
        assert build_container(given, fmu_dir, path) == path and path.is_file()
        return
    with pytest.raises(ValueError, match="exposes, not ") as refused:
        build_container(given, fmu_dir, path)
    assert f"not {instance}.{name}; build it" in str(refused.value) and "\n" not in str(refused.value)
    assert not path.exists()


def test_a_system_without_a_controller_packs_with_the_plants_demand_as_an_input(fmu_dir, tmp_path):
    """The free swing: nothing inside feeds the plant's u, so the container takes it as an input (a KeyError
    before); it runs as our Jacobi master."""
    container = build_container(systems.get("free"), fmu_dir, tmp_path / "CraneFree.fmu")
    assert {v.name: v.causality for v in read_model_description(str(container)).modelVariables}["u"] == "input"
    result = simulate_fmu(str(container), stop_time=3.0, output_interval=1e-3)
    ours = run(systems.get("free"), fmu_dir, algorithm="jacobi", initial_exchange=False, stop_time=3.0).columns()
    for name in ("x", "theta1", "theta2"):
        assert np.array_equal(result[name], ours["plant." + name]), name
