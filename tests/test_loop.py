"""`crane-fmu linearize --loop`: the sampled-data closed loop of a system's plant and controller.

- On the LQR loop, an independent answer: python-control designs the discrete LQR itself (``dlqr`` on the
  zero-order-hold plant) and computes the loop's poles, margins and sensitivity peak; ours identifies the
  controller FMU from its step map. Gains, poles, margins and Ms agree.
- A law file's PD gains come out of its step map as the law says (u = -k_x x - k_v dx + k_s dtheta1), and
  its loop's poles are those of Phi + Gamma K C.
- A controller with memory: the loop's poles from its state matrix are where 1 + L(z) = 0.
"""

import warnings
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
    measured = np.vstack([Hs, np.zeros((8, 2))])  # its response over a window of 10 steps: it dies out
    a = loop.analyse(plant, "u", [("x", "x"), ("dx", "dx")], measured, 0.1, {})
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
    (["--loop", "--system", "lqr", "--memory", "0"], "--memory must be > 0 s, got 0.0"),
    (["--loop", "--system", "lqr", "--memory", "2"],  # the LQR reads 7 inputs: the six states and l1_now
     "--memory 2 s: 2000 steps x 7 inputs of controller make 14000 states, more than the 6000 the analysis takes "
     "(--memory <= 0.857 s at h = 0.001 s)"),
    (["plant.fmu", "--memory", "1"], "--memory is for --loop"),
])
def test_a_loop_that_cannot_be_analysed_is_one_line(fmu_folder, capsys, argv, message):
    code = main(["linearize", *argv, "--fmu-dir", str(fmu_folder)] if "--loop" in argv else ["linearize", *argv])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err


# A law file of state feedback plus an integral of x - x_d (the state), as a user writes it (try-designer's
# sway_pi.py): u = -(K y + k_i s), s[k+1] = s[k] + (x[k] - x_d) h. Its impulse response never dies out.
_PI_LAW = '''
from crane_fmu.model.component import Component
from crane_fmu.model.tables import MEASURED_STATE, output, parameter

NAMES = ("k_x", "k_v", "k_t1", "k_dt1", "k_t2", "k_dt2", "k_i", "k_ii", "x_d", "leak")


def configure(values):
    return tuple(values[k] for k in NAMES)


def initial_state(config):
    return (0.0, 0.0)  # the integral of x - x_d, and the integral of that


def update(config, state, inputs, time, step):
    return (state[0] * (1 - config[9] * step) + (inputs[0] - config[8]) * step, state[1] + state[0] * step)


def law(config, state, inputs):
    k_x, k_v, k_t1, k_dt1, k_t2, k_dt2, k_i, k_ii, x_d, _ = config
    x, dx, t1, dt1, t2, dt2 = inputs
    return (-(k_x * (x - x_d) + k_v * dx + k_t1 * t1 + k_dt1 * dt1 + k_t2 * t2 + k_dt2 * dt2 + k_i * state[0]
              + k_ii * state[1]),)


COMPONENT = Component(
    "SwayPiTest", "controller", "state feedback with an integral on the trolley error",
    (parameter("k_x", 30.0, "1/s2", "position gain"), parameter("k_v", 27.0, "1/s", "velocity gain"),
     parameter("k_t1", -160.0, "m/s2", "hook angle gain"), parameter("k_dt1", 3.5, "m/s", "hook rate gain"),
     parameter("k_t2", 50.0, "m/s2", "payload angle gain"), parameter("k_dt2", 2.0, "m/s", "payload rate gain"),
     parameter("k_i", 0.0, "1/s2", "integral gain (units loose)"),
     parameter("k_ii", 0.0, "1/s2", "double integral gain (units loose)"),
     parameter("x_d", 0.0, "m", "target"), parameter("leak", 0.0, "1/s", "the integral's leak (a first-order lag)"))
    + MEASURED_STATE + (output("u", "m/s2", "demanded trolley acceleration"),),
    configure, law, feedthrough=True, initial_state=initial_state, update=update)
'''
_PI_GAINS = np.array([30.0, 27.0, -160.0, 3.5, 50.0, 2.0])


def _pi_loop(fmu_folder, tmp_path, values):
    law = tmp_path / "sway_pi_test.py"
    law.write_text(_PI_LAW)
    with systems.open_system("lqr") as system:
        system = system.with_instances({"controller": str(law)}).with_parameters({"controller": values})
        system = systems.prepare(system, H)
        fmus, connections = systems.resolve(system, fmu_folder)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            a = loop.of_system(system, fmus, connections)
            text = loop.report(a)
        return a, text, [str(w.message) for w in caught]


