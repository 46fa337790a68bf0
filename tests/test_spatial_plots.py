"""The pictures of the crane in three dimensions (crane_fmu/analysis/spatial_plots.py, ``crane-fmu plot --view top |
swing``, ``crane-fmu animate``), on real runs of the ``open-loop-3d`` system (its Python FMUs) and of the planar
``lqr`` system; the corridor's distances against a brute-force sampling of the centre line."""

import math

import numpy as np
import pytest
from PIL import Image

from crane_fmu.analysis.metrics import find_crane
from crane_fmu.analysis.score_plots import _animated
from crane_fmu.analysis.spatial_plots import distance_to_path, parse_corridor, plot_swing, plot_top
from crane_fmu.cli import main
from crane_fmu.cosim import read_result

L_PATH = [(0.0, 0.0), (3.0, 0.0), (3.0, 2.0)]  # S13's L: 3 m along x, then 2 m along y


def _brute_force(points, px, py, n=20001):
    """The distance to the polyline sampled every 1/n of each segment: within 2e-4 m of the exact one here."""
    samples = np.concatenate([np.linspace(a, b, n) for a, b in zip(np.array(points[:-1]), np.array(points[1:]))])
    return np.array([np.hypot(samples[:, 0] - x, samples[:, 1] - y).min() for x, y in zip(px, py)])


@pytest.mark.quick
def test_the_distance_to_the_centre_line_has_its_known_answers():
    px = np.array([1.0, -1.0, 4.0, 3.5, 2.0, 3.0, 2.5])
    py = np.array([0.2, 0.0, 3.0, 1.0, 1.0, -0.4, 0.5])
    # beside the first leg; before its start; past the end (a corner's distance); beside the second leg; inside the
    # L's corner (nearer the second leg); below the corner; inside, equally near both legs
    exact = [0.2, 1.0, math.hypot(1.0, 1.0), 0.5, 1.0, 0.4, 0.5]
    assert distance_to_path(L_PATH, px, py) == pytest.approx(exact, abs=1e-15)
    rng = np.random.default_rng(5)
    x, y = rng.uniform(-1, 4, 200), rng.uniform(-1, 3, 200)
    assert np.abs(distance_to_path(L_PATH, x, y) - _brute_force(L_PATH, x, y)).max() < 2e-4


@pytest.mark.quick
@pytest.mark.parametrize("text, width, message", [
    ("0,0,3", 0.6, "at least two points X0,Y0,X1,Y1 of finite numbers, in pairs"),
    ("0,0", 0.6, "at least two points"),
    ("0,0,3,nan", 0.6, "of finite numbers"),
    ("0,0,a,1", 0.6, "numbers X0,Y0,X1,Y1,... [m] separated by commas"),
    ("0,0,3,0", 0.0, "--corridor-width must be > 0 and finite with --corridor, got 0.0"),
    ("0,0,3,0", None, "--corridor needs --corridor-width W: the corridor's width [m], > 0"),  # was "got None"
])
def test_a_bad_corridor_is_refused_in_one_line_naming_it(text, width, message):
    with pytest.raises(ValueError, match=".*" + message.replace("[", r"\[").replace("]", r"\]").replace(".", r"\.")):
        parse_corridor(text, width)
    assert parse_corridor("0,0,3,0,3,2", 0.6) == L_PATH


@pytest.fixture(scope="module")
def runs(fmu_dir, tmp_path_factory):
    """``crane-fmu simulate`` of open-loop-3d (ZV-shaped), of it unshaped, and of lqr (planar): their CSV files."""
    folder = tmp_path_factory.mktemp("spatial_runs")
    made = {}
    for label, args in (("shaped", ["--system", "open-loop-3d"]),
                        ("unshaped", ["--system", "open-loop-3d", "--set", "planner_x.shaper=none", "--set",
                                      "planner_y.shaper=none"]),
                        ("planar", ["--system", "lqr", "--stop-time", "2"])):
        made[label] = folder / f"{label}.csv"
        assert main(["simulate", "--fmu-dir", str(fmu_dir), *args, "--out", str(made[label])]) == 0
    return made


def _cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_the_top_view_gives_the_loads_largest_distance_from_the_corridor(runs, tmp_path, capsys):
    """The diagonal move's centre line (0,0)-(2,1.5): the shaped move keeps its load nearer than the unshaped one,
    whose residual swing carries it far out; each distance is the brute force's over the recorded load path."""
    png = tmp_path / "top.png"
    code, out, err = _cli(capsys, "plot", runs["shaped"], runs["unshaped"], "--view", "top", "--corridor",
                          "0,0,2,1.5", "--corridor-width", "0.6", "--out", png)
    assert code == 0, err
    printed = {line.split(":")[0]: float(line.split("at most ")[1].split(" m")[0]) for line in out.splitlines()
               if "from the corridor" in line}
    for label in ("shaped", "unshaped"):
        c = read_result(runs[label])
        brute = _brute_force([(0, 0), (2, 1.5)], c["plant.x2"], c["plant.y2"], n=4001).max()
        assert printed[label] == pytest.approx(brute, abs=5e-4), label  # 2.5 m sampled every 0.6 mm
    assert printed["shaped"] < 0.3 < printed["unshaped"]  # the unshaped load leaves a corridor of 0.6 m
    assert "unshaped: the load at most" in out and "(OUTSIDE 0.3 m)" in out.splitlines()[-1]
    with Image.open(png) as image:
        assert image.size[0] > 600


