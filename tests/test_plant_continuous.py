"""The plant as a host integrates it (Model Exchange): derivatives, exact directional derivatives, events.

The Python model is the specification the native Model Exchange plant is held equal to; here it is
checked against the co-simulation's own functions, central differences, the linearisation and a
host of our own (scipy's DOP853 with event location, :func:`crane_fmu.analysis.reference.model_exchange`).
"""

import math

import numpy as np
import pytest
from helpers import continuous_plant_cases

from crane_fmu.analysis.reference import model_exchange
from crane_fmu.model import plant
from crane_fmu.model import plant_continuous as me
from crane_fmu.model.plant_continuous import FREE, Mode

COMPONENT = plant.COMPONENT
N, M = len(me.STATES), len(me.INPUTS)


def _central(f, x, k, h):
    up, down = list(x), list(x)
    up[k] += h
    down[k] -= h
    return (np.array(f(tuple(up))) - np.array(f(tuple(down)))) / (2 * h)


def test_directional_derivatives_equal_central_differences():
    """Every column of the Jacobians against central differences of the values themselves.

    Central differences at h = 1e-5 are exact to h^2 |f'''| / 6 (about 1e-10 relative here) plus the
    rounding eps |f| / h (about 1e-11): 1e-7 of the column's scale catches any wrong or missing term,
    which is of the order of the column itself.
    """
    for case in continuous_plant_cases():
        _check_columns(*case, h=1e-5)


def _check_columns(config, state, inputs, mode, h):
    a, b, c, d = (np.array(m) for m in me.jacobians(config, state, inputs, mode))

    def close(got, fd):
        assert got == pytest.approx(fd, rel=1e-7, abs=1e-7 * (1 + np.abs(fd).max())), mode

    for k in range(N):
        close(a[:, k], _central(lambda s: me.derivatives(config, s, inputs, mode), state, k, h))
        close(c[:, k], _central(lambda s: me.output_values(config, s, inputs, mode), state, k, h))
    for k in range(M):
        if k == 0 and abs(abs(inputs[0]) - config.u_max) < 2 * h:
            continue  # the drive's limit is a kink in u
        close(b[:, k], _central(lambda i: me.derivatives(config, state, i, mode), inputs, k, h))
        close(d[:, k], _central(lambda i: me.output_values(config, state, i, mode), inputs, k, h))


def test_derivatives_are_the_function_the_co_simulation_rk4_calls():
    """Free of limits, the derivatives are plant.derivative's (which RK4 calls), bit for bit."""
    for config, state, inputs, _ in continuous_plant_cases():
        if config.tau > 0 or config.u_max < math.inf:
            continue
        u, hoist, f1, f2 = inputs
        got = me.derivatives(config, state, inputs, FREE)
        want = plant.derivative(state[:8], u, config.params, hoist, (f1, f2, *config.damping))
        assert got[:8] == want


def test_limits_held_in_the_derivatives():
    config = COMPONENT.check({"tau": 0.5})
    state = (0.0, 0.3, 0.1, 0.2, -0.1, 0.0, 1.2, 0.4, 0.8)
    free = me.derivatives(config, state, (2.0, 1.0, 0.0, 0.0), FREE)
    assert free[1] == 0.8 and free[8] == pytest.approx((2.0 - 0.8) / 0.5)  # the lag: x'' is the drive's output
    assert free[6:8] == (0.4, 1.0)
    held = me.derivatives(config, state[:7] + (0.0, 0.8), (2.0, 1.0, 0.0, 0.0), Mode(1, 1, 0))
    assert held[1] == 0.0 and held[6:8] == (0.0, 0.0) and held[8] == free[8]
    assert me.derivatives(config, state, (2.0, 1.0, 0.0, 0.0), Mode(0, 0, 1))[6:8] == (0.4, 0.0)