def _exact_pi_loop(fmu_folder, k_i, leak=0.0):
    """try-designer's independent model: the zero-order-hold plant with the law's integral as a 7th state,
    ``u[k] = -(K y[k] + k_i s[k])``: its closed-loop matrix and its loop broken at u (python-control)."""
    plant = lin.linearize(fmu_folder / "CranePlant.fmu", {"theta1": 0.0})
    A, B = plant.A, plant.B[:, [plant.inputs.index("u")]]
    d = control.c2d(control.ss(A, B, np.eye(6), 0), H, "zoh")
    Ad = np.zeros((7, 7))
    Ad[:6, :6], Ad[6, 6], Ad[6, 0] = d.A, 1 - leak * H, H
    Bd = np.vstack([d.B, [[0.0]]])
    K = np.concatenate([_PI_GAINS, [k_i]])[None, :]
    return Ad - Bd @ K, control.ss(Ad, Bd, K, 0, dt=H)


@pytest.mark.parametrize("k_i, leak", [(60.0, 0.0), (20.0, 0.0), (20.0, 1.0)])
def test_a_law_with_an_integrator_has_the_poles_and_margins_of_its_exact_model(fmu_folder, tmp_path, k_i, leak):
    """The integral's response never dies out: cut at 0.5 s it was a finite average, and k_i = 60 was called
    stable (|z| = 0.999637) where the loop grows as e^(0.037 t). Continued as the integrator it is, the poles
    are those of the exact 7-state model (k_i = 60: s = +0.037 +- 1.41j, unstable; k_i = 20: stable). A leaky
    integral (a first-order lag of time constant 1 s, alive at 0.5 s too) is continued as that mode."""
    ours, text, caught = _pi_loop(fmu_folder, tmp_path, {"k_i": k_i, "leak": leak})
    closed, L = _exact_pi_loop(fmu_folder, k_i, leak)
    theirs = np.linalg.eigvals(closed)
    if k_i == 60.0:  # as docs/guide/interoperability.md shows it
        assert np.abs(theirs).max() > 1 and "closed loop: UNSTABLE (largest |z| = 1.00004)" in text, text
        assert "; memory of 1 step, then for ever one mode, x1 a step (an integrator), from -0.06 x\n" in text, text
        assert text.endswith("(the closed loop is unstable: the margins above are where L crosses, not how far it "
                             "is from instability)"), text
    else:
        assert np.abs(theirs).max() < 1 and "closed loop: stable" in text, text
    assert np.allclose(np.sort_complex(ours.poles), np.sort_complex(theirs), atol=1e-8), (ours.poles, theirs)
    assert not caught  # no numpy warning reaches the terminal
    assert ours.tail is not None and ours.tail.ratio == pytest.approx(1 - leak * H, abs=1e-9)
    if k_i == 20.0:  # a stable loop: its margins are those of the exact loop broken at u
        w = np.logspace(-2, np.log10(np.pi / H), 20000)[:-1]
        gm, pm, _, wg, wp, _ = control.stability_margins(control.frd(L, w))
        m = ours.margins
        assert m.gain_margin == pytest.approx(gm, rel=1e-3) and m.gain_crossover == pytest.approx(wg, rel=1e-3)
        assert m.phase_margin_deg == pytest.approx(pm, abs=0.05) and m.phase_crossover == pytest.approx(wp, rel=1e-3)


def test_a_static_law_file_is_taken_as_before(fmu_folder, tmp_path):
    """k_i = 0: the same law is static, its margins those of python-control's static loop -K (zI - Phi)^-1 Gamma."""
    ours, text, caught = _pi_loop(fmu_folder, tmp_path, {})
    assert ours.memory == 1 and np.allclose(ours.K, -_PI_GAINS, atol=1e-8) and not caught
    _, L = _exact_pi_loop(fmu_folder, 0.0)
    w = np.logspace(-2, np.log10(np.pi / H), 20000)[:-1]
    gm, pm, _, wg, wp, _ = control.stability_margins(control.frd(L, w))
    m = ours.margins
    assert m.gain_margin == pytest.approx(gm, rel=1e-3) and m.phase_margin_deg == pytest.approx(pm, abs=0.05)
    assert "static at this point (no memory)" in text


def test_a_response_the_window_cuts_off_is_refused_in_one_line(fmu_folder, tmp_path, capsys):
    """A double integral's response grows for ever and is no single mode: no verdict, one line naming the
    controller, the window and --memory."""
    _pi_loop(fmu_folder, tmp_path, {})  # writes the law file
    law = tmp_path / "sway_pi_test.py"
    code = main(["linearize", "--loop", "--system", "lqr", "--fmu-dir", str(fmu_folder), "--use",
                 f"controller={law}", "--set", "controller.k_i=20", "--set", "controller.k_ii=5"])
    out, err = capsys.readouterr()
    assert code == 2 and "closed loop:" not in out, out
    assert err.count("\n") == 1 and "controller (sway_pi_test.py): its impulse response has not died out within " \
        "the 0.5 s analysed" in err and "--memory SECONDS" in err, err
