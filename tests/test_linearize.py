"""``crane-fmu linearize``: a plant FMU's A, B, C, D against the model's linearisation and exact Jacobians."""

import math

import numpy as np
import pytest

from crane_fmu.analysis.linearize import linearize
from crane_fmu.build_scripts.build_fmus import fmi3_dir
from crane_fmu.cli import main
from crane_fmu.model import plant
from crane_fmu.model import plant_continuous as me

SWING_ROWS, ANGLES = [3, 5], [2, 4]  # dtheta1, dtheta2 and theta1, theta2 among the states


@pytest.fixture(scope="module", params=["FMI 2.0", "FMI 3.0"])
def python_plant(request, fmu_dir):
    return (fmu_dir if request.param == "FMI 2.0" else fmi3_dir(fmu_dir)) / "CranePlant.fmu"


def _swing_error(lin, p):
    big_w, small_w = plant.linearisation(p)
    return (np.abs(lin.A[np.ix_(SWING_ROWS, ANGLES)] + np.array(big_w)).max(),
            np.abs(lin.B[SWING_ROWS, 0] + np.array(small_w)).max())


def test_co_simulation_plant_at_rest_is_the_linearisation(python_plant):
    """The Python (co-simulation only) plant by central differences of its map: at rest, -W and -w.

    With RK4 sub-steps of 0.1 ms the FMU's map is the ODE's to (w h)^4 (about 1e-13 here), and
    the differences (Richardson-extrapolated, delta = 1e-4) are exact to rounding: the issue's 1e-9.
    """
    lin = linearize(python_plant, {"theta1": 0.0}, {"max_substep": 1e-4})
    assert "central differences of the co-simulation's map" in lin.method
    assert lin.states == ["x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"]
    assert lin.inputs == ["u", "hoist", "F1", "F2"]
    assert max(_swing_error(lin, plant.COMPONENT.check({}).params)) < 1e-9
    assert lin.A[0, 1] == pytest.approx(1.0, abs=1e-9) and lin.B[1, 0] == pytest.approx(1.0, abs=1e-9)
    assert lin.C[lin.outputs.index("x2"), 4] == pytest.approx(0.5, abs=1e-9)  # x2 = x + l1 th1 + l2 th2


def test_co_simulation_plant_at_its_default_step_is_off_by_its_rk4_error(fmu_dir):
    """At the default 1 ms RK4 sub-steps the FMU's own frequencies are off by w^5 h^4 / 120 (w up to 9.5 rad/s),
    so A's stiffness entries, of the order w^2, are off by up to 2 w^6 h^4 / 120: 1.2e-8."""
    p = plant.COMPONENT.check({}).params
    lin = linearize(fmu_dir / "CranePlant.fmu", {"theta1": 0.0})
    big_w, _ = plant.linearisation(p)
    w_max = math.sqrt(max(np.linalg.eigvals(np.array(big_w)).real))
    assert _swing_error(lin, p)[0] < 2 * w_max ** 6 * 1e-3 ** 4 / 120


def test_co_simulation_plant_off_an_equilibrium_within_the_spread_it_states(fmu_dir):
    """Where the state moves, the map follows it; the result is the exact Jacobian within the stated spread."""
    at = {"theta1": 0.1, "dtheta2": 0.3, "u": 0.5}
    lin = linearize(fmu_dir / "CranePlant.fmu", at, {"l1": 1.5})
    config = plant.COMPONENT.check({"theta1_0": 0.1, "dtheta2_0": 0.3, "l1": 1.5})
    a, b, c, _ = (np.array(m) for m in me.jacobians(config, me.initial(config), (0.5, 0.0, 0.0, 0.0), me.FREE))
    assert np.abs(lin.A - a[:6, :6]).max() < lin.spread
    assert np.abs(lin.B[:, [0, 2, 3]] - b[:6, [0, 2, 3]]).max() < lin.spread  # hoist moves l1, no state here
    assert np.abs(lin.C - c[:, :6]).max() < 1e-8  # the outputs at the start: central differences only


