"""The commands on the crane in three dimensions, by its roles: a sweep of ``open-loop-3d`` (Python and native FMUs,
on Dask) with the metrics named after its swing angles, each figure against a run of our master measured here;
a metric of another plant refused; ``linearize --loop`` on a plant of two axes refused in one line."""

import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from crane_fmu import components, systems
from crane_fmu.cli import main
from crane_fmu.cosim import run
from crane_fmu.sweep import spec
from crane_fmu.sweep.runner import run_study

ROOT = Path(__file__).resolve().parent.parent

SPATIAL = components.get("CranePlant3D").crane
TARGETS = [1.0, 2.0]  # planner_x.x_d of the sweep's cases


@pytest.mark.quick
def test_the_metrics_are_named_after_each_plants_swing_angles():
    assert spec.metric_names(components.get("CranePlant").crane) == spec.METRICS
    names = spec.metric_names(SPATIAL)
    assert [n for n in names if n not in spec.METRICS] == ["max_swing1_deg", "max_swing2_deg", "rms_swing1_deg"]
    study = spec.parse({"system": "open-loop-3d", "stop_time": 1.0, "step": 1e-3, "metrics": ["max_theta1_deg"]})
    with pytest.raises(ValueError, match=r"^metrics: max_theta1_deg is no metric of system open-loop-3d's plant; "
                                         r"its metrics: outcome, .*max_swing1_deg"):
        study.metrics_of(SPATIAL, "system open-loop-3d")
    with pytest.raises(ValueError, match="unknown metric 'max_swing3_deg'"):
        spec.parse({"stop_time": 1.0, "step": 1e-3, "metrics": ["max_swing3_deg"]})


@pytest.mark.quick
def test_each_axis_move_target_is_its_own_planners():
    """open-loop-3d: planner_y plans along its own x (its x_d) and drives uy, so y's target is planner_y's x_d;
    the planar systems keep theirs (the planner's, the controller's, none: 0)."""
    from crane_fmu.closed_loop import axis_planners

    system = systems.get("open-loop-3d")
    assert axis_planners(SPATIAL, systems.kinds(system), system.connections) == {"x": "planner_x", "y": "planner_y"}
    assert systems.move_target(system) == {"x": 2.0, "y": 1.5}
    assert systems.move_target(system.with_parameters({"planner_y": {"x_d": -0.7}})) == {"x": 2.0, "y": -0.7}
    planar = ("transport", "hoist-transport", "mpc-transport", "lqr")
    assert [systems.move_target(systems.get(name)) for name in planar] == [{"x": 2.0}] * 3 + [{"x": 0.0}]


@pytest.mark.quick
def test_a_planner_of_the_cable_plans_no_axis():
    """S7's MPC plans its own move while a planner hoists (hoist.ddx_ref to plant.hoist): the move's target is the
    controller's x_d (2 m), not the hoist's (1 m), which made `crane-fmu targets` print S7's arrival as never."""
    from crane_fmu.analysis import scenarios

    mpc = components.get("MpcController")
    contender = scenarios.Contender("MpcController", "MpcController", list(mpc.names("input")),
                                    list(mpc.names("parameter")))
    (_, system, *_), = scenarios.systems_for(contender, "S7", 1)
    assert "hoist" in systems.kinds(system) and systems.move_target(system) == {"x": 2.0}


@pytest.mark.parametrize("kind", ["python", "native"])
def test_a_sweep_of_the_spatial_crane_gives_its_swing_angles_figures(fmu_dir, native, dask_scheduler, tmp_path,
                                                                     kind):
    """Every metric of the plant (no metrics given): each case's largest swing of each cable, the RMS of the hook
    cable's and the trolley's last x (the case's target), as our master's run of that case gives them."""
    folder = fmu_dir if kind == "python" else native[2]
    study = spec.parse({"system": "open-loop-3d", "stop_time": 6.0, "step": 1e-3,
                        "parameters": {"planner_x.x_d": TARGETS}})
    summary = run_study(study, tmp_path / "out", folder, scheduler=dask_scheduler, progress=False)
    assert summary["ran"] == summary["cases"] == 2 and summary["not_ok"] == 0
    rows = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    assert set(spec.metric_names(SPATIAL)) <= set(rows[0])
    for row, target in zip(rows, TARGETS):
        system = systems.bind(systems.get("open-loop-3d")).with_parameters({"planner_x": {"x_d": target}})
        c = run(system, folder, stop_time=6.0).columns()
        for name in ("swing1", "swing2"):
            assert row[f"max_{name}_deg"] == pytest.approx(math.degrees(np.abs(c[f"plant.{name}"]).max()), rel=1e-12)
        assert row["rms_swing1_deg"] == pytest.approx(math.degrees(np.sqrt(np.mean(c["plant.swing1"] ** 2))),
                                                      rel=1e-12)
        assert row["trolley_final_m"] == pytest.approx(target, abs=1e-9) and row["max_swing1_deg"] > 5.0


def test_a_sweep_that_names_another_plants_metric_is_refused_in_one_line(fmu_dir, tmp_path, capsys):
    (tmp_path / "study.toml").write_text('system = "open-loop-3d"\nstop_time = 1.0\nstep = 0.001\n'
                                         'metrics = ["outcome", "max_theta1_deg"]\n'
                                         '[parameters]\n"planner_y.x_d" = [1.0, 1.5]\n')
    assert main(["sweep", str(tmp_path / "study.toml"), "--fmu-dir", str(fmu_dir), "--out",
                 str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "metrics: max_theta1_deg is no metric of system open-loop-3d's plant; its metrics: " in err
    assert not (tmp_path / "out").exists()


def test_the_loop_analysis_of_a_plant_of_two_axes_is_refused_in_one_line(fmu_dir, capsys):
    assert main(["linearize", "--loop", "--system", "open-loop-3d", "--fmu-dir", str(fmu_dir)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "CranePlant3D has the demands ux, uy: the loop analysis takes one" in err
    page = " ".join((ROOT / "docs" / "guide" / "interoperability.md").read_text().split())
    assert err.strip().removeprefix("crane-fmu: error: ") in page  # the page says so (it did not)
