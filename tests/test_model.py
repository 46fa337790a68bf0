"""The runtime core: parameters, integrator, control law (no FMUs)."""

import math
import random

import numpy as np
import pytest

from crane_fmu.model import backstepping as controller
from crane_fmu.model import plant, tables
from crane_fmu.model.parameters import ControllerGains, PlantParameters

pytestmark = pytest.mark.quick  # no build: in the quick subset


@pytest.mark.parametrize("field, value, rule", [
    ("l1", -1.0, "l1 must be > 0 and finite, got -1.0"),
    ("l1", 0.0, "l1 must be > 0 and finite, got 0.0"),
    ("m1", 0.0, "m1 must be > 0 and finite, got 0.0"),
    ("m2", -0.5, "m2 must be >= 0 and finite, got -0.5"),
    ("g", math.inf, "g must be > 0 and finite, got inf"),
    ("l2", math.nan, "l2 must be > 0 and finite, got nan"),
])
def test_plant_parameters_name_the_field_and_the_rule(field, value, rule):
    with pytest.raises(ValueError) as err:
        PlantParameters(**{field: value})
    assert str(err.value) == rule


@pytest.mark.parametrize("kwargs, message", [
    ({"K1_x": math.nan}, "K1_x must be finite, got nan"),
    ({"w_theta2": -1.0}, "w_theta2 must be >= 0 and finite, got -1.0"),
    ({"w_x": 0.0}, "w_x must be > 0"),
    ({"b3_form": "guessed"}, "b3_form must be one of derived, printed, got 'guessed'"),
])
def test_controller_gains_reject_bad_values(kwargs, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        ControllerGains(**kwargs)


def test_defaults_are_the_papers_section_v_values():
    assert PlantParameters() == PlantParameters(m1=3.0, m2=7.0, l1=1.0, l2=0.5, g=9.8)
    k = ControllerGains()
    assert (k.K1_x, k.K1_theta1, k.K1_theta2) == (0.92, 4.0, 122.0)
    assert (k.K2_x, k.K2_theta1, k.K2_theta2) == (0.84, 2.0, 310.0)
    assert plant.COMPONENT.defaults()["theta1_0"] == math.pi / 18


def test_plant_output_names_match_the_model_order():
    """plant_equations.outputs gives the state, the positions and the energy; the FMU's outputs start with them."""
    names = tables.STATE + ("x1", "y1", "x2", "y2", "energy")
    assert plant.COMPONENT.names("output")[:len(names)] == names
    assert len(plant.outputs((0.0,) * 6, PlantParameters())) == len(names)


@pytest.mark.parametrize("step, max_substep, n", [(1e-3, 1e-3, 1), (0.01, 1e-3, 10), (0.0105, 1e-3, 11),
                                                  (1e-4, 1e-3, 1), (0.1, 0.03, 4)])
def test_substeps_never_exceed_max_substep(step, max_substep, n):
    assert plant.substeps(step, max_substep) == n
    assert step / n <= max_substep * (1 + 1e-9)


def test_rk4_is_fourth_order():
    """Halving dt divides the one-step error by about 2^5 = 32 (local error O(dt^5))."""
    p = PlantParameters()
    s0 = (0.0, 0.0, 0.6, 0.5, -0.3, 1.0)

    def error(dt):
        fine = s0
        for _ in range(64):
            fine = plant.rk4_step(fine, 2.0, dt / 64, p)
        return max(abs(a - b) for a, b in zip(plant.rk4_step(s0, 2.0, dt, p), fine))

    ratio = error(0.02) / error(0.01)
    assert 25 < ratio < 40


def test_trolley_motion_is_exact_under_held_acceleration():
    p = PlantParameters()
    s = plant.advance((0.5, 0.2, 0.1, 0.0, 0.0, 0.0), 3.0, 0.5, 1e-3, p)
    assert s[0] == pytest.approx(0.5 + 0.2 * 0.5 + 0.5 * 3.0 * 0.25, rel=1e-12)
    assert s[1] == pytest.approx(0.2 + 3.0 * 0.5, rel=1e-12)


def test_control_law_equals_least_squares_of_eq_20():
    """The least-squares step of eq (21) (and its weighted form), solved with numpy from the code's f and b
    (which tests/test_equations.py checks against the symbolic derivation)."""
    rng = random.Random(7)
    p = PlantParameters()
    for _ in range(50):
        k = ControllerGains(w_x=rng.uniform(0.1, 2), w_theta1=rng.uniform(0, 2), w_theta2=rng.uniform(0, 2),
                            x_d=rng.uniform(-1, 1), b3_form=rng.choice(["derived", "printed"]))
        state = [rng.uniform(-1, 1) for _ in range(6)]
        f, b = (np.array(v) for v in controller.drift_and_input_gain(*state[2:], p, k.b3_form))
        e1 = np.array([state[0] - k.x_d, state[2] - k.theta1_d, state[4] - k.theta2_d])
        e2 = np.array([state[1], state[3], state[5]])
        K1 = np.diag([k.K1_x, k.K1_theta1, k.K1_theta2])
        K2 = np.diag([k.K2_x, k.K2_theta1, k.K2_theta2])
        e3d = -K1 @ e2 - K2 @ (e2 + K1 @ e1)  # eqs (18)-(20)
        sw = np.sqrt([k.w_x, k.w_theta1, k.w_theta2])
        expected = np.linalg.lstsq((sw * b)[:, None], sw * (e3d - f), rcond=None)[0][0]
        assert controller.control(state, p, k) == pytest.approx(expected, rel=1e-10, abs=1e-10)


def test_only_the_trolley_row_gives_a_pd_law_on_x():
    """With the swing rows weighted 0, eq (21) reduces to u = e3d_x (a PD law on x)."""
    p = PlantParameters()
    k = ControllerGains(w_theta1=0.0, w_theta2=0.0)
    state = (0.3, -0.2, 0.1, 0.4, -0.2, 0.3)
    expected = -k.K1_x * -0.2 - k.K2_x * (-0.2 + k.K1_x * 0.3)
    assert controller.control(state, p, k) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("step, max_substep, message", [
    (0.0, 1e-3, "communication step must be > 0 and finite, got 0.0"),
    (-0.1, 1e-3, "communication step must be > 0 and finite, got -0.1"),
    (math.nan, 1e-3, "communication step must be > 0 and finite, got nan"),
    (1e300, 1e-3, "needs more than 10000000 RK4 sub-steps"),
    (1.0, 1e-300, "needs more than 10000000 RK4 sub-steps"),
])
def test_unusable_step_sizes_are_refused(step, max_substep, message):
    with pytest.raises(ValueError, match=message):
        plant.substeps(step, max_substep)


def _random_plant(rng):
    return PlantParameters(m1=rng.uniform(0.1, 5), m2=rng.uniform(0, 5), l1=rng.uniform(0.2, 3),
                           l2=rng.uniform(0.1, 2), g=rng.uniform(1, 20))


def test_the_fast_paths_compute_the_same_numbers_as_the_equations():
    """The FMUs' hot path (constants computed once) and the readable eqs (8)-(9), (12)-(21): bit for bit."""
    rng = random.Random(7)
    for _ in range(3000):
        p = _random_plant(rng)
        k = ControllerGains(**{name: rng.uniform(0, 5) for name in ("K1_x", "K2_x", "K1_theta1", "K2_theta1",
                                                                    "K1_theta2", "K2_theta2", "w_x", "w_theta1",
                                                                    "w_theta2")},
                            x_d=rng.uniform(-2, 2), theta1_d=rng.uniform(-0.1, 0.1),
                            b3_form=rng.choice(["derived", "printed"]))
        state = tuple(rng.uniform(-1.5, 1.5) for _ in range(6))
        assert controller.law(p, k)(state) == controller.control(state, p, k)
        u, dt, big_l = rng.uniform(-3, 3), rng.choice([1e-3, 0.01, 0.05]), rng.uniform(0.2, 3)
        swing = state + (big_l, 0.0)
        assert plant.paper_stepper(p)(swing, u, dt) == plant.rk4_step(swing, u, dt, p)


def test_the_plants_fast_step_equals_its_general_step():
    """update() of the paper's model (no hoist, forces, damping, lag, limits) against the general path."""
    values = {v.name: v.start for v in plant.VARIABLES if v.causality == "parameter"}
    config = plant.configure({**values, "theta1_0": 0.3, "dtheta2_0": -0.2, "u_max": 2.5})
    assert config.fast
    state_fast = state_general = config.state0
    for k in range(300):
        inputs = (3.0 * math.sin(0.05 * k), 0.0, 0.0, 0.0)
        state_fast = plant.fast_update(config, state_fast, inputs[0], k * 0.01, 0.01)
        state_general = plant.general_update(config, state_general, inputs, k * 0.01, 0.01)
        assert state_fast == state_general


@pytest.mark.parametrize("name, value", [("c1", 0.1), ("c2", 0.1), ("tau", 0.05), ("v_max", 0.5)])
def test_any_effect_away_from_its_neutral_value_leaves_the_fast_path(name, value):
    """The fast path is chosen from the parameters themselves: an effect cannot be skipped."""
    values = {v.name: v.start for v in plant.VARIABLES if v.causality == "parameter"}
    assert plant.configure(values).fast and not plant.configure({**values, name: value}).fast


def test_the_fast_step_tells_huge_finite_states_from_non_finite_ones():
    """Its finite check sums the state first: a sum that overflows must not discard a finite step."""
    from crane_fmu.model.component import Discard

    values = {v.name: v.start for v in plant.VARIABLES if v.causality == "parameter"}
    config = plant.configure(values)
    huge = (1e308, 0.0, 1e308, 0.0, 0.0, 0.0) + config.state0[6:]  # x and theta1 sum to inf
    assert config.fast and math.isinf(sum(huge[:8]))
    state = plant.update(config, huge, (0.0, 0.0, 0.0, 0.0), 0.0, 1e-3)
    assert state[0] == 1e308 and all(map(math.isfinite, state))
    with pytest.raises(Discard, match="plant state became non-finite"):
        plant.update(config, (0.0, math.inf) + huge[2:], (0.0, 0.0, 0.0, 0.0), 0.0, 1e-3)