def test_cli_prints_and_saves(fmu_dir, tmp_path, capsys):
    out = tmp_path / "plant.npz"
    assert main(["linearize", str(fmu_dir / "CranePlant.fmu"), "--at", "theta1=0deg", "--set", "l1=2",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "from central differences" in text and f"wrote {out}" in text
    saved = np.load(out)
    assert list(saved["states"]) == ["x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"]
    assert saved["A"].shape == (6, 6) and saved["B"].shape == (6, 4) and saved["D"].shape == (14, 4)
    big_w, _ = plant.linearisation(plant.COMPONENT.check({"l1": 2.0}).params)  # --set l1=2 reached the FMU
    assert np.abs(saved["A"][np.ix_(SWING_ROWS, ANGLES)] + np.array(big_w)).max() < 1e-7
    scipy_io = pytest.importorskip("scipy.io")
    mat = tmp_path / "plant.mat"
    assert main(["linearize", str(fmu_dir / "CranePlant.fmu"), "--at", "theta1=0", "--out", str(mat)]) == 0
    loaded = scipy_io.loadmat(mat)
    assert loaded["A"].shape == (6, 6) and [str(s[0]) for s in loaded["inputs"][0]] == ["u", "hoist", "F1", "F2"]


@pytest.mark.parametrize("argv, message", [
    (["--at", "speed=1"], "--at 'speed=1': the FMU has no state or input 'speed'"),
    (["--at", "theta1"], "--at 'theta1': expected NAME=VALUE"),
    (["--set", "mass=1"], "--set 'mass=1': the FMU has no parameter 'mass'"),
    (["--at", "theta1=0", "--set", "theta1_0=0.1"], "--at theta1 and --set theta1_0 both set the state theta1"),
    (["--set", "l1=-1"], "l1 must be > 0 and finite, got -1.0"),
    (["--out", "plant.txt"], "--out plant.txt: writes a .npz or .mat file"),
    (["--horizon", "0"], "--horizon must be > 0"),
    (["--at", "theta1=foo"], "--at 'theta1=foo': 'foo' is not a number"),
    (["--at", "theta1=nan"], "--at 'theta1=nan': 'nan' is not a finite number"),
    (["--at", "u=inf"], "--at 'u=inf': 'inf' is not a finite number"),
    (["--set", "l1=INF"], "l1 must be > 0 and finite, got inf"),
])
def test_cli_refuses_bad_input_in_one_line(fmu_dir, capsys, argv, message):
    assert main(["linearize", str(fmu_dir / "CranePlant.fmu"), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_cli_refuses_a_missing_fmu(capsys, tmp_path):
    assert main(["linearize", str(tmp_path / "none.fmu")]) == 2
    assert "none.fmu not found" in capsys.readouterr().err


def test_the_documented_example_prints_what_the_docs_show(fmu_dir, capsys):
    """The interoperability page's excerpt of `crane-fmu linearize ... --at theta1=0`: each shown number is the
    printed one to its 6 digits, and a shown 0 is within the co-simulation method's 1e-9 of it."""
    import re
    from pathlib import Path

    page = (Path(__file__).parent.parent / "docs" / "guide" / "interoperability.md").read_text()
    section = page.split("## Linearising a plant FMU", 1)[1].split("\n## ", 1)[0]
    command = re.search(r"```bash\ncrane-fmu (linearize .*)\n```", section).group(1).split()
    excerpt = re.findall(r"^(dtheta[12]) +(.*)$", section, re.M)
    assert len(excerpt) == 2
    fmu = str(fmu_dir / "CranePlant.fmu")
    assert main([a if a != "build/fmus/CranePlant.fmu" else fmu for a in command if a != "--out" and
                 not a.endswith(".npz")]) == 0
    printed = dict(re.findall(r"^(dtheta[12]) +(.*)$", capsys.readouterr().out.split("\nB (")[0], re.M))
    for name, shown in excerpt:
        got = [float(v) for v in printed[name].split()]
        assert [float(v) for v in shown.split()] == pytest.approx(got, rel=5e-6, abs=1e-9), name


@pytest.mark.parametrize("text", ["INF", "inf", "1e60"])
def test_a_limit_set_to_no_limit_as_the_docs_write_it(fmu_dir, capsys, text):
    """u_max's description says "1e60 or INF: no limit"; --set takes both (the same run, limits.py)."""
    assert main(["linearize", str(fmu_dir / "CranePlant.fmu"), "--at", "theta1=0", "--set", f"u_max={text}"]) == 0
    assert "1e60 or INF" in next(v.description for v in plant.COMPONENT.variables if v.name == "u_max")