def test_the_top_view_draws_trolley_hook_and_load_of_each_run(runs, tmp_path):
    drawn = plot_top({k: read_result(runs[k]) for k in ("shaped", "unshaped")}, tmp_path / "top.png",
                     corridor=L_PATH, width=0.6)
    assert drawn["legend"][0].startswith("corridor's centre line (width 0.6 m)")
    assert [t.split(" (")[0] for t in drawn["legend"][1:]] == [
        f"{r}: {part}" for r in ("shaped", "unshaped") for part in ("trolley", "hook", "load")]


def test_the_swing_view_shows_each_cables_angle_in_space(runs, tmp_path):
    """swing1 and swing2, the angles from the vertical: the ZV-shaped move leaves the residual swing far below the
    unshaped one's (its peak over the last 5 s, in the plot's peaks: the whole run's)."""
    columns = {k: read_result(runs[k]) for k in ("shaped", "unshaped")}
    drawn = plot_swing(columns, tmp_path / "swing.png")
    assert drawn["panels"] == ["swing1 [deg]", "swing2 [deg]"]
    for label, c in columns.items():
        assert drawn["peaks"][label] == pytest.approx([math.degrees(np.abs(c[f"plant.{n}"]).max())
                                                      for n in ("swing1", "swing2")], rel=1e-12)
    late = {k: math.degrees(np.abs(c["plant.swing2"][c["time"] > 5]).max()) for k, c in columns.items()}
    assert late["shaped"] < 0.5 and late["unshaped"] > 5.0


def test_planar_and_spatial_results_in_one_plot_are_refused_in_one_line(runs, tmp_path, capsys):
    for view in ("time", "top", "swing"):
        code, _, err = _cli(capsys, "plot", runs["shaped"], runs["planar"], "--view", view, "--out",
                            tmp_path / "mixed.png")
        assert code == 2 and len(err.strip().splitlines()) == 1, (view, err)
        assert "planar is a CranePlant result and shaped a CranePlant3D one: one plot takes the results of one " \
               "plant" in err, err
    assert not (tmp_path / "mixed.png").exists()


def test_a_planar_top_view_and_a_misplaced_corridor_are_refused_in_one_line(runs, tmp_path, capsys):
    code, _, err = _cli(capsys, "plot", runs["planar"], "--view", "top", "--out", tmp_path / "top.png")
    assert code == 2 and "--view top needs a crane that moves in two horizontal axes; planar is a CranePlant " \
                         "result (axes x)" in err
    code, _, err = _cli(capsys, "plot", runs["shaped"], "--corridor", "0,0,1,1", "--corridor-width", "1", "--out",
                        tmp_path / "t.png")
    assert code == 2 and "--corridor and --corridor-width go with --view top, not --view time" in err
    code, _, err = _cli(capsys, "plot", runs["shaped"], "--view", "top", "--corridor-width", "1", "--out",
                        tmp_path / "t.png")
    assert code == 2 and "--corridor-width needs --corridor X0,Y0,X1,Y1,..." in err
    assert len(err.strip().splitlines()) == 1


def test_the_animation_of_a_spatial_run_takes_the_spatial_plant_and_draws_three_views(runs, tmp_path, capsys):
    """The spatial run has the planar plant's x, x1, y1, x2, y2 too: the animation reads the plant whose roles name
    the most (CranePlant3D), and draws the x-z plane, the y-z plane and the top view; a planar run stays planar."""
    columns = read_result(runs["shaped"])
    assert find_crane(columns, _animated)[1].model_identifier == "CranePlant3D"
    assert find_crane(read_result(runs["planar"]), _animated)[1].model_identifier == "CranePlant"
    gif = tmp_path / "move.gif"
    code, out, err = _cli(capsys, "animate", runs["shaped"], "--out", gif, "--fps", "5")
    assert code == 0, err
    with Image.open(gif) as image:
        assert image.n_frames == 51 and image.size == (920, 320)  # 10 s at 5 fps; three views side by side
        image.seek(25)
        middle = np.asarray(image.convert("RGB"))
    thirds = [middle[:, k * 306:(k + 1) * 306] for k in range(3)]
    orange = [np.sum((t[..., 0] > 200) & (t[..., 1] > 100) & (t[..., 1] < 160) & (t[..., 2] < 60)) for t in thirds]
    assert all(n > 20 for n in orange), orange  # the load in each view
