"""`crane-fmu linearize --loop`: the sampled-data closed loop of a system's plant and controller.

- On the LQR loop, an independent answer: python-control designs the discrete LQR itself (``dlqr`` on the
  zero-order-hold plant) and computes the loop's poles, margins and sensitivity peak; ours identifies the
  controller FMU from its step map. Gains, poles, margins and Ms agree.
- A law file's PD gains come out of its step map as the law says (u = -k_x x - k_v dx + k_s dtheta1), and
  its loop's poles are those of Phi + Gamma K C.
- A controller with memory: the loop's poles from its state matrix are where 1 + L(z) = 0.
"""

from pathlib import Path

import numpy as np
import pytest

from crane_fmu import components, systems
from crane_fmu.analysis import linearize as lin
from crane_fmu.analysis import loop
from crane_fmu.build_scripts.build_fmus import build_all
from crane_fmu.cli import main

control = pytest.importorskip("control")
ROOT = Path(__file__).resolve().parents[1]
H = 1e-3


@pytest.fixture(scope="module")
def fmu_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("loop") / "fmus"
    build_all(out, ["CranePlant", "LqrController"], systems=[], containers=[], native=False, fmi3=False,
              log=lambda line: None)
    return out


def _analysis(fmu_folder, use=None):
    with systems.open_system("lqr") as system:
        if use:
            system = system.with_instances({"controller": str(use)})
        system = systems.prepare(system, H)
        fmus, connections = systems.resolve(system, fmu_folder)
        return loop.of_system(system, fmus, connections)


def test_the_lqr_loop_agrees_with_python_control(fmu_folder):
    ours = _analysis(fmu_folder)
    plant = lin.linearize(fmu_folder / "CranePlant.fmu", {"theta1": 0.0})
    states = list(plant.states)
    A, B = plant.A, plant.B[:, [plant.inputs.index("u")]]
    discrete = control.c2d(control.ss(A, B, np.eye(6), 0), H, "zoh")
    defaults = components.get("LqrController").defaults()
    Q = np.diag([defaults[f"q_{name}"] for name in states])
    K, _, _ = control.dlqr(discrete.A, discrete.B, Q, [[defaults["r"]]])  # u = -K x, designed here
    assert ours.inputs[:6] == states
    assert np.allclose(ours.K[:6], -K[0], rtol=1e-6, atol=1e-9), (ours.K, K)
    assert ours.memory == 1  # a static law at this point
    theirs_poles = np.linalg.eigvals(discrete.A - discrete.B @ K)
    assert np.allclose(np.sort_complex(ours.poles), np.sort_complex(theirs_poles), atol=1e-7)
    L = control.ss(discrete.A, discrete.B, K, 0, dt=H)  # the loop broken at u: u -> plant -> -(-K x)
    # python-control's margins of its own frequency response of that loop (its state-space margins of this
    # discrete loop, h = 1 ms with poles near z = 1, return crossings where |L| is not 1: 0.25 at 96 rad/s)
    w = np.logspace(-2, np.log10(np.pi / H), 20000)[:-1]
    gm, pm, _, wg, wp, _ = control.stability_margins(control.frd(L, w))
    m = ours.margins
    assert m.gain_margin == pytest.approx(gm, rel=1e-3) and m.gain_crossover == pytest.approx(wg, rel=1e-3)
    assert m.phase_margin_deg == pytest.approx(pm, abs=0.05) and m.phase_crossover == pytest.approx(wp, rel=1e-3)
    S = control.feedback(control.ss([], [], [], [[1.0]], dt=H), L)  # 1 / (1 + L)
    peak = np.abs(S(np.exp(1j * w * H))).max()
    assert m.sensitivity_peak == pytest.approx(peak, rel=1e-3)


def test_a_law_files_gains_come_out_of_its_step_map(fmu_folder):
    ours = _analysis(fmu_folder, ROOT / "examples" / "my_controller" / "pd_sway.py")
    k_x, k_v, k_s = 1.0, 1.5, 2.0  # the example's defaults
    assert np.allclose(ours.K, [-k_x, -k_v, 0, k_s, 0, 0], atol=1e-8)
    Phi, Gamma, C, _ = ours.G_parts
    expected = np.linalg.eigvals(Phi + Gamma @ np.array([[-k_x, -k_v, 0, k_s, 0, 0]]) @ C)
    assert np.allclose(np.sort_complex(ours.poles), np.sort_complex(expected), atol=1e-9)


def test_a_controller_with_memory_has_its_poles_where_one_plus_l_vanishes():
    """A made-up dynamic law (a two-step moving average of a PD law) on a double integrator: the state matrix's
    eigenvalues are the roots of 1 + L(z) (the return difference vanishes there)."""
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    plant = lin.Linearisation(A, np.array([[0.0], [1.0]]), np.eye(2), np.zeros((2, 1)), ["x", "dx"], ["u"],
                              ["x", "dx"], {"x": 0.0, "dx": 0.0, "u": 0.0}, "test", None)
    gains = np.array([-2.0, -1.5])
    Hs = np.array([gains * 0.6, gains * 0.4])
    a = loop.analyse(plant, "u", [("x", "x"), ("dx", "dx")], Hs, 0.1, {})
    assert a.memory == 2 and len(a.poles) == 4
    Phi, Gamma, C, D = a.G_parts
    for z in a.poles:
        if abs(z) < 1e-9:
            continue
        G = C @ np.linalg.solve(z * np.eye(2) - Phi, Gamma)[:, 0]
        K = Hs[0] + Hs[1] / z
        assert abs(1 - K @ G) < 1e-9 * max(1.0, abs(K @ G))


def test_the_loop_command_prints_the_analysis_and_plots(fmu_folder, tmp_path, capsys):
    code = main(["linearize", "--loop", "--system", "lqr", "--fmu-dir", str(fmu_folder), "--plot",
                 str(tmp_path / "loop.png")])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "closed loop: stable" in out and "phase margin:" in out and "sensitivity peak: Ms = " in out
    assert (tmp_path / "loop.png").stat().st_size > 10000


def test_a_moving_systems_loop_is_taken_at_rest_at_the_target(fmu_folder, capsys):
    """transport gives the plant its start values (theta1_0 = 0) and the law the move's target: the point is the
    load at rest at x = 2 m, where the law is off its limit (its gains, not zero)."""
    use = ROOT / "examples" / "my_controller" / "pd_sway.py"
    build_all(fmu_folder, ["TrajectoryPlanner"], systems=[], containers=[], native=False, fmi3=False,
              log=lambda line: None)
    code = main(["linearize", "--loop", "--system", "transport", "--fmu-dir", str(fmu_folder), "--use",
                 f"controller={use}"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "at x = 2, dx = 0, theta1 = 0" in out and "u[k] = -1 x -1.5 dx +0 theta1 +2 dtheta1" in out


@pytest.mark.parametrize("argv, message", [
    (["--loop"], "--loop and --system go together"),
    (["--loop", "--system", "lqr", "--at", "foo=1"], "--at 'foo=1': the FMU has no state or input 'foo'"),
    (["--loop", "--system", "free"], "nothing feeds plant.u: no loop to analyse"),
    ([], "give an FMU to linearise, or --loop --system NAME"),
])
def test_a_loop_that_cannot_be_analysed_is_one_line(fmu_folder, capsys, argv, message):
    code = main(["linearize", *argv, "--fmu-dir", str(fmu_folder)] if "--loop" in argv else ["linearize", *argv])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err
