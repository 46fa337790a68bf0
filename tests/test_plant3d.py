"""The spatial crane (CranePlant3D) against what is known of it: the planar crane in the plane, conservation of energy
and of the vertical angular momentum, symmetry under a rotation about the vertical, Airy's precession of an elliptic
swing, the linearisation at rest. The Python model in process (the FMUs: test_plant3d_fmus.py)."""

import math
import random

import numpy as np
import pytest
from helpers import spatial_plant_cases as cases

from crane_fmu.model import plant, plant3d
from crane_fmu.model import plant3d_continuous as me3
from crane_fmu.model import plant3d_equations as eq3
from crane_fmu.model import plant_continuous as me2
from crane_fmu.model.component import Discard, Step

COMPONENT = plant3d.COMPONENT
quick = pytest.mark.quick


def _run(values, inputs, seconds, h=1e-3, component=COMPONENT, every=1):
    """The states of an in-process run with ``inputs(k)`` held over step k (every ``every``-th state kept)."""
    config = component.check(values)
    state, states = config.state0, [config.state0]
    for k in range(round(seconds / h)):
        state = component.update(config, state, inputs(k), k * h, h)
        state = state.state if isinstance(state, Step) else state
        if (k + 1) % every == 0:
            states.append(state)
    return config, np.array(states)


# --- the planar crane in the plane ---------------------------------------------------------------------------------

PLANAR_TO_SPATIAL = {"u_max": "ux_max", "v_max": "vx_max", "tau": "tau_x", "x_min": "x_min", "x_max": "x_max",
                     "x0": "x0", "dx0": "dx0", "theta1_0": "theta1x_0", "dtheta1_0": "dtheta1x_0",
                     "theta2_0": "theta2x_0", "dtheta2_0": "dtheta2x_0"}
PLANAR_STATE = [plant3d.SWING_STATE.index(n) for n in ("x", "dx", "theta1x", "dtheta1x", "theta2x", "dtheta2x")]


def spatial_values(planar):
    """The CranePlant3D's parameters for a CranePlant's: the planar axis is x."""
    return {PLANAR_TO_SPATIAL.get(name, name): value for name, value in planar.items()}


def _planar_inputs(u, hoist, f1, f2):
    return (u, 0.0, hoist, f1, 0.0, f2, 0.0)


