"""The floor, our QP solver against daqp, and the MpcController: its plan, its limits, through the FMUs."""

import math

import daqp
import numpy as np
import pytest
from helpers import mpc_loop, random_qp

from crane_fmu import systems
from crane_fmu.analysis import controller_targets, floor, metrics, scenarios
from crane_fmu.analysis import planar_scenarios as planar
from crane_fmu.cosim import ArrayRecorder, run
from crane_fmu.model import mpc, qp
from crane_fmu.model.parameters import PlantParameters

TEN_DEG = math.radians(10.0)


# --- the floor ----------------------------------------------------------------------------------


@pytest.mark.parametrize("distance, u_max, v_max", [(2.0, 2.0, 1.0), (1.0, 1.0, 0.5), (0.25, 2.0, 1.0)])
def test_a_rigid_loads_floor_is_the_bang_coast_bang_move(distance, u_max, v_max):
    """d/v + v/a when the drive reaches full speed, 2 sqrt(d/a) when it does not; on the 10 ms grid the least
    multiple of 10 ms at or above it (the first two are multiples)."""
    exact = distance / v_max + v_max / u_max if distance > v_max ** 2 / u_max else 2 * math.sqrt(distance / u_max)
    assert floor.rigid_floor(distance, u_max, v_max) == pytest.approx(math.ceil(exact / floor.GRID - 1e-9)
                                                                      * floor.GRID, abs=1e-9)


def test_the_cranes_floors_are_the_known_answers():
    """The issue's table: 2 m rest to rest 2.70 s (rigid 2.50 s); from theta1 = 10 deg to rest 2.02 s, with the
    trolley free to stop anywhere 1.72 s (linearised crane, 10 ms hold, |u| <= 2 m/s2, |v| <= 1 m/s)."""
    assert floor.crane_floor(target=(2.0, 0, 0, 0, 0, 0)) == pytest.approx(2.70, abs=1e-9)
    assert floor.crane_floor(start=(0, 0, TEN_DEG, 0, 0, 0)) == pytest.approx(2.02, abs=1e-9)
    assert floor.crane_floor(start=(0, 0, TEN_DEG, 0, 0, 0), free=(0,)) == pytest.approx(1.72, abs=1e-9)


def test_a_floor_is_never_below_the_trolleys_own_move():
    """The crane's trolley is the rigid load plus the swing's constraints: its floor is at least the rigid one."""
    assert floor.crane_floor(target=(1.0, 0, 0, 0, 0, 0), u_max=1.0, v_max=0.5) >= floor.rigid_floor(1.0, 1.0, 0.5)


def _linear_crane_from_sympy(p):
    """``(A, B)`` of the crane about rest, s = (x, dx, theta1, dtheta1, theta2, dtheta2), from the Jacobian of the
    angular accelerations that sympy derives from the Lagrangian (tests/derivation.py), not from the code's model."""
    import sympy
    from derivation import SOLUTION, a1, a2, dd1, dd2, g, l1, l2, m1, m2, u, w1, w2

    rest = {a1: 0, w1: 0, a2: 0, w2: 0, u: 0}
    values = {m1: p.m1, m2: p.m2, l1: p.l1, l2: p.l2, g: p.g}
    a, b = np.zeros((6, 6)), np.zeros(6)
    a[0, 1] = a[2, 3] = a[4, 5] = b[1] = 1.0
    for row, dd in ((3, dd1), (5, dd2)):
        expression = SOLUTION[dd].subs(values)
        a[row, 2:] = [float(sympy.diff(expression, q).subs(rest)) for q in (a1, w1, a2, w2)]
        b[row] = float(sympy.diff(expression, u).subs(rest))
    return a, b


def _reaches(a, b, dt, steps, start, target, u_max, v_max, free=()):
    """Whether an input held over ``dt`` (scipy's zero-order hold) takes ``start`` to ``target`` in ``steps`` within
    |u| <= u_max and |v| <= v_max at every grid point: daqp on the least-input QP of the constraints."""
    import scipy.signal

    ad, bd, *_ = scipy.signal.cont2discrete((a, b[:, None], np.eye(6), np.zeros((6, 1))), dt, method="zoh")
    gamma, phi = np.zeros((6, steps)), np.eye(6)
    for k in range(steps):
        gamma = ad @ gamma
        gamma[:, k] = bd[:, 0]
        phi = ad @ phi
    rows = [i for i in range(6) if i not in free]
    end = (np.asarray(target) - phi @ np.asarray(start))[rows]
    speeds = np.tril(np.ones((steps, steps))) * dt  # v_k = v0 + dt (u_0 + ... + u_{k-1}): v0 = 0 here
    matrix = np.vstack([gamma[rows], speeds, np.eye(steps)])
    upper = np.concatenate([end, np.full(steps, v_max), np.full(steps, u_max)])
    lower = np.concatenate([end, np.full(steps, -v_max), np.full(steps, -u_max)])
    sense = np.concatenate([np.full(len(rows), 5), np.zeros(2 * steps)]).astype(np.int32)  # 5: an equality
    _, _, flag, _ = daqp.solve(np.eye(steps), np.zeros(steps), matrix, upper, lower, sense)
    assert flag in (1, -1), flag  # 1: solved, -1: infeasible
    return flag == 1


