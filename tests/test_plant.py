"""The extended CranePlant FMU: hoisting, forces, damping, drive limits and rail ends, against physics.

Each physics check runs on every kind of plant FMU (``plant_dir``: the Python FMU and the native one), so
the native plant has checks of its own that share no code with it, beside its equality with the Python one.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from crane_fmu.cosim import ArrayRecorder, FmiError, open_instance, simulate
from crane_fmu.model import plant
from crane_fmu.model.parameters import PlantParameters

P = PlantParameters()


def _run(fmu_dir, values, stop_time, step=1e-3):
    """The plant FMU alone with parameters and constant inputs ``values``; its columns without the prefix."""
    result = simulate({"plant": fmu_dir / "CranePlant.fmu"}, [], stop_time, step, parameters={"plant": values},
                      recorder=ArrayRecorder()).columns()
    return {name.removeprefix("plant."): values for name, values in result.items()}


def test_static_deflection_under_constant_forces_with_damping(plant_dir):
    """Equilibrium of the hanging loads under horizontal forces, in closed form:
    ``tan theta2 = F2 / (m2 g)`` (the payload's cable) and ``tan theta1 = (F1 + F2) / ((m1 + m2) g)`` (the hook's)."""
    f1, f2 = 4.0, 10.0
    c = _run(plant_dir, {"theta1_0": 0.0, "F1": f1, "F2": f2, "c1": 20.0, "c2": 5.0}, 60.0, 0.01)
    assert c["theta2"][-1] == pytest.approx(math.atan(f2 / (P.m2 * P.g)), abs=1e-9)
    assert c["theta1"][-1] == pytest.approx(math.atan((f1 + f2) / ((P.m1 + P.m2) * P.g)), abs=1e-9)
    assert np.abs(np.diff(c["theta1"][:500])).max() > 1e-4  # it did swing on its way there


def test_hoisting_run_equals_scipy_on_the_symbolic_equations(plant_dir):
    """Lowering at 0.3 m/s2 while the trolley accelerates, forces and damping on: DOP853 on the
    sympy-derived equations (tests/derivation.py). RK4 at 1 ms: measured 3e-11 rad; bound 1e-8."""
    from derivation import EXT_ACCEL

    values = {"theta1_0": 0.1, "theta2_0": -0.05, "u": 0.5, "hoist": 0.3, "F1": 1.0, "F2": -2.0, "c1": 0.5, "c2": 0.2}
    c = _run(plant_dir, values, 2.0)

    def field(t, s):
        q1, w1, q2, w2, length, dl = s
        dd1, dd2 = EXT_ACCEL(q1, w1, q2, w2, 0.5, P.m1, P.m2, length, P.l2, P.g, dl, 0.3, 1.0, -2.0, 0.5, 0.2)
        return [w1, dd1, w2, dd2, dl, 0.3]

    ref = solve_ivp(field, (0, 2.0), [0.1, 0.0, -0.05, 0.0, P.l1, 0.0], method="DOP853", t_eval=c["time"],
                    rtol=1e-12, atol=1e-12)
    assert np.abs(c["theta1"] - ref.y[0]).max() < 1e-8 and np.abs(c["theta2"] - ref.y[2]).max() < 1e-8
    assert c["l1_now"][-1] == pytest.approx(P.l1 + 0.5 * 0.3 * 4.0, rel=1e-12)  # l1'' = 0.3 exactly
    assert c["dl1_now"][-1] == pytest.approx(0.6, rel=1e-12)


def test_the_papers_fast_path_with_a_clamped_demand_equals_scipy_on_the_symbolic_equations(plant_dir):
    """The fast path (the paper's RK4 of eqs (8)-(9), nothing but u acting) with a demand beyond the drive:
    u = -3 m/s2 asked, u_max = 1.2, so the trolley takes -1.2. DOP853 at rtol = atol = 1e-12 on the equations sympy
    derives (tests/derivation.py) with u = -1.2: the angles within 1e-8 rad (RK4 at 1 ms: measured 1.8e-10), the
    trolley x = -0.6 t^2 to rounding (RK4 integrates a constant acceleration exactly). The free swing (u = 0,
    test_fmus.py) cannot see a term of u; this run can."""
    from derivation import ACCEL

    values = {"theta1_0": 0.1, "theta2_0": -0.05, "u": -3.0, "u_max": 1.2}
    c = _run(plant_dir, values, 3.0, 0.01)

    def field(t, s):
        dd1, dd2 = ACCEL(s[0], s[1], s[2], s[3], -1.2, P.m1, P.m2, P.l1, P.l2, P.g)
        return [s[1], dd1, s[3], dd2]

    ref = solve_ivp(field, (0, 3.0), [0.1, 0.0, -0.05, 0.0], method="DOP853", t_eval=c["time"], rtol=1e-12,
                    atol=1e-12)
    assert np.abs(c["theta1"] - ref.y[0]).max() < 1e-8 and np.abs(c["theta2"] - ref.y[2]).max() < 1e-8
    assert np.abs(c["x"] + 0.6 * c["time"] ** 2).max() < 1e-12
    assert np.abs(c["ddx"][1:] + 1.2).max() == 0.0


def test_power_balance(plant_dir):
    """dE/dt (the energy output) = trolley + hoist + forces - damping, with every new input in use.

    The drives' powers are their generalised forces times their rates: ``H = m1 x1'' + m2 x2'' - F1 - F2``
    for the trolley and ``Q_L = (m1 a1 + m2 a2 + (m1 + m2) g ey) . (sin th1, -cos th1) - (F1 + F2) sin th1``
    for the hoist, with the loads' accelerations from the kinematics of eqs (4)-(5) and the angular
    accelerations of the symbolic Lagrange derivation (tests/derivation.py), not of the plant's code: the
    FMU's recorded state and energy are the only things taken from the code under test.
    """
    u, hoist, f1, f2, c1, c2 = 0.7, -0.2, 3.0, -5.0, 0.8, 0.3
    values = {"l1": 1.5, "theta1_0": 0.3, "theta2_0": -0.2, "u": u, "hoist": hoist, "F1": f1, "F2": f2,
              "c1": c1, "c2": c2}
    c = _run(plant_dir, values, 2.0)
    t, m1, m2, l2, g = c["time"], P.m1, P.m2, P.l2, P.g
    q1, w1, q2, w2, length, dl, v = (c[n] for n in ("theta1", "dtheta1", "theta2", "dtheta2", "l1_now", "dl1_now",
                                                     "dx"))
    from derivation import EXT_ACCEL  # the sympy-derived accelerations, not the plant's own code

    dd = np.array([EXT_ACCEL(a, b, c_, d, u, m1, m2, e, l2, g, f, hoist, f1, f2, c1, c2)
                   for a, b, c_, d, e, f in zip(q1, w1, q2, w2, length, dl)])
    s1, co1, s2, co2 = np.sin(q1), np.cos(q1), np.sin(q2), np.cos(q2)
    ax1 = u + hoist * s1 + 2 * dl * w1 * co1 + length * dd[:, 0] * co1 - length * w1 ** 2 * s1
    ay1 = -hoist * co1 + 2 * dl * w1 * s1 + length * dd[:, 0] * s1 + length * w1 ** 2 * co1
    ax2, ay2 = ax1 + l2 * (dd[:, 1] * co2 - w2 ** 2 * s2), ay1 + l2 * (dd[:, 1] * s2 + w2 ** 2 * co2)
    vx1 = v + dl * s1 + length * w1 * co1
    vx2 = vx1 + l2 * w2 * co2
    trolley = (m1 * ax1 + m2 * ax2 - f1 - f2) * v
    hoisting = ((m1 * ax1 + m2 * ax2) * s1 - (m1 * (ay1 + g) + m2 * (ay2 + g)) * co1 - (f1 + f2) * s1) * dl
    power = trolley + hoisting + f1 * vx1 + f2 * vx2 - c1 * w1 ** 2 - c2 * (w2 - w1) ** 2
    e, h = c["energy"], t[1] - t[0]
    d_energy = (e[:-4] - 8 * e[1:-3] + 8 * e[3:-1] - e[4:]) / (12 * h)  # five-point stencil, O(h^4)
    # measured 9.6e-8 W against powers up to 49 W (second-order differences left 7e-4 W, shrinking as h^2)
    assert np.abs(d_energy - power[2:-2]).max() < 1e-6
    assert np.abs(power).max() > 10.0


def test_drive_limits_and_lag(plant_dir):
    """u = 5 m/s2 demanded; u_max 2, v_max 1, lag tau = 0.2 s: v(t) = 2 (t - tau (1 - exp(-t/tau))) until 1 m/s."""
    c = _run(plant_dir, {"theta1_0": 0.0, "u": 5.0, "u_max": 2.0, "v_max": 1.0, "tau": 0.2}, 2.0)
    t, v = c["time"], c["dx"]
    early = t <= 0.5
    assert np.abs(v[early] - 2 * (t[early] - 0.2 * (1 - np.exp(-t[early] / 0.2)))).max() < 1e-12
    assert v.max() <= 1.0 + 1e-12 and v[-1] == pytest.approx(1.0, abs=1e-12)
    assert c["ddx"].max() <= 2.0 and c["ddx"][-1] == pytest.approx(0.0, abs=1e-12)


def test_a_rail_end_discards_the_step_with_position_and_time(plant_dir):
    """u = 1 m/s2 from rest: x = t^2 / 2 passes x_max = 0.3 m at t = sqrt(0.6) = 0.7746 s, in the 10 ms step
    from 0.77 s; the plant checks the rail after each 1 ms sub-step, first past it at t = 0.775 s, where
    x = 0.775^2 / 2 = 0.3003125 m (the message's x = 0.300312...)."""
    with pytest.raises(FmiError) as err:
        _run(plant_dir, {"theta1_0": 0.0, "u": 1.0, "x_max": 0.3}, 2.0, 0.01)
    assert err.value.status == "discard"
    message = str(err.value)
    assert "the trolley would pass the rail end x_max = 0.3 m (x = 0.300312" in message
    assert "at t = 0.775 s" in message


def test_the_hoist_holds_l1_at_its_limit_and_says_so(plant_dir):
    """l1'' = 1 m/s2 from l1 = 1 m at rest: l1 = 1 + t^2 / 2 reaches l1_max = 1.2 m at t = sqrt(0.4) = 0.632 s, at
    l1' = 0.632 m/s: a limit that stops a moving cable, a warning with the speed (first past it after the 1 ms
    sub-step to 0.633 s)."""
    inst = open_instance(plant_dir / "CranePlant.fmu", "plant")
    try:
        inst.setup(0.0)
        for name, value in {"theta1_0": 0.0, "l1_max": 1.2, "hoist": 1.0}.items():
            inst.set(name, value)
        inst.enter_initialization()
        inst.exit_initialization()
        seen = []
        for k in range(100):
            inst.messages.clear()
            inst.do_step(k * 0.01, 0.01)
            seen += list(inst.messages)
        assert inst.get("l1_now") == 1.2 and inst.get("dl1_now") == 0.0
        assert len(seen) == 1 and seen[0].startswith("hoist: l1 hit the limit 1.2 m at 0.633") and \
            seen[0].endswith("m/s at t = 0.633 s and is held there")
    finally:
        inst.free()


@pytest.mark.quick
@pytest.mark.parametrize("values, message", [
    ({"c1": -1.0}, "c1 must be >= 0 and finite, got -1.0"),
    ({"m2": 0.0, "c2": 1.0}, "c2 must be 0 when m2 = 0"),
    ({"x_min": 1.0, "x_max": 0.5}, "x_min must be < x_max, got 1.0 and 0.5"),
    ({"x0": 2.0, "x_max": 1.0}, "x0 must lie on the rail"),
    ({"l1": 3.0, "l1_max": 2.0}, "l1 must lie within [l1_min, l1_max]"),
    ({"u_max": 0.0}, "u_max must be > 0 (INF: no limit), got 0.0"),
])
def test_new_parameter_rules(values, message):
    with pytest.raises(ValueError) as err:
        plant.COMPONENT.check(values)
    assert message in str(err.value)


@pytest.mark.quick
@pytest.mark.parametrize("name", ["x0", "dx0", "theta1_0", "dtheta1_0", "theta2_0", "dtheta2_0"])
def test_initial_state_must_be_finite(name):
    """Found by the fuzz test: a NaN initial velocity was accepted when initialisation ended."""
    with pytest.raises(ValueError) as err:
        plant.COMPONENT.check({name: math.nan})
    assert str(err.value) == f"{name} must be finite, got nan"
