"""The controllers and the planner: designs against scipy, limits, the energy law's proof, through the FMUs."""

import math
import re

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp
from scipy.signal import cont2discrete

from crane_fmu import systems
from crane_fmu.cosim import ArrayRecorder, open_instance, run
from crane_fmu.model import energy, limits, lqr, planner, plant
from crane_fmu.model.parameters import PlantParameters

# The LQR's documented default weights (README, LqrController's variable table), written here rather than
# read from lqr.DEFAULT_WEIGHTS so that the scipy comparisons hold the FMU's defaults to the documented design.
WEIGHTS = [50.0, 0.0, 400.0, 10.0, 50.0, 5.0]  # q_x, q_dx, q_theta1, q_dtheta1, q_theta2, q_dtheta2


def _jacobian(p):
    """``(A, B)`` of the plant by central differences of eqs (8)-(9) (plant.derivative) about rest."""
    def f(s, u):
        return np.array(plant.derivative(tuple(s), u, p))

    eps, a = 1e-6, np.empty((6, 6))
    for j in range(6):
        d = np.zeros(6)
        d[j] = eps
        a[:, j] = (f(d, 0.0) - f(-d, 0.0)) / (2 * eps)
    b = (f(np.zeros(6), eps) - f(np.zeros(6), -eps)) / (2 * eps)
    return a, b[:, None]


@pytest.mark.quick
@pytest.mark.parametrize("p", [PlantParameters(), PlantParameters(l1=1.5, m2=3.0), PlantParameters(m2=0.0)])
def test_linearisation_is_the_jacobian_of_eqs_8_9(p):
    a, b = _jacobian(p)
    got_a, got_b = map(np.array, lqr.continuous_model(p))
    assert np.abs(got_a - a).max() < 1e-7 * np.abs(a).max()  # central differences: ~1e-10 relative
    assert np.abs(got_b - b).max() < 1e-7


@pytest.mark.quick
@pytest.mark.parametrize("p, weights, r, h", [
    (PlantParameters(), WEIGHTS, 0.05, 1e-3),
    (PlantParameters(l1=1.5), WEIGHTS, 0.05, 1e-3),
    (PlantParameters(m2=10.5, l2=0.6), [1, 2, 3, 4, 5, 6], 1.0, 1e-2),
    (PlantParameters(), [10, 0, 100, 0, 100, 0], 0.5, 5e-2),
])
def test_lqr_gains_equal_scipy_riccati(p, weights, r, h):
    """Our pure-Python ZOH and doubling DARE against scipy's cont2discrete and solve_discrete_are.

    Measured: 3e-12 relative at h = 1 ms, where the DARE is worst conditioned; bound 1e-9.
    """
    # (A, B) themselves are checked against the Jacobian above
    ad, bd, *_ = cont2discrete((*map(np.array, lqr.continuous_model(p)), np.eye(6), np.zeros((6, 1))), h)
    big_p = scipy.linalg.solve_discrete_are(ad, bd, np.diag(weights), np.array([[r]]))
    expected = np.linalg.solve(r + bd.T @ big_p @ bd, bd.T @ big_p @ ad)[0]
    got = np.array(lqr.design(p, weights, r, h))
    assert np.abs(got - expected).max() < 1e-9 * np.abs(expected).max()
    assert np.abs(np.linalg.eigvals(ad - bd @ got[None, :])).max() < 1  # the loop it closes is stable