@pytest.mark.parametrize("scenario, free", [("S1", ()), ("S2", ()), ("S6", ()), ("S1", (0,))],
                         ids=["S1", "S2", "S6", "S1 trolley free"])
def test_a_floor_is_reachable_and_one_grid_step_less_is_not_by_an_independent_computation(scenario, free):
    """The board's floors (and S1's with the trolley free to stop anywhere), checked without the floor's code: the
    crane linearised by sympy from the Lagrangian, held by scipy's zero-order hold, feasibility by daqp. At the
    floor the move is feasible; one grid step (10 ms, S6: 50 ms) earlier it is not."""
    drive = planar.DRIVE
    found = floor.scenario_floors()[scenario]
    if free:
        found = found._replace(seconds=floor.crane_floor(start=(0, 0, TEN_DEG, 0, 0, 0), free=free, **drive))
    start, target = {"S1": ((0, 0, TEN_DEG, 0, 0, 0), (0,) * 6), "S6": ((0, 0, TEN_DEG, 0, 0, 0), (0,) * 6),
                     "S2": ((0,) * 6, (planar.DISTANCE, 0, 0, 0, 0, 0))}[scenario]
    a, b = _linear_crane_from_sympy(PlantParameters())
    steps = round(found.seconds / found.grid)
    assert abs(steps * found.grid - found.seconds) < 1e-9
    assert _reaches(a, b, found.grid, steps, start, target, free=free, **drive)
    assert not _reaches(a, b, found.grid, steps - 1, start, target, free=free, **drive)


# --- our QP solver against daqp ------------------------------------------------------------------


def _reference(prepared, f, lower, upper):
    """daqp's solution of the same QP: ``(x, objective)``."""
    n = prepared.n
    rows = np.zeros((len(prepared.rows), n))
    for i, (first, values) in enumerate(prepared.rows):
        rows[i, first:first + len(values)] = values
    h = np.array(prepared.h)
    lower, upper = np.array(lower, float), np.array(upper, float)
    sense = np.where(lower == upper, 5, 0).astype(np.int32)  # 5: an equality
    x, value, flag, _ = daqp.solve(h, np.array(f, float), rows, upper, lower, sense)
    assert flag == 1, flag
    return x, value, rows