@quick
@pytest.mark.parametrize("values", [
    {},
    {"tau": 0.2, "v_max": 0.5, "u_max": 1.5, "c1": 0.5, "c2": 0.2, "theta2_0": -0.1, "dtheta1_0": 0.3},
    {"l1": 2.0, "l1_min": 1.0, "l1_max": 2.0, "dl1_max": 0.5, "m2": 0.0, "theta1_0": 0.6},
])
def test_without_y_it_is_the_planar_crane_in_process(values):
    """Every effect of the planar plant (drive lag and limits, damping, forces, hoisting to a limit) with a varying
    input: the same states to 1e-12 over 3 s (the whole-run check on the built-in systems: test_plant3d_fmus.py)."""
    rng = random.Random(3)
    hoisting = "l1_min" in values
    table = [(rng.uniform(-2, 2), rng.uniform(-0.6, 0.2) if hoisting else 0.0, rng.uniform(-5, 5),
              0.0 if values.get("m2") == 0.0 else rng.uniform(-5, 5)) for _ in range(30)]
    planar = lambda k: table[k // 100]  # noqa: E731
    _, want = _run(values, planar, 3.0, component=plant.COMPONENT)
    _, got = _run(spatial_values(values), lambda k: _planar_inputs(*planar(k)), 3.0)
    assert np.abs(got[:, PLANAR_STATE] - want[:, :6]).max() < 1e-12
    assert np.abs(got[:, [eq3.L1, eq3.DL1]] - want[:, [6, 7]]).max() < 1e-12
    assert not got[:, [eq3.Y, eq3.DY, eq3.B1, eq3.DB1, eq3.B2, eq3.DB2]].any()  # exactly in the plane


# --- conservation ----------------------------------------------------------------------------------------------------

def _rk4_drift_bound(config, seconds, h):
    """What RK4's order allows a conserved quantity to drift, relative to its scale, over ``seconds`` at step ``h``.

    RK4's local error on an oscillation of frequency w is (h w)^5 / 120 of its amplitude (the first term its Taylor
    series leaves out); a conserved quantity quadratic in the state moves by at most twice that per step, relative:
    over N = T / h steps at most T w (h w)^4 / 60. The fastest motion is the double pendulum's fast mode (from the
    linearisation, at rest: the frequencies fall with amplitude).
    """
    big_w, _ = plant.linearisation(config.params)
    trace, det = big_w[0][0] + big_w[1][1], big_w[0][0] * big_w[1][1] - big_w[0][1] * big_w[1][0]
    w = math.sqrt((trace + math.sqrt(trace * trace - 4 * det)) / 2)
    return seconds * w * (h * w) ** 4 / 60


def _kinematics(state, p):
    """Positions relative to the trolley and velocities of hook and load, written out here from (S1)."""
    x, dx, y, dy, a1, da1, b1, db1, a2, da2, b2, db2, length, rate = state[:14]

    def direction(a, da, b, db):
        e = np.array([math.sin(a) * math.cos(b), math.sin(b), -math.cos(a) * math.cos(b)])
        de = np.array([math.cos(a) * math.cos(b) * da - math.sin(a) * math.sin(b) * db, math.cos(b) * db,
                       math.sin(a) * math.cos(b) * da + math.cos(a) * math.sin(b) * db])
        return e, de

    (e1, de1), (e2, de2) = direction(a1, da1, b1, db1), direction(a2, da2, b2, db2)
    rho1, rho2 = length * e1, length * e1 + p.l2 * e2
    v1 = np.array([dx, dy, 0.0]) + rate * e1 + length * de1
    return rho1, rho2, v1, v1 + p.l2 * de2


def _vertical_angular_momentum(state, p):
    """About the trolley's vertical axis: sum of m (rho x v)_z."""
    rho1, rho2, v1, v2 = _kinematics(state, p)
    return p.m1 * (rho1[0] * v1[1] - rho1[1] * v1[0]) + p.m2 * (rho2[0] * v2[1] - rho2[1] * v2[0])


ELLIPTIC = {"theta1x_0": 0.5, "theta1y_0": 0.0, "dtheta1y_0": 1.2, "theta2x_0": -0.3, "theta2y_0": 0.4,
            "dtheta2x_0": 0.8, "dtheta2y_0": -1.0}  # a large spatial swing, both cables moving out of the plane


def test_energy_and_vertical_angular_momentum_are_conserved_with_the_trolley_held():
    """100 s at h = 1 ms of a large spatial swing, nothing acting: both within RK4's bound (and the trolley's held,
    the vertical angular momentum about it conserved: gravity and the cables pull in planes through that axis)."""
    config, states = _run(ELLIPTIC, lambda k: (0.0,) * 7, 100.0, every=100)
    p, bound = config.params, _rk4_drift_bound(config, 100.0, 1e-3)
    energy = np.array([eq3.outputs(s, p)[-1] for s in states])
    rest = eq3.outputs(COMPONENT.check({"theta1x_0": 0.0}).state0, p)[-1]
    assert np.abs(energy - energy[0]).max() <= bound * (energy[0] - rest)
    momentum = np.array([_vertical_angular_momentum(s, p) for s in states])
    rho1, rho2, v1, v2 = _kinematics(states[0], p)
    scale = p.m1 * np.linalg.norm(rho1) * np.linalg.norm(v1) + p.m2 * np.linalg.norm(rho2) * np.linalg.norm(v2)
    assert abs(momentum[0]) > 0.1 * scale  # a swing with angular momentum to keep
    assert np.abs(momentum - momentum[0]).max() <= bound * scale


@quick
def test_hoisting_keeps_the_vertical_angular_momentum():
    """The hoist pulls along the cable, through the trolley's axis: no torque about it (energy is not kept)."""
    config, states = _run({**ELLIPTIC, "l1": 1.5}, lambda k: (0.0, 0.0, -0.4 if k < 1000 else 0.4, 0, 0, 0, 0), 2.0)
    momentum = [_vertical_angular_momentum(s, config.params) for s in states]
    assert states[-1][eq3.L1] < 1.5 and np.ptp(momentum) < 1e-9 * abs(momentum[0])


# --- symmetry --------------------------------------------------------------------------------------------------------

def _angles_of(e, de):
    """``(a, da, b, db)`` of a cable direction ``e`` moving at ``de``: the inverse of (S1)-(S2)."""
    a, b = math.atan2(e[0], -e[2]), math.asin(e[1])
    u = (math.cos(a), 0.0, math.sin(a))
    v = (-math.sin(a) * math.sin(b), math.cos(b), math.cos(a) * math.sin(b))
    return a, float(np.dot(de, u)) / math.cos(b), b, float(np.dot(de, v))


def _rotated_start(values, p):
    """The start values turned by 90 degrees about the vertical: (x, y) -> (-y, x)."""
    config = COMPONENT.check(values)
    s = config.state0
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    _, _, _, _ = _kinematics(s, p)
    cables = []
    for a, b in ((eq3.A1, eq3.B1), (eq3.A2, eq3.B2)):
        e = np.array([math.sin(s[a]) * math.cos(s[b]), math.sin(s[b]), -math.cos(s[a]) * math.cos(s[b])])
        de = np.array([math.cos(s[a]) * math.cos(s[b]) * s[a + 1] - math.sin(s[a]) * math.sin(s[b]) * s[b + 1],
                       math.cos(s[b]) * s[b + 1],
                       math.sin(s[a]) * math.cos(s[b]) * s[a + 1] + math.cos(s[a]) * math.sin(s[b]) * s[b + 1]])
        cables.append(_angles_of(turn @ e, turn @ de))
    names = ("theta1x_0", "dtheta1x_0", "theta1y_0", "dtheta1y_0", "theta2x_0", "dtheta2x_0", "theta2y_0",
             "dtheta2y_0")
    return {**values, "x0": -s[eq3.Y], "y0": s[eq3.X], "dx0": -s[eq3.DY], "dy0": s[eq3.DX],
            **dict(zip(names, cables[0] + cables[1]))}


@quick
def test_a_rotation_of_inputs_and_start_by_90_degrees_rotates_the_motion():
    """Hook and load positions of the turned run are those of the run turned, for 3 s of varying inputs and forces
    with damping and hoisting (the angles are not: (S1) is not symmetric in x and y; the motion is)."""
    values = {"theta1x_0": 0.3, "theta1y_0": -0.2, "dtheta1y_0": 0.5, "theta2x_0": 0.1, "dtheta2y_0": 0.4,
              "dx0": 0.2, "y0": 0.5, "c1": 0.3, "c2": 0.1, "l1": 1.5}
    p = COMPONENT.check(values).params
    rng = random.Random(5)
    table = [tuple(rng.uniform(-3, 3) for _ in range(2)) + (rng.uniform(-0.3, 0.3),)
             + tuple(rng.uniform(-10, 10) for _ in range(4)) for _ in range(30)]

    def turned(k):
        ux, uy, hoist, f1x, f1y, f2x, f2y = table[k // 100]
        return (-uy, ux, hoist, -f1y, f1x, -f2y, f2x)

    config, first = _run(values, lambda k: table[k // 100], 3.0)
    _, second = _run(_rotated_start(values, p), turned, 3.0)
    out_first = np.array([eq3.outputs(s, p)[:6] for s in first])
    out_second = np.array([eq3.outputs(s, p)[:6] for s in second])
    turn = lambda r: np.stack([-r[:, 1], r[:, 0], r[:, 2]], axis=1)  # noqa: E731
    for hook_or_load in (slice(0, 3), slice(3, 6)):
        assert np.abs(out_second[:, hook_or_load] - turn(out_first[:, hook_or_load])).max() < 1e-9
    assert np.abs(out_first[:, 3:6] - out_first[0, 3:6]).max() > 0.5  # it moved


# --- Airy's precession -----------------------------------------------------------------------------------------------

def test_a_small_elliptic_swing_precesses_at_airys_rate():
    """The single-pendulum limit (m2 = 0: the hook alone, a spherical pendulum of length l1): an ellipse of semi-axes
    A, B turns at (3/8) w A B / l1^2, w = sqrt(g / l1) (Airy); the next term is of relative order (A^2 + B^2) / l1^2
    (here 1.3 %): within 3 %. Its sense is the swing's."""
    length, big_a, big_b = 1.0, 0.1, 0.05
    w = math.sqrt(9.8 / length)
    values = {"m2": 0.0, "l1": length, "theta1x_0": math.asin(big_a / length), "dtheta1y_0": big_b * w / length}
    config, states = _run(values, lambda k: (0.0,) * 7, 60.0)
    hook = np.array([eq3.outputs(s, config.params)[:2] for s in states])  # the trolley stays at 0
    r2 = (hook ** 2).sum(axis=1)
    peaks = [k for k in range(1, len(r2) - 1) if r2[k] > r2[k - 1] and r2[k] >= r2[k + 1]]
    # the apsides: the far ends of the ellipse, half a period apart, at the angle of the major axis (mod pi)
    times, angles = [], []
    for k in peaks:
        shift = 0.5 * (r2[k - 1] - r2[k + 1]) / (r2[k - 1] - 2 * r2[k] + r2[k + 1])  # the parabola's vertex
        times.append((k + shift) * 1e-3)
        angles.append(math.atan2(*hook[k][::-1]) % math.pi)
    angles = np.unwrap(np.array(angles) * 2) / 2
    rate = np.polyfit(times, angles, 1)[0]
    airy = 3 / 8 * w * big_a * big_b / length ** 2
    assert len(peaks) > 50 and rate == pytest.approx(airy, rel=0.03)


# --- the linearisation at rest ---------------------------------------------------------------------------------------

@quick
@pytest.mark.parametrize("values", [{}, {"m1": 2.0, "m2": 0.5, "l1": 2.5, "l2": 0.8, "g": 9.81}])
def test_the_jacobian_at_rest_is_two_planar_cranes(values):
    """A and B of the Model Exchange plant at the hanging rest: per axis the planar plant's, no coupling."""
    config3 = COMPONENT.check({**spatial_values(values), "theta1x_0": 0.0})
    config2 = plant.COMPONENT.check({**values, "theta1_0": 0.0})
    a3, b3, _, _ = me3.jacobians(config3, me3.initial(config3), (0.0,) * 7, me3.FREE)
    a2, b2, _, _ = me2.jacobians(config2, me2.initial(config2), (0.0,) * 4, me2.FREE)
    planar = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
    axes = {"x": ("x", "dx", "theta1x", "dtheta1x", "theta2x", "dtheta2x"),
            "y": ("y", "dy", "theta1y", "dtheta1y", "theta2y", "dtheta2y")}
    a3, b3, a2, b2 = map(np.array, (a3, b3, a2, b2))
    index = {name: me3.STATES.index(name) for name in me3.STATES}
    for axis, names in axes.items():
        rows = [index[n] for n in names]
        same = [me2.STATES.index(n) for n in planar]
        assert a3[np.ix_(rows, rows)] == pytest.approx(a2[np.ix_(same, same)], rel=1e-12, abs=1e-12)
        assert b3[rows, me3.INPUTS.index("u" + axis)] == pytest.approx(b2[same, 0], rel=1e-12, abs=1e-12)
        other = [index[n] for n in axes["y" if axis == "x" else "x"]]
        assert not a3[np.ix_(rows, other)].any()
        assert not b3[rows, me3.INPUTS.index("u" + ("y" if axis == "x" else "x"))].any()


@quick
@pytest.mark.parametrize("values", [{}, {"m1": 2.0, "m2": 0.5, "l1": 2.5, "l2": 0.8, "g": 9.81}])
def test_linearised_is_the_exact_jacobian_at_rest(values):
    """plant3d.linearised (two planar cranes, what phase 2's controllers design from) against the Model Exchange
    plant's exact Jacobian at the hanging rest: its swing-state rows and columns, its ux and uy columns."""
    config = COMPONENT.check({**values, "theta1x_0": 0.0})
    a3, b3, _, _ = me3.jacobians(config, me3.initial(config), (0.0,) * 7, me3.FREE)
    rows = [me3.STATES.index(n) for n in plant3d.SWING_STATE]
    a, b = plant3d.linearised(values)
    assert np.array(a3)[np.ix_(rows, rows)] == pytest.approx(np.array(a), rel=1e-12, abs=1e-12)
    assert np.array(b3)[np.ix_(rows, [me3.INPUTS.index("ux"), me3.INPUTS.index("uy")])] == pytest.approx(
        np.array(b), rel=1e-12, abs=1e-12)


# --- the co-simulation's step ----------------------------------------------------------------------------------------

@quick
def test_rail_ends_speed_limits_and_refusals():
    config = COMPONENT.check({"y_max": 0.01, "vy_max": 0.2, "vx_max": 0.3})
    state = config.state0
    for k in range(100):  # along x the speed is held at vx_max
        state = COMPONENT.update(config, state, (5.0, 0.0, 0, 0, 0, 0, 0), k * 1e-3, 1e-3)
    assert state[eq3.DX] == pytest.approx(0.3) and state[plant3d.ACCEL_X] == 0.0
    with pytest.raises(Discard, match=r"rail end y_max = 0.01 m \(y = "):
        for k in range(1000):
            state = COMPONENT.update(config, state, (0.0, 1.0, 0, 0, 0, 0, 0), k * 1e-3, 1e-3)
    with pytest.raises(Discard, match="acts on a load of mass m2 = 0"):
        COMPONENT.update(COMPONENT.check({"m2": 0.0}), config.state0, (0, 0, 0, 0, 0, 0, 1.0), 0.0, 1e-3)
    for bad, message in [({"y_min": 1.0, "y_max": 0.0}, "y_min must be < y_max"),
                         ({"vy_max": 0.0}, r"vy_max must be > 0 \(INF: no limit\), got 0.0"),
                         ({"tau_y": -1.0}, "tau_y must be >= 0 and finite"),
                         ({"y0": 2.0, "y_max": 1.0}, r"y0 must lie on the rail \[-1e\+60, 1.0\], got 2.0"),
                         ({"theta2y_0": math.inf}, "theta2y_0 must be finite")]:
        with pytest.raises(ValueError, match=message):
            COMPONENT.check(bad)


# --- Model Exchange --------------------------------------------------------------------------------------------------

def _central(f, x, k, h):
    up, down = list(x), list(x)
    up[k] += h
    down[k] -= h
    return (np.array(f(tuple(up))) - np.array(f(tuple(down)))) / (2 * h)


@quick
def test_directional_derivatives_equal_central_differences():
    """Every column of the four Jacobians against central differences (h = 1e-5: exact to about 1e-10 relative;
    1e-7 of the column's scale catches any wrong or missing term)."""
    for case in cases(8):
        _check_columns(*case, h=1e-5)


def _check_columns(config, state, inputs, mode, h):
    a, b, c, d = (np.array(m) for m in me3.jacobians(config, state, inputs, mode))

    def close(got, fd):
        assert got == pytest.approx(fd, rel=1e-7, abs=1e-7 * (1 + np.abs(fd).max())), mode

    for k in range(len(me3.STATES)):
        close(a[:, k], _central(lambda s: me3.derivatives(config, s, inputs, mode), state, k, h))
        close(c[:, k], _central(lambda s: me3.output_values(config, s, inputs, mode), state, k, h))
    for k in range(len(me3.INPUTS)):
        if k < 2 and abs(abs(inputs[k]) - (config.x_axis, config.y_axis)[k].u_max) < 2 * h:
            continue  # the drive's limit is a kink
        close(b[:, k], _central(lambda i: me3.derivatives(config, state, i, mode), inputs, k, h))
        close(d[:, k], _central(lambda i: me3.output_values(config, state, i, mode), inputs, k, h))


@quick
def test_derivatives_are_the_function_the_co_simulation_rk4_calls():
    """Free of limits and lags, the derivatives are plant3d_equations.derivative's (which RK4 calls), bit for bit."""
    for config, state, inputs, _ in cases():
        if config.x_axis.tau > 0 or config.y_axis.tau > 0 or config.x_axis.u_max < math.inf \
                or config.y_axis.u_max < math.inf:
            continue
        ux, uy, hoist, *forces = inputs
        got = me3.derivatives(config, state, inputs, me3.FREE)
        assert got[:14] == eq3.derivative(state[:14], ux, uy, config.params, hoist, (*forces, *config.damping))


@quick
def test_event_indicators_and_updates_per_axis():
    config = COMPONENT.check({"x_min": -1.0, "x_max": 2.0, "vx_max": 0.5, "y_min": -0.5, "y_max": 0.5,
                              "vy_max": 0.25, "l1_min": 0.5, "l1_max": 1.5, "dl1_max": 0.3})
    state = (0.5, 0.2, 0.1, -0.05) + (0.0,) * 8 + (1.2, -0.1, 0.0, 0.0)
    z = me3.event_indicators(config, state, (1.0, -1.0, -0.4, 0, 0, 0, 0), me3.FREE)
    assert z == pytest.approx((1.5, 1.5, 0.7, 0.3, 0.6, 0.4, 0.2, 0.3, 0.7, 0.3, 0.2, 0.4))
    held = me3.event_indicators(config, state, (1.0, -1.0, -0.4, 0, 0, 0, 0), me3.Mode(1, -1, 0, 0))
    assert held[3] == 1.0 and held[6] == 1.0  # the pressing accelerations
    at_speed = state[:3] + (-0.2500001,) + state[4:]
    event = me3.event_update(config, at_speed, (0.0, -1.0, 0, 0, 0, 0, 0), me3.FREE, 1.0)
    assert event.mode == me3.Mode(0, -1, 0, 0) and event.state[3] == -0.25 and event.terminate is None
    at_end = state[:2] + (0.5, 0.1) + state[4:]
    assert "rail end y_max = 0.5 m (y = 0.5 m)" in me3.event_update(config, at_end, (0,) * 7, me3.FREE, 2.0).terminate