def test_jacobian_at_rest_is_the_linearisation():
    """The swing rows of A and B at the hanging equilibrium are -W and -w of plant_equations.linearisation."""
    for values in ({}, {"m1": 2.0, "m2": 0.5, "l1": 2.5, "l2": 0.8, "g": 9.81}):
        config = COMPONENT.check({**values, "theta1_0": 0.0})
        a, b, _, _ = me.jacobians(config, me.initial(config), (0.0, 0.0, 0.0, 0.0), FREE)
        big_w, small_w = plant.linearisation(config.params)
        rows, cols = (3, 5), (2, 4)
        for i in range(2):
            assert [a[rows[i]][j] for j in cols] == pytest.approx([-v for v in big_w[i]], rel=1e-12)
            assert b[rows[i]][0] == pytest.approx(-small_w[i], abs=1e-12)
        assert a[0][1] == a[2][3] == a[4][5] == 1.0 and b[1][0] == 1.0


def test_event_indicators_watch_the_limits():
    config = COMPONENT.check({"x_min": -1.0, "x_max": 2.0, "v_max": 0.5, "l1_min": 0.5, "l1_max": 1.5,
                              "dl1_max": 0.3})
    state = (0.5, 0.2, 0.0, 0.0, 0.0, 0.0, 1.2, -0.1, 0.0)
    z = me.event_indicators(config, state, (1.0, -0.4, 0.0, 0.0), FREE)
    assert z == pytest.approx((1.5, 1.5, 0.7, 0.3, 0.7, 0.3, 0.2, 0.4))
    held = me.event_indicators(config, state, (1.0, -0.4, 0.0, 0.0), Mode(1, -1, 0))
    assert held[3] == 1.0 and held[4] == 0.4  # the pressing accelerations
    no_limits = me.event_indicators(COMPONENT.check({}), state, (1.0, 0.0, 0.0, 0.0), FREE)
    assert no_limits == (1.0,) * 4 + (1.2,) + (1.0,) * 3  # l1_min = 0 stays a limit: a cable of no length