def _check_against_daqp(prepared, f, lower, upper, solution):
    x_ref, value_ref, rows = _reference(prepared, f, lower, upper)
    assert solution.optimal
    x = np.array(solution.x)
    value = qp.objective(prepared.h, f, solution.x)
    assert abs(value - value_ref) <= 1e-6 * max(1.0, abs(value_ref))
    products = rows @ x
    assert np.all(products <= np.array(upper) + 1e-9) and np.all(products >= np.array(lower) - 1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_the_solver_gives_daqps_answer_on_random_convex_qps(seed):
    rng = np.random.default_rng(seed)
    for _ in range(25):
        prepared, f, lower, upper, start = random_qp(rng)
        _check_against_daqp(prepared, f, lower, upper, qp.solve(prepared, f, lower, upper, start, (), 1000))


@pytest.fixture(scope="module")
def crane_qps():
    """Every QP the MPC solves in the first 3.5 s of the 2 m move on a plant heavier and longer than its model
    (plan attempts and tracking QPs), and in the first 2 s from a hook swing of 40 deg."""
    recorded, solve = [], qp.solve

    def recording(prepared, f, lower, upper, start, hint=(), max_iterations=100):
        solution = solve(prepared, f, lower, upper, start, hint, max_iterations)
        recorded.append((prepared, f, lower, upper, solution))
        return solution

    qp.solve = recording
    try:
        mpc_loop({"theta1_0": 0.0, "l1": 1.1, "l2": 0.6, "m2": 10.5}, {"x_d": 2.0}, 3.5)
        mpc_loop({"theta1_0": math.radians(40.0)}, {}, 2.0)
    finally:
        qp.solve = solve
    return recorded


def test_the_solver_gives_daqps_answer_on_the_cranes_qps(crane_qps):
    plans = [q for q in crane_qps if q[0].n != mpc.COMPONENT.check({}).steps]
    tracking = [q for q in crane_qps if q[0].n == mpc.COMPONENT.check({}).steps]
    # bisections; one QP every 50 ms until the MPC hands over to its LQR, at rest on the target (2.85 s of 3.5 s)
    assert len(plans) >= 3 and len(tracking) == 57 + 41
    assert any(len(q[4].active) > 10 for q in plans) and any(len(q[4].active) > 3 for q in tracking)  # limits bind
    for prepared, f, lower, upper, solution in crane_qps:
        _check_against_daqp(prepared, f, lower, upper, solution)


def test_a_warm_start_takes_few_iterations(crane_qps):
    tracking = [q[4].iterations for q in crane_qps if q[0].n == mpc.COMPONENT.check({}).steps]
    assert sorted(tracking)[len(tracking) // 2] <= 2  # the last solution, shifted, is (nearly) the next one


def test_at_its_cap_the_solver_gives_a_feasible_point_no_worse_than_its_start():
    rng = np.random.default_rng(7)
    capped = 0
    for _ in range(40):
        prepared, f, lower, upper, start = random_qp(rng)
        solution = qp.solve(prepared, f, lower, upper, start, (), 2)
        rows = np.array([[0.0] * first + values + [0.0] * (prepared.n - first - len(values))
                         for first, values in prepared.rows])
        products = rows @ np.array(solution.x)
        assert np.all(products <= np.array(upper) + 1e-9) and np.all(products >= np.array(lower) - 1e-9)
        assert qp.objective(prepared.h, f, solution.x) <= qp.objective(prepared.h, f, start) + 1e-12
        capped += not solution.optimal
    assert capped > 5  # the cap was reached in many of them


# --- the MpcController ---------------------------------------------------------------------------


def _move_metrics(result, x_d, h=1e-3):
    t = np.arange(len(result)) * h
    return metrics.move_metrics(t, result[:, 0], result[:, 1], (result[:, 2], result[:, 4]), result[:, 6], x_d)


def test_the_plan_is_as_short_as_the_floor_on_its_grid():
    """Our QP's bisection finds the move HiGHS's LPs find, on the MPC's 50 ms grid within 95 % of the limits."""
    c = mpc.configure({**mpc.COMPONENT.defaults(), "x_d": 2.0})
    for start, target in (((0.0,) * 6, (2.0, 0, 0, 0, 0, 0)), ((0, 0, TEN_DEG, 0, 0, 0), (0.0,) * 6)):
        inputs, states = mpc.plan_move(c.designs[0], start, target, 1.9, 0.95, c.interval, 120)
        lp = floor.crane_floor(start=start, target=target, u_max=1.9, v_max=0.95, dt=c.interval)
        assert abs(len(inputs) * c.interval - lp) <= c.interval + 1e-9
        assert np.abs(inputs).max() <= 1.9 + 1e-9
        assert np.abs(np.array(states[-1]) - target).max() <= mpc.REACHED


@pytest.mark.quick
def test_a_tiny_deviation_is_planned_in_at_least_one_interval():
    """The trolley at rest on its target, the hook's swing rate just past REACHED: the bisection's low end reaches 0
    intervals, whose (absent) end state once counted as reaching the target: the plan was empty, and the native
    MPC stopped with an error there."""
    c = mpc.configure(mpc.COMPONENT.defaults())
    start, target = (0, 0, 0, 0.0011, 0, 0), (0.0,) * 6
    inputs, states = mpc.plan_move(c.designs[0], start, target, 1.9, 0.95, c.interval, 120)
    assert len(inputs) >= 1 and np.abs(np.array(states[-1]) - target).max() <= mpc.REACHED


def test_the_mpc_keeps_the_drive_within_its_limits_and_warns_once_at_its_cap():
    """From a 40 deg swing (the limits bind at once) with one QP iteration allowed: u is still within
    |u| <= 2 and keeps |v| <= 1 (the drive never has to limit it), and the host hears of the cap once."""
    result, messages = mpc_loop({"theta1_0": math.radians(40.0)}, {"max_iterations": 1.0}, 3.0)
    u, ddx = result[:, 6], result[:, 7]
    assert np.abs(u).max() <= 2.0 + 1e-12 and np.abs(result[:, 1]).max() <= 1.0 + 1e-12
    assert np.abs(ddx[1:] - u[:-1]).max() <= 1e-12  # what the drive did is what was demanded
    assert len(messages) == 1 and "iteration cap (1)" in messages[0]


@pytest.mark.parametrize("values, message", [
    ({"interval": 0.0}, "interval must be > 0"),
    ({"margin": 1.0}, "margin must be >= 0 and < 1, got 1.0"),
    ({"max_iterations": 2.5}, "max_iterations must be a whole number >= 1, got 2.5"),
    ({"v_max": math.inf}, "u_max and v_max must be finite"),
    ({"horizon": 20.0}, "horizon must be at most 200 intervals"),
    ({"interval": 0.004, "horizon": 0.4}, "interval must be at least 0.005 s"),
    ({"l1_low": 1.0, "l1_high": 0.5}, "l1_high must be finite and > l1_low"),
])
def test_mpc_parameter_rules(values, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        mpc.COMPONENT.check(values)


def test_the_mpc_fmus_give_the_python_loop_bit_for_bit(fmu_dir):
    """The FMU (its output and its step share one solve) equals the model called directly; the move arrives."""
    result = run(systems.get("mpc-transport"), fmu_dir, recorder=ArrayRecorder(), stop_time=4.0).columns()
    loop, _ = mpc_loop({"theta1_0": 0.0}, {"x_d": 2.0}, 4.0)
    assert np.array_equal(result["plant.x"], loop[:, 0]) and np.array_equal(result["controller.u"], loop[:, 6])
    assert abs(result["plant.x"][-1] - 2.0) < 0.005
    assert result["controller.plan_end"][-1] == pytest.approx(2.75)  # 55 intervals of 50 ms


def test_the_mpc_keeps_its_limits_in_every_board_scenario(native):
    """Every case of every scenario (3 of the paired design), the first 3 s (the move): |u| <= 2 m/s2 always, and
    where the controller sees the true state the drive never has to limit what it demands (so |v| <= 1 m/s by its
    own doing). On the native FMUs (held to the Python MPC bit for bit by test_native_mpc.py, and on the board by
    test_native_board.py): 30 runs in a tenth of the time."""
    contender = scenarios.Contender("MpcController", "MpcController",
                                     list(mpc.COMPONENT.names("input")), list(mpc.COMPONENT.names("parameter")))
    for sid in (sid for sid, s in scenarios.scenarios().items() if s.plant == "CranePlant"):  # its plant's
        for label, system, step, *_ in scenarios.systems_for(contender, sid, 3):
            system = systems.prepare(system, step)
            c = run(system, native[2], recorder=ArrayRecorder(), stop_time=3.0).columns()
            assert np.abs(c["controller.u"]).max() <= 2.0 + 1e-9, (sid, label)
            if sid not in ("S5", "S8", "S9"):  # behind a sensor the MPC's speed is an estimate
                assert np.abs(c["plant.ddx"][1:] - c["controller.u"][:-1]).max() <= 1e-9, (sid, label)


# --- the issue's targets it meets (Section V plant, h = 1 ms, |u| <= 2 m/s2, |v| <= 1 m/s) ------------------------


def test_the_mpc_meets_the_nominal_move_and_regulation_targets():
    """S2: the 2 m move arrives (5 mm, 0.5 deg) within 2.95 s; S1: from 10 deg both angles within 0.1 deg by 2.5 s."""
    move, _ = mpc_loop({"theta1_0": 0.0}, {"x_d": 2.0}, 4.0)
    regulation, _ = mpc_loop({}, {}, 4.0)
    assert _move_metrics(move, 2.0)["arrival_s"] <= 2.95
    assert _move_metrics(regulation, 0.0)["settling_0.1deg_s"] <= 2.5


@pytest.mark.parametrize("true", [planar.MISMATCH[0], planar.MISMATCH[-1]], ids=str)
def test_the_mpc_identifies_a_plant_it_does_not_know_and_arrives_within_5_s(true):
    """S3's extreme plants (l1, l2, m2 unknown to the controller): the identified swing model is the true one
    (lengths and the payload's share m2 / (m1 + m2) within 1 %, eqs (8)-(9) hold exactly on the plant) and the
    2 m move arrives within 5.0 s (the target for every S3 plant)."""
    result, _, state = mpc_loop({"theta1_0": 0.0, **true}, {"x_d": 2.0}, 5.5, with_state=True)
    configured = PlantParameters()
    found = state[mpc.HEADER.l1], state[mpc.HEADER.l2], state[mpc.HEADER.m2] / (configured.m1 + configured.m2)
    wanted = true["l1"], true["l2"], true["m2"] / (configured.m1 + true["m2"])
    assert found == pytest.approx(wanted, rel=0.01)
    assert _move_metrics(result, 2.0)["arrival_s"] <= 5.0


@pytest.mark.parametrize("scenario, case, metric, bound", [
    ("S7", "l1 2 m -> 1 m", "arrival_s", 5.5),  # transport while hoisting
    ("S8", "S1", "settling_0.1deg_s", 3.0),  # behind the estimator: S1's 2.5 s + 0.5 s
])
def test_the_mpc_meets_the_board_targets_through_the_fmus(fmu_dir, scenario, case, metric, bound):
    """The board's own S7 and S8 systems through the FMUs: S7's arrival within 5.5 s, S8's regulation within
    0.1 deg by 3.0 s."""
    contender = scenarios.Contender("MpcController", "MpcController",
                                     list(mpc.COMPONENT.names("input")), list(mpc.COMPONENT.names("parameter")))
    (system, step, x_d), = [(r.system, r.step, r.x_d) for r in scenarios.systems_for(contender, scenario)
                            if r.label == case]
    c = run(systems.prepare(system, step), fmu_dir, recorder=ArrayRecorder(), stop_time=7.0).columns()
    s = metrics.crane_signals(c)
    m = metrics.move_metrics(s["time"], s["position"], s["velocity"], list(s["swing"].values()), s["demand"], x_d)
    assert m[metric] is not None and m[metric] <= bound


def test_the_targets_measure_the_mpcs_residual_over_the_boards_window():
    """``crane-fmu targets`` and the board give the same residual: every MPC run of the targets carries its board
    case's window (a move's: the planned move's end plus a slow period, not the last quarter of the run)."""
    contender = scenarios.Contender("MpcController", "MpcController",
                                     list(mpc.COMPONENT.names("input")), list(mpc.COMPONENT.names("parameter")))
    runs = controller_targets.mpc_runs(quick=True)
    assert {r.group for r in runs} == {"mpc_S1", "mpc_S2", "mpc_S3"}
    for r in runs:
        board = {case.label: case.residual_from for case in scenarios.systems_for(contender, r.group[4:], 3)}
        assert r.residual_from == board[r.label]
        if r.group != "mpc_S1":  # a move: the window opens well before the run's last quarter
            assert r.residual_from < 0.75 * r.stop_time


def test_the_targets_measure_s5_s9_and_s10_as_the_board_does():
    """``crane-fmu targets`` runs the MPC on every case of S5, S9 and S10 as the board measures them (the scenario
    named: S10's own figures about the lean) against the scenarios' own limits; a made-up S10 with one case of two
    beyond a limit is reported missed in 1 of 2 cases, the load's error in metres."""
    runs = [r for r in controller_targets.mpc_runs() if r.group in ("mpc_S5", "mpc_S9", "mpc_S10")]
    assert [sum(r.group == g for r in runs) for g in ("mpc_S5", "mpc_S9", "mpc_S10")] == [1, 64, 64]
    assert all(r.scenario == r.group[4:] and r.x_d == 2.0 for r in runs)
    limits = {t.metric: t.limit for t in scenarios.get("S10").targets}
    wanted = {t.metric: t.target for t in controller_targets.MPC_TARGETS if t.group == "mpc_S10"}
    assert wanted == limits
    made_up = [(controller_targets.Run("mpc_S10", f"#0{k}", None, {}, 1e-3, 11.3),
                {"error": None, "arrival_eq_s": 4.0, "residual_eq_deg": 0.2, "load_error_m": load})
               for k, load in ((1, 0.05), (2, 0.07))]
    lines = []
    controller_targets.report_mpc(made_up, {}, out=lines.append)
    load = next(line for line in lines if "S10: every load error" in line)
    assert "0.0700 m at #02" in load and load.endswith("MISSED in 1 of 2 cases")
    assert next(line for line in lines if "S10: every residual" in line).endswith(": met")


@pytest.mark.parametrize("degrees, planned, peak", [(10.0, True, 2.0), (10.8, True, 1.9), (60.0, False, 2.0)])
def test_no_move_is_planned_from_a_swing_beyond_the_linear_models_reach(degrees, planned, peak):
    """S1's 10 deg swing is planned at the first solve, and so is 10.8 deg's, above PLAN_BELOW (the hysteresis
    applies only once no plan is held after the first solve); from a hard hit's 60 deg (beyond LARGEST_SWING as a
    modal amplitude) no plan is made and the tracking QP alone acts, at the drive's limit (10.8 deg's plan at its
    margin's, 95 % of it, over the first 0.1 s)."""
    result, _, state = mpc_loop({"theta1_0": math.radians(degrees)}, {}, 0.1, with_state=True)
    d = mpc.configure({**mpc.COMPONENT.defaults(), "h": 1e-3}).designs[0]
    amplitude = mpc.deviation(d, result[0, :6], (0.0,) * 6)[1]
    assert (amplitude <= mpc.LARGEST_SWING) == planned
    assert (amplitude > mpc.PLAN_BELOW) == (degrees > 10.0)
    assert (state[mpc.HEADER.plan_steps] > 0) == planned
    assert np.max(np.abs(result[:, 6])) == pytest.approx(peak)


# --- hard hits (issue 51, item 4) ------------------------------------------------------------------

HARD_HIT_STOP = 15.0  # s: every start of HARD_HIT_ANGLES settles well before (and stays settled)


@pytest.fixture(scope="module")
def hard_hits():
    """``{start angle [deg]: both angles within 0.5 deg from [s]}`` (None: never) of the MPC called directly as the
    master calls its FMU, from theta1(0) over controller_targets.HARD_HIT_ANGLES (payload in line, at rest, Section
    V plant, |u| <= 2 m/s2, |v| <= 1 m/s, h = 1 ms); the drive's limits checked at every step."""
    times = {}
    for degrees in controller_targets.HARD_HIT_ANGLES:
        result, _ = mpc_loop({"theta1_0": math.radians(degrees)}, {}, HARD_HIT_STOP)
        assert np.max(np.abs(result[:, 6])) <= 2.0 + 1e-9 and np.max(np.abs(result[:, 1])) <= 1.0 + 1e-9
        t = np.arange(len(result)) * 1e-3
        times[degrees] = metrics.move_metrics(t, result[:, 0], result[:, 1], (result[:, 2], result[:, 4]),
                                              result[:, 6], 0.0)["settling_0.5deg_s"]
    return times


@pytest.mark.quick
def test_slower_than_larger_names_every_pair_out_of_order():
    assert controller_targets.slower_than_larger({30: 4.0, 35: 5.0, 40: 6.0}) == []
    assert controller_targets.slower_than_larger({30: 4.0, 35: 5.0, 40: 4.5}) == [(35, 40)]
    assert controller_targets.slower_than_larger({40: None, 30: 4.0, 35: 5.0}) == []
    assert controller_targets.slower_than_larger({30: None, 35: 5.0}) == [(30, 35)]


@pytest.mark.quick
def test_the_targets_print_the_hard_hits_and_whether_they_are_monotone():
    """`crane-fmu targets`: the 60 deg run against issue 51's 6.5 s, and every start with the pairs out of order."""
    def result(angle, seconds):
        group = "mpc_hard_hit" if angle == controller_targets.HARD_HIT_DEG else "mpc_hard_hits"
        return (controller_targets.Run(group, f"{angle:g} deg", "mpc", {}, 1e-3, 20.0),
                {"settling_0.5deg_s": seconds, "error": None})

    lines = []
    controller_targets.report_mpc([result(50, 7.0), result(55, 6.0), result(60, 6.4)], {}, lines.append)
    assert "  hard hit: from theta1 = 60 deg to within 0.5 deg: 6.40 s (target <= 6.5 s, ambition 6 s): met" in lines
    assert lines[-1] == ("  hard hits from 50 to 60 deg, to within 0.5 deg: 50: 7.00 s, 55: 6.00 s, 60: 6.40 s "
                         "(target: no start slower than a larger one): MISSED at 50 > 55 deg, 50 > 60 deg")


def test_no_hard_hit_is_slower_than_one_from_a_larger_angle(hard_hits):
    """Issue 51: from 30 to 70 deg in steps of 5 deg, every start settles (0.5 deg), and none later than a larger
    one (from 50 deg it had got slower than from 60 deg)."""
    assert None not in hard_hits.values(), hard_hits
    assert controller_targets.slower_than_larger(hard_hits) == [], hard_hits


@pytest.mark.xfail(strict=True, reason="issue 51 item 4 not met: 7.77 s from 60 deg against 6.5 s, which physics "
                                        "allows (a plan settles by 5.95 s: tests/test_hard_hit_floor.py; see "
                                        "docs/guide/controllers.md)")
def test_a_hard_hit_from_60_deg_settles_within_the_issues_6_5_s(hard_hits):
    """Issue 51's requirement: from theta1(0) = 60 deg both angles within 0.5 deg by 6.5 s (ambition 6.0 s)."""
    assert hard_hits[controller_targets.HARD_HIT_DEG] <= 6.5, hard_hits


# --- the safety envelope (issue 51): made-up failures ---------------------------------------------


def _envelope_loop(controller_values, stop_time, kick=None, plant_values=None, noise=0.0):
    """The nominal plant and the MpcController called directly (as ``helpers.mpc_loop``), the plant's hook swing
    pushed by ``kick = (time [s], angle [rad])`` once, the angles and rates the controller is given with ``noise``
    [rad, rad/s] of white noise (seeded): ``(config, rows of (time, inputs, u, controller state))``."""
    rng = np.random.default_rng(1)
    from crane_fmu.model import plant
    from crane_fmu.model.component import Step

    h = 1e-3
    pc = plant.configure({**plant.COMPONENT.defaults(), "theta1_0": 0.0, "u_max": 2.0, "v_max": 1.0,
                          **(plant_values or {})})
    cc = mpc.configure({**mpc.COMPONENT.defaults(), "h": h, **controller_values})
    ps, cs = pc.state0, mpc.initial_state(cc)
    rows = []
    for k in range(round(stop_time / h) + 1):
        if kick and k == round(kick[0] / h):
            ps = ps[:2] + (ps[2] + kick[1],) + ps[3:]
        out = plant.COMPONENT.output(pc, ps, (0.0,) * 4)
        inputs = tuple(out[:6]) + (out[11], 0.0, 0.0)
        if noise:  # on the angles and their rates (rad, rad/s)
            inputs = inputs[:2] + tuple(v + noise * rng.normal() for v in inputs[2:6]) + inputs[6:]
        u = mpc.COMPONENT.output(cc, cs, inputs)[0]
        rows.append((k * h, inputs, u, cs))
        ps = plant.update(pc, ps, (u, 0.0, 0.0, 0.0), k * h, h)
        cs = mpc.update(cc, cs, inputs, k * h, h)
        cs = cs.state if isinstance(cs, Step) else cs
    return cc, rows


def test_an_identified_payload_beyond_the_envelope_does_not_reach_the_plan():
    """A payload of 0.6 kg on a crane configured for 7 kg (the cables as configured): identified as ``k = l2 m2 /
    (m1 + m2)``, which with the configured ``m1 + m2`` is a payload of 1.7 kg, beyond the factor 3 of the envelope:
    refused, the model stays the configured one. The same crane with a payload of 1.5 kg (3.3 kg so identified) is
    taken."""
    configured = PlantParameters()
    refused = _envelope_loop({"x_d": 2.0}, 1.0, plant_values={"m2": 0.6})[1][-1][3]
    taken = _envelope_loop({"x_d": 2.0}, 1.0, plant_values={"m2": 1.5})[1][-1][3]
    assert refused[mpc.HEADER.l1] == 0.0 and refused[mpc.HEADER.samples] > 0  # the data gathered, no model
    assert taken[mpc.HEADER.l1] == pytest.approx(configured.l1, rel=0.01)
    mu = configured.m1 + configured.m2
    assert taken[mpc.HEADER.m2] == pytest.approx(mu * 1.5 / (configured.m1 + 1.5), rel=0.01)


@pytest.mark.parametrize("seed", range(3))
def test_the_envelopes_standard_errors_are_numpys(seed):
    """:func:`mpc.precise` on least-squares fits of known noise: its verdict is that of the standard errors from
    numpy's solution (``sigma^2 (X'X)^-1``), on both sides of the 1 % bound."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(24, 3))
    beta = np.array([1.0, 0.5, 0.3])
    verdicts = []
    for noise in (1e-3, 3e-3, 1e-2, 3e-2, 1e-1):
        y = x @ beta + noise * rng.normal(size=24)
        fit, residuals, *_ = np.linalg.lstsq(x, y, rcond=None)
        errors = np.sqrt(residuals[0] / (24 - 3) * np.diag(np.linalg.inv(x.T @ x)))
        normal = (x.T @ x).tolist()
        factor = qp.cholesky(normal)
        z = (x.T @ y).tolist()
        values = qp.cholesky_solve(factor, z)
        residual = float(y @ y) - sum(v * zi for v, zi in zip(values, z))
        wanted = bool(np.all(errors <= mpc.STANDARD_ERROR * np.abs(fit)))
        assert mpc.precise(factor, values, residual, 24.0) == wanted
        verdicts.append(wanted)
    assert True in verdicts and False in verdicts


def test_a_swing_past_the_plans_largest_hands_over_to_the_lqr():
    """The hook knocked by 20 deg at 1.0 s, mid-move, the way it swings (the plan's largest swing is 16 deg): at the
    next solve
    (1.0 s is one) the MPC hands over to its LQR, whose input (:func:`.lqr.control`, the configured crane's) it
    gives from then on, every step."""
    from crane_fmu.model import lqr

    config, rows = _envelope_loop({"x_d": 2.0}, 1.5, kick=(1.0, math.radians(-20.0)))
    handed = [t for t, _, _, state in rows if state[mpc.HEADER.handed]]
    assert handed and handed[0] == pytest.approx(1.001)  # the state after the solve at 1.0 s
    assert rows[1000][3][mpc.HEADER.replans] == 0.0  # not for plans run out
    assert all(u == lqr.control(config.lqr, inputs[:6]) for t, inputs, u, _ in rows if t >= 1.0)
    assert math.degrees(rows[999][3][mpc.HEADER.bound]) == pytest.approx(15.8, abs=0.1)


@pytest.mark.parametrize("kick_deg", [-3.0, -5.0])
def test_a_swing_past_the_largest_swing_mid_move_is_planned_for_not_dropped(kick_deg):
    """The hook knocked by 3 or 5 deg at 1.0 s, mid-move, the way it swings: the swing passes LARGEST_SWING
    (17.5 deg) but not the plan's largest by SWING_MARGIN. The held plan is not dropped (the tracking QP alone with
    the trolley free had swung S10's case #57 to 26 deg): a plan for the deviation is made at once, and a plan is
    held to the end of the run, no handover."""
    config, rows = _envelope_loop({"x_d": 2.0}, 3.0, kick=(1.0, math.radians(kick_deg)))
    after = [state for t, _, _, state in rows if t > 1.0]
    assert math.degrees(after[0][mpc.HEADER.bound]) > math.degrees(mpc.LARGEST_SWING)  # planned from past it
    assert after[0][mpc.HEADER.plan_start] == 20 and after[0][mpc.HEADER.replans] == 1.0
    assert all(state[mpc.HEADER.plan_steps] > 0 and not state[mpc.HEADER.handed] for state in after)


def test_a_plan_without_surprises_is_kept_to_its_end():
    """Without a knock the same move keeps its plan to the end: no handover mid-move (the envelope's bounds are not
    under the nominal move)."""
    config, rows = _envelope_loop({"x_d": 2.0}, 2.7)
    assert not any(state[mpc.HEADER.handed] for _, _, _, state in rows)


@pytest.mark.parametrize("noise_deg, unexplained", [(0.0, False), (0.1, True)])
def test_data_beyond_the_cranes_equations_are_told_from_a_crane(noise_deg, unexplained):
    """The identification's first full window (0.3 s of the 2 m move): the plant's own states leave nothing
    unexplained (and give the model); with 0.1 deg (deg/s) of noise on the angles and rates the data leave more
    than 1e-3 of their squares unexplained (the envelope's sign that the states are not the crane's), no model is
    taken, and the MPC does not hand over before its plan is over."""
    config, rows = _envelope_loop({"x_d": 2.0}, 5.0, noise=math.radians(noise_deg))  # the cautious plan ends at 3.6 s
    k = next(k for k, (_, _, _, state) in enumerate(rows)
             if state[mpc.HEADER.samples] == config.samples - 1 and k % config.every == 0)
    _, model, found = mpc.identify(config, rows[k][3], rows[k][1][:6])
    assert found == unexplained and (model is None) == unexplained
    if unexplained:
        plan_end = (rows[k][3][mpc.HEADER.plan_start] + rows[k][3][mpc.HEADER.plan_steps]) * config.interval
        handed = next(t for t, _, _, state in rows if state[mpc.HEADER.handed])
        assert plan_end < handed


def test_the_plans_length_is_the_least_number_of_intervals_by_an_independent_computation():
    """The MPC's plan (its QP's bisection) for S2's 2 m move and from a hook swing of 10 deg, at 95 % of the limits
    on its 50 ms grid: as many intervals as the least that reach the target without the planner's or the floor's
    code (the crane linearised by sympy, scipy's zero-order hold, feasibility by daqp): the target is reachable in
    the plan's number of intervals and not in one fewer."""
    c = mpc.configure({**mpc.COMPONENT.defaults(), "x_d": 2.0})
    a, b = _linear_crane_from_sympy(PlantParameters())
    for start, target in (((0.0,) * 6, (2.0, 0, 0, 0, 0, 0)), ((0, 0, TEN_DEG, 0, 0, 0), (0.0,) * 6)):
        inputs, _ = mpc.plan_move(c.designs[0], start, target, 1.9, 0.95, c.interval, 120)
        assert _reaches(a, b, c.interval, len(inputs), start, target, 1.9, 0.95), start
        assert not _reaches(a, b, c.interval, len(inputs) - 1, start, target, 1.9, 0.95), start


@pytest.mark.parametrize("distance", [1.5, 2.0, 3.0])
def test_the_spatial_scenarios_axis_floors_are_reachable_and_one_grid_step_less_is_not(distance):
    """The floors the spatial scenarios take per axis (S11: 2 m and 1.5 m, S13's legs 3 m and 2 m; 2.44 s, 2.70 s
    and 4.27 s in the issue), from the floor's code, checked as the board's: sympy, scipy's hold and daqp."""
    drive = planar.DRIVE
    seconds = floor.crane_floor(target=(distance, 0, 0, 0, 0, 0), **drive)
    a, b = _linear_crane_from_sympy(PlantParameters())
    steps = round(seconds / floor.GRID)
    assert abs(steps * floor.GRID - seconds) < 1e-9
    assert _reaches(a, b, floor.GRID, steps, (0,) * 6, (distance, 0, 0, 0, 0, 0), **drive)
    assert not _reaches(a, b, floor.GRID, steps - 1, (0,) * 6, (distance, 0, 0, 0, 0, 0), **drive)


@pytest.mark.parametrize("noise_deg", [0.0, 0.1])
def test_unexplained_data_make_every_plan_cautious_from_the_third_interval(noise_deg):
    """Behind noisy states (0.1 deg, deg/s on the angles and rates: the data beyond the crane's equations, as an
    estimator's of another crane are) the MPC turns cautious at the solve of its SUSPECT_AFTER-th interval (0.15 s)
    and plans at once again: the least-effort move of ceil(CAUTIOUS_STRETCH n) intervals, ``n`` the shortest move's
    from the same state, no plan for a deviation counted. The plant's own states leave it as it was: never cautious,
    the shortest move (55 intervals) kept."""
    config, rows = _envelope_loop({"x_d": 2.0}, 1.0, noise=math.radians(noise_deg))
    cautious = [k for k, (_, _, _, state) in enumerate(rows) if state[mpc.HEADER.cautious]]
    if not noise_deg:
        assert not cautious and all(state[mpc.HEADER.plan_steps] == 55.0 for _, _, _, state in rows[1:])
        return
    k = cautious[0]  # the state after the solve at k - 1: that solve turned it, before the model's window was full
    at = round(rows[k - 1][0] / config.interval)
    assert mpc.SUSPECT_AFTER <= at < config.samples and rows[k - 1][0] == pytest.approx(at * config.interval)
    before, after = rows[k - 1][3], rows[k][3]
    assert before[mpc.HEADER.plan_steps] == 55.0 and after[mpc.HEADER.plan_start] == at
    assert after[mpc.HEADER.replans] == 0.0
    shrink = 1.0 - config.margin
    shortest, _ = mpc.plan_move(config.designs[0], rows[k - 1][1][:6], (2.0, 0, 0, 0, 0, 0), config.u_max * shrink,
                                config.v_max * shrink, config.interval, int(mpc.LONGEST_PLAN / config.interval))
    assert after[mpc.HEADER.plan_steps] == math.ceil(len(shortest) * mpc.CAUTIOUS_STRETCH) > len(shortest)


def _fast_swing_left(config, inputs, s0, target):
    """The largest fast swing mode's amplitude [deg] (mpc.fast_mode_rows) that ``inputs`` from ``s0`` leave at the
    end on the cranes at the corners of mpc.SPREAD about the configured one (their linear models)."""
    worst = 0.0
    for ad, bd, rows in mpc.robust_ends(config, (0.0, 0.0, 0.0)):
        s = list(s0)
        for value in inputs:
            s = [sum(a * b for a, b in zip(row, s)) + b_row[0] * value for row, b_row in zip(ad, bd)]
        e = [a - b for a, b in zip(s, target)]
        worst = max(worst, math.degrees(math.hypot(*(sum(r * x for r, x in zip(row, e)) for row in rows))))
    return worst


# S2's move from rest; a state 0.15 s into the shortest move (S9's case #07, as the estimator gave it), from which
# the first of the ROBUST_WEIGHTS does not reach the target and a smaller one does
@pytest.mark.parametrize("s0, bound_deg", [((0.0,) * 6, planar.STOPPED_DEG),
                                           ((0.0219, 0.2905, -0.0215, -0.2684, -0.0024, -0.0583), None)],
                         ids=["from rest", "mid-move"])
def test_a_cautious_plan_leaves_the_fast_swing_at_rest_on_the_cranes_about_the_model(s0, bound_deg):
    """The cautious plan (ceil(1.3 n) intervals) made robust to the cranes at the corners of mpc.SPREAD
    (mpc.robust_ends) still reaches the target on the configured crane, and leaves their fast swing mode (the one an
    estimator of the configured crane cannot see) at rest: from rest within S2's 0.1 deg on every corner, where the
    plan for the configured crane alone leaves more than 1 deg; from mid-move (a smaller weight of ROBUST_WEIGHTS)
    less than half of that plan's."""
    config = mpc.configure({**mpc.COMPONENT.defaults(), "x_d": 2.0})
    d, target, shrink = config.designs[0], (2.0, 0.0, 0.0, 0.0, 0.0, 0.0), 1.0 - config.margin
    limits = (config.u_max * shrink, config.v_max * shrink, config.interval, int(mpc.LONGEST_PLAN / config.interval))
    plain, _ = mpc.plan_move(d, s0, target, *limits, mpc.CAUTIOUS_STRETCH)
    robust, states = mpc.plan_move(d, s0, target, *limits, mpc.CAUTIOUS_STRETCH,
                                   mpc.robust_ends(config, (0.0, 0.0, 0.0)))
    assert len(robust) == len(plain) and max(abs(a - b) for a, b in zip(states[-1], target)) <= mpc.REACHED
    assert max(abs(u) for u in robust) <= config.u_max * shrink * (1 + 1e-9)
    left, left_plain = _fast_swing_left(config, robust, s0, target), _fast_swing_left(config, plain, s0, target)
    if bound_deg:
        assert left <= bound_deg < 1.0 < left_plain
    else:
        assert left < 0.5 * left_plain