def test_lqr_fmu_designs_from_the_parameters_it_is_given(fmu_dir):
    """--set controller.l1=1.5 gives the LQR for 1.5 m: the FMU's u is -K s with scipy's K for 1.5 m.

    The FMU runs on its default weights, scipy on the documented ones written in this file: a changed
    default (q_theta2 halved, say) is a different K and fails here.
    """
    state = (0.01, -0.02, 0.003, 0.01, -0.002, 0.004)  # small: no limit acts

    def u_of(values):
        inst = open_instance(fmu_dir / "LqrController.fmu", "lqr")
        try:
            inst.setup(0.0)
            for name, value in values.items():
                inst.set(name, value)
            inst.enter_initialization()
            inst.exit_initialization()
            for name, value in zip(("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2"), state):
                inst.set(name, value)
            return inst.get("u")
        finally:
            inst.free()

    for values, p, h in (({}, PlantParameters(), 1e-3), ({"l1": 1.5, "h": 0.01}, PlantParameters(l1=1.5), 0.01)):
        ad, bd, *_ = cont2discrete((*map(np.array, lqr.continuous_model(p)), np.eye(6), np.zeros((6, 1))), h)
        big_p = scipy.linalg.solve_discrete_are(ad, bd, np.diag(WEIGHTS), np.array([[0.05]]))
        k = np.linalg.solve(0.05 + bd.T @ big_p @ bd, bd.T @ big_p @ ad)[0]
        assert u_of(values) == pytest.approx(-k @ np.array(state), rel=1e-9)


def test_lqr_regulation_meets_its_targets(fmu_dir):
    """Section V regulation from 10 deg by the LQR through the FMUs, against the targets the README sets for
    it ("Controllers that stop the swing": both angles within 0.5 deg by 3.0 s, within 0.1 deg by 4.0 s,
    the trolley within 1 cm of x_d by 4 s) and its limits (|u| <= u_max = 2 m/s2, |v| <= v_max = 1 m/s).

    A settling time is that of both angles: from it on both stay within the band, and at the sample before
    at least one is outside. In this run the payload's angle settles last (theta2 is the slower mode), so a
    settling time taken from theta1 alone breaks the second half.
    """
    from crane_fmu.analysis import metrics

    c = run(systems.get("lqr"), fmu_dir, recorder=ArrayRecorder()).columns()
    t, theta1, theta2 = c["time"], c["plant.theta1"], c["plant.theta2"]
    m = metrics.move_metrics(t, c["plant.x"], c["plant.dx"], (theta1, theta2), c["controller.u"], 0.0)
    for band, target in ((0.5, 3.0), (0.1, 4.0)):
        settled = m[f"settling_{band}deg_s"]
        assert settled is not None and settled <= target, (band, settled)
        k = int(np.searchsorted(t, settled))
        inside = (np.abs(theta1) <= math.radians(band)) & (np.abs(theta2) <= math.radians(band))
        late = k + int(np.argmin(inside[k:])) if not inside[k:].all() else None
        assert late is None, (f"settled within {band} deg at {settled} s, yet at t = {t[late]:.3f} s theta1 = "
                              f"{math.degrees(theta1[late]):.3f} deg, theta2 = {math.degrees(theta2[late]):.3f} deg")
        assert not inside[k - 1], f"both angles within {band} deg already at t = {t[k - 1]:.3f} s, before {settled} s"
    assert m["position_1cm_s"] <= 4.0
    assert m["peak_abs_u"] <= 2.0 and m["peak_abs_v"] <= 1.0


@pytest.mark.quick
@pytest.mark.parametrize("u, dx, expected", [
    (5.0, 0.0, 2.0), (-5.0, 0.0, -2.0), (1.0, 0.0, 1.0),
    (2.0, 0.999, 1.0),  # 1 ms from the speed limit: only what reaches it exactly
    (2.0, 1.5, -2.0),  # faster than v_max: brake
    (-2.0, -1.0, 0.0),
])
def test_limits(u, dx, expected):
    assert limits.limited(u, dx, 2.0, 1.0, 1e-3) == pytest.approx(expected, rel=1e-12)
    assert limits.limited(u, dx, math.inf, math.inf, 1e-3) == u