def test_event_updates_hold_release_and_end():
    config = COMPONENT.check({"x_max": 2.0, "v_max": 0.5, "l1_max": 1.5})
    at_speed = (0.5, 0.5000001, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    event = me.event_update(config, at_speed, (1.0, 0.0, 0.0, 0.0), FREE, 1.0)
    assert event.mode == Mode(1, 0, 0) and event.state[1] == 0.5 and event.terminate is None
    assert me.event_update(config, event.state, (-1.0, 0.0, 0.0, 0.0), event.mode, 2.0).mode == FREE
    at_cable = (0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.5000001, 0.2, 0.0)
    event = me.event_update(config, at_cable, (0.0, 0.1, 0.0, 0.0), FREE, 3.0)
    assert event.mode == Mode(0, 1, 0) and event.state[6:8] == (1.5, 0.0)
    assert event.messages == ["hoist: l1 hit the limit 1.5 m at 0.2 m/s at t = 3.0 s and is held there"]
    at_end = (2.0, 0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    assert "rail end x_max = 2.0 m" in me.event_update(config, at_end, (0.0,) * 4, FREE, 4.0).terminate
    leaving = (2.0, -0.1, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    assert me.event_update(config, leaving, (0.0,) * 4, FREE, 4.0).terminate is None


TIMES = np.arange(2001) * 1e-3  # 2 s at the co-simulation's 1 ms


def _co_simulation(values, inputs, n):
    config = COMPONENT.check(values)
    state, rows = config.state0, [config.state0]
    for k in range(n):
        state = plant.update(config, state, inputs, k * 1e-3, 1e-3)
        state = state.state if isinstance(state, plant.Step) else state
        rows.append(state)
    return np.array(rows)


@pytest.mark.parametrize("values, inputs", [
    ({}, (0.0, 0.0, 0.0, 0.0)),  # Section V's free swing
    ({"theta1_0": 0.05}, (0.5, 0.3, 2.0, -1.0)),  # hoisting while the trolley moves, with forces
    ({"c1": 0.5, "c2": 0.2, "tau": 0.2}, (1.0, 0.0, 0.0, 0.0)),  # damping and a drive lag
])
def test_integrated_by_a_host_it_is_the_co_simulation_plant(values, inputs):
    """DOP853 at rtol 1e-10 on the derivatives against the co-simulation's RK4 at 1 ms: RK4's error over
    2 s is about 1e-9 rad (its step's (w h)^5 with w up to 7 rad/s); 1e-6 rad is the issue's bound for hosts."""
    states, _, events = model_exchange(COMPONENT, values, inputs, TIMES)
    cosim = _co_simulation(values, inputs, len(TIMES) - 1)
    assert not events
    assert np.abs(states[:, 2:6:2] - cosim[:, 2:6:2]).max() < 1e-6
    assert np.abs(states[:, 6:8] - cosim[:, 6:8]).max() < 1e-9  # the cable: exact in both


def test_a_host_stops_at_the_rail_end_when_the_trolley_reaches_it():
    """x = x0 + u t^2 / 2 reaches x_max = 0.5 m at t = 1 s exactly (u = 1 m/s2 from rest)."""
    states, _, events = model_exchange(COMPONENT, {"x_max": 0.5}, (1.0, 0.0, 0.0, 0.0), TIMES)
    (time, event), = events
    assert time == pytest.approx(1.0, abs=1e-9)
    assert event.terminate.startswith("the trolley reached the rail end x_max = 0.5 m")
    assert len(states) == 1001  # up to 1 s


def test_a_host_stops_at_the_cable_limit_and_the_cable_stays_there():
    """l1 = 1 + 0.4 t^2 / 2 reaches l1_max = 1.2 m at t = 1 s; held at rest there while the hoist pushes."""
    states, outputs, events = model_exchange(COMPONENT, {"l1_max": 1.2}, (0.0, 0.4, 0.0, 0.0), TIMES)
    (time, event), = events
    assert time == pytest.approx(1.0, abs=1e-9)
    assert event.mode.cable == 1
    assert np.all(states[1001:, 6] == 1.2) and np.all(states[1001:, 7] == 0.0)
    assert outputs[-1, -1] == 0.0 and np.all(np.isfinite(outputs))


def test_a_host_stops_at_the_speed_limit_and_the_speed_stays_there():
    """dx = u t reaches v_max = 0.5 m/s at t = 0.5 s; then the trolley moves at v_max."""
    states, _, events = model_exchange(COMPONENT, {"v_max": 0.5}, (1.0, 0.0, 0.0, 0.0), TIMES)
    (time, event), = events
    assert time == pytest.approx(0.5, abs=1e-9) and event.mode.speed == 1
    assert np.all(states[501:, 1] == 0.5)
    assert states[-1, 0] == pytest.approx(0.125 + 0.5 * 1.5, abs=1e-9)


@pytest.mark.parametrize("u, lift", [(-0.7, 0.4), (0.6, -0.3)])
def test_a_held_limits_indicator_is_the_acceleration_pressing_into_it_at_both_ends(u, lift):
    """Every held limit, lower and upper, of the trolley's speed, the cable's length and the cable's speed (issue
    50, item 7: one sign of these was turned and a single test saw it): its indicator is the demand pressing into
    the limit, positive while it presses and negative once it pulls away (the event that releases it): at the
    lower limit -demand, at the upper +demand (the trolley's demand u, the hoist's acceleration)."""
    config = COMPONENT.check({"x_min": -1.0, "x_max": 2.0, "v_max": 0.5, "l1_min": 0.5, "l1_max": 1.5,
                              "dl1_max": 0.3})
    state = (0.5, 0.2, 0.0, 0.0, 0.0, 0.0, 1.2, -0.1, 0.0)
    inputs = (u, lift, 0.0, 0.0)
    expected = {"-v_max": -u, "v_max": u, "l1_min": -lift, "l1_max": lift, "-dl1_max": -lift, "dl1_max": lift}
    position = {name: i for i, name in enumerate(me.INDICATORS)}
    for field, (lower, upper) in (("speed", ("-v_max", "v_max")), ("cable", ("l1_min", "l1_max")),
                                  ("hoist", ("-dl1_max", "dl1_max"))):
        for held, name in ((-1, lower), (1, upper)):
            z = me.event_indicators(config, state, inputs, FREE._replace(**{field: held}))
            assert z[position[name]] == pytest.approx(expected[name], rel=1e-12), (field, held, name)