@pytest.mark.quick
@pytest.mark.parametrize("values, message", [
    ({"u_max": 0.0}, "u_max must be > 0 (inf: no limit), got 0.0"),
    ({"v_max": -1.0}, "v_max must be > 0 (inf: no limit), got -1.0"),
    ({"r": 0.0}, "r must be > 0 and finite, got 0.0"),
    ({"q_theta1": -1.0}, "q_theta1 must be >= 0 and finite, got -1.0"),
    ({"h": 0.0}, "h must be > 0 and finite, got 0.0"),
])
def test_lqr_parameter_rules(values, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        lqr.COMPONENT.check(values)


def _linear_swing(p, accel, t_end):
    """The linearised swing driven by a trolley acceleration, from the Jacobian (not from plant.linearisation)."""
    a, b = _jacobian(p)
    sol = solve_ivp(lambda t, s: a[[2, 3, 4, 5]][:, [2, 3, 4, 5]] @ s + b[[2, 3, 4, 5], 0] * accel(t),
                    (0.0, t_end), np.zeros(4), method="DOP853", rtol=1e-11, atol=1e-13, max_step=0.005,
                    dense_output=True)
    return sol.sol


@pytest.mark.quick
@pytest.mark.parametrize("shaper", ["zv", "zvd", "ei", "none"])
def test_planner_reference_is_a_consistent_move_within_the_limits(shaper):
    c = planner.configure({**planner.COMPONENT.defaults(), "x_d": 2.0, "shaper": shaper})
    t = np.arange(0.0, c.end + 1.0, 1e-3)
    ref = np.array([planner.reference(c, ti) for ti in t])
    assert np.abs(ref[:, 2]).max() <= 2.0 * (1 + 1e-12) and np.abs(ref[:, 1]).max() <= 1.0 * (1 + 1e-12)
    assert ref[-1, 0] == 2.0 and ref[-1, 1] == 0.0
    # x_ref and dx_ref integrate ddx_ref (trapezoid over 1 ms on piecewise-constant steps: ~1e-3 * 2 m/s2)
    assert np.abs(np.diff(ref[:, 1]) - 0.5 * (ref[1:, 2] + ref[:-1, 2]) * 1e-3).max() < 2.1e-3
    assert np.abs(np.diff(ref[:, 0]) - 0.5 * (ref[1:, 1] + ref[:-1, 1]) * 1e-3).max() < 2e-6


def test_planner_swing_references_and_zero_residual_in_the_linear_model():
    p = PlantParameters()
    for shaper in ("zv", "zvd"):
        c = planner.configure({**planner.COMPONENT.defaults(), "x_d": 2.0, "shaper": shaper})
        swing = _linear_swing(p, lambda t, c=c: planner.reference(c, t)[2], c.end + 3.0)
        during = np.arange(0.0, c.end, 0.01)
        ref = np.array([planner.reference(c, ti)[3:] for ti in during])
        assert np.abs(ref - swing(during).T).max() < 1e-6  # the analytic modal response equals DOP853
        after = swing(np.arange(c.end, c.end + 3.0, 0.01))
        assert np.abs(after[[0, 2]]).max() < 1e-6  # rad: the shaped move leaves no swing in the linear model


def _closed_form_periods(m1, m2, l1, l2, g):
    """The two swing periods of the double pendulum on a held trolley, linearised about rest, in closed form: with
    mu = m1 + m2, det(K - w^2 M) = 0 for M = [[mu l1, m2 l2], [l1, l2]], K = diag(mu g, g) is
    m1 l1 l2 w^4 - mu g (l1 + l2) w^2 + mu g^2 = 0 (eqs (8)-(9) with sin q = q, cos q = 1, u = 0)."""
    mu = m1 + m2
    a, b, c = m1 * l1 * l2, -mu * g * (l1 + l2), mu * g * g
    roots = ((-b - math.sqrt(b * b - 4 * a * c)) / (2 * a), (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a))
    return tuple(2 * math.pi / math.sqrt(w2) for w2 in roots)  # the slow mode's first


@pytest.mark.quick
@pytest.mark.parametrize("crane", [{}, {"l1": 2.0, "l2": 0.3}, {"m1": 5.0, "m2": 1.0, "l1": 0.6, "l2": 1.2},
                                   {"m2": 20.0, "g": 9.81}], ids=str)
def test_the_shapers_impulses_are_at_half_periods_of_the_closed_form_modes(crane):
    """ZV: 1/2 at 0 and T/2 per mode; ZVD: 1/4, 1/2, 1/4 at 0, T/2, T; the planner applies one shaper per mode, one
    after the other: every sum of one impulse of each, its amplitude the product. Times to 1e-12 s, the closed-form
    periods from the quadratic in w^2 (the Section V crane: 2.36825 s and 0.65880 s)."""
    values = {**planner.COMPONENT.defaults(), **crane, "x_d": 2.0}
    slow, fast = _closed_form_periods(*(values[n] for n in ("m1", "m2", "l1", "l2", "g")))
    if not crane:
        assert (slow, fast) == pytest.approx((2.36825, 0.65880), abs=1e-5)  # 0.42225 Hz and 1.51792 Hz
    one = {"zv": [(0.0, 0.5), (0.5, 0.5)], "zvd": [(0.0, 0.25), (0.5, 0.5), (1.0, 0.25)]}  # (time / T, amplitude)
    for kind, impulses in one.items():
        c = planner.configure({**values, "shaper": kind})
        wanted = sorted((ts * slow + tf * fast, a_s * a_f) for ts, a_s in impulses for tf, a_f in impulses)
        assert len(c.impulses) == len(wanted)
        for (t, amplitude), (t_wanted, a_wanted) in zip(c.impulses, wanted):
            assert t == pytest.approx(t_wanted, abs=1e-12) and amplitude == pytest.approx(a_wanted, abs=1e-15)


def test_zvd_and_ei_are_more_robust_than_zv_to_a_wrong_cable_length():
    """Planned for l2 = 0.5 m, run on a linear model with l2 = 0.6 m: residual swing by shaper."""
    residual = {}
    for shaper in ("zv", "zvd", "ei", "none"):
        c = planner.configure({**planner.COMPONENT.defaults(), "x_d": 2.0, "shaper": shaper})
        swing = _linear_swing(PlantParameters(l2=0.6), lambda t, c=c: planner.reference(c, t)[2], c.end + 4.0)
        residual[shaper] = np.abs(swing(np.arange(c.end, c.end + 4.0, 0.01))[[0, 2]]).max()
    assert residual["zvd"] < residual["zv"] < residual["none"] and residual["ei"] < residual["zv"]


def _relative_energy(s, p):
    """Kinetic energy of hook and payload relative to the trolley, plus their potential energy, eq (E1)."""
    _, _, q1, w1, q2, w2 = s
    v1 = np.array([p.l1 * w1 * math.cos(q1), p.l1 * w1 * math.sin(q1)])
    v2 = v1 + np.array([p.l2 * w2 * math.cos(q2), p.l2 * w2 * math.sin(q2)])
    potential = p.g * ((p.m1 + p.m2) * p.l1 * (1 - math.cos(q1)) + p.m2 * p.l2 * (1 - math.cos(q2)))
    return 0.5 * (p.m1 * v1 @ v1 + p.m2 * v2 @ v2) + potential


@pytest.mark.quick
def test_energy_law_lyapunov_function_never_increases():
    """Eq (E5): along the continuous-time closed loop from 40 deg, V(t) is non-increasing and |u| <= u_max."""
    p = PlantParameters()
    c = energy.configure({**energy.COMPONENT.defaults(), "v_max": math.inf})
    a = c.u_max / 2
    mu = p.m1 + p.m2

    def law(s):
        return energy.control(c, s)

    def lyapunov(s):
        x, v, q1, w1, q2, w2 = s
        chi = x - c.x_d - (mu * p.l1 * math.sin(q1) + p.m2 * p.l2 * math.sin(q2)) / mu / c.k_c
        phi = a * a / c.k_p * math.log(math.cosh(c.k_p * chi / a))
        return _relative_energy(s, p) / mu + 0.5 * c.k_c * v * v + c.k_c * phi

    sol = solve_ivp(lambda t, s: plant.derivative(tuple(s), law(s), p), (0.0, 30.0),
                    [0.0, 0.0, math.radians(40), 0.0, 0.0, 0.0], method="DOP853", rtol=1e-10, atol=1e-12,
                    t_eval=np.arange(0.0, 30.0, 0.01))
    values = np.array([lyapunov(s) for s in sol.y.T])
    assert np.diff(values).max() < 1e-9 * values[0]  # non-increasing up to the integrator's error
    assert values[-1] < 0.1 * values[0]  # and it does decrease
    assert max(abs(law(s)) for s in sol.y.T) <= c.u_max


def test_every_controller_keeps_its_limits_through_the_fmus(fmu_dir):
    for name in ("lqr", "energy"):
        system = systems.get(name).with_parameters({"plant": {"theta1_0": math.radians(30)}})
        c = run(system, fmu_dir, recorder=ArrayRecorder(), stop_time=5.0).columns()
        assert np.abs(c["controller.u"]).max() <= 2.0
        assert np.abs(c["plant.dx"]).max() <= 1.0 + 1e-9


def test_lqr_system_through_the_fmus_equals_the_python_loop(fmu_dir):
    """Same code in the FMUs and here: bit for bit; and the regulation converges."""
    result = run(systems.get("lqr"), fmu_dir, recorder=ArrayRecorder(), stop_time=6.0).columns()
    config = plant.configure(plant.COMPONENT.defaults())
    law = lqr.configure(lqr.COMPONENT.defaults())
    state = config.state0
    for k in range(6000):
        assert result["plant.x"][k] == state[0] and result["plant.theta1"][k] == state[2]
        state = plant.update(config, state, (lqr.control(law, state[:6]), 0.0, 0.0, 0.0), k * 1e-3, 1e-3)
    assert abs(result["plant.theta1"][-1]) < math.radians(0.1) and abs(result["plant.x"][-1]) < 0.01


def test_transport_through_the_fmus_arrives(fmu_dir):
    result = run(systems.get("transport"), fmu_dir, recorder=ArrayRecorder(), stop_time=8.0).columns()
    assert result["plant.x"][-1] == pytest.approx(2.0, abs=1e-3)
    assert np.abs(result["plant.dx"]).max() <= 1.0 + 1e-9
    assert max(abs(result["plant.theta1"][-1]), abs(result["plant.theta2"][-1])) < math.radians(0.1)


def test_runs_at_another_step_get_designs_for_it():
    adapted = systems.prepare(systems.get("transport"), 0.01)
    assert adapted.step == 0.01 and adapted.parameters["controller"]["h"] == 0.01
    assert "h" not in adapted.parameters.get("planner", {})
    kept = systems.prepare(systems.get("lqr"), 0.01, values=[{"controller": {"h": 0.002}}])
    assert kept.parameters["controller"]["h"] == 0.002  # what the user set stays
    with pytest.raises(ValueError, match="controller: h must be > 0"):
        systems.prepare(systems.get("lqr"), values=[{"controller": {"h": -1.0}}])


@pytest.mark.quick
def test_lqr_gains_follow_the_measured_cable_length():
    c = lqr.configure({**lqr.COMPONENT.defaults(), "l1_low": 1.0, "l1_high": 2.0})
    at_1_5 = lqr.design(PlantParameters(l1=1.5), WEIGHTS, 0.05, 1e-3)
    assert lqr.scheduled_gains(c, 1.5) == pytest.approx(at_1_5, rel=1e-12)  # a design point
    between = lqr.scheduled_gains(c, 1.525)  # halfway to the next design point, 1.55 m
    at_1_55 = lqr.design(PlantParameters(l1=1.55), WEIGHTS, 0.05, 1e-3)
    assert between == pytest.approx([(a + b) / 2 for a, b in zip(at_1_5, at_1_55)], rel=1e-12)
    assert lqr.scheduled_gains(c, 0.0) == c.gains  # not measured: the design for l1
    assert lqr.scheduled_gains(c, 5.0) == pytest.approx(lqr.scheduled_gains(c, 2.0), rel=0)  # clamped


def test_hoist_transport_through_the_fmus(fmu_dir):
    """The 2 m move while lifting from 2 m to 1 m: the trolley and the hoist arrive and the swing dies out."""
    result = run(systems.bind(systems.get("hoist-transport")), fmu_dir, recorder=ArrayRecorder()).columns()
    assert result["plant.x"][-1] == pytest.approx(2.0, abs=1e-3)
    assert result["plant.l1_now"][0] == 2.0 and result["plant.l1_now"][-1] == pytest.approx(1.0, abs=1e-9)
    assert max(abs(result["plant.theta1"][-1]), abs(result["plant.theta2"][-1])) < math.radians(0.1)
    assert np.abs(result["controller.u"]).max() <= 2.0
