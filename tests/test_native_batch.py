"""The batch path of native FMUs (crane_fmu/native_batch.py) against the per-case path, on built native FMUs.

Every figure of every case must be the per-case master's bit for bit: the board's cases and the built-in studies'
(run here in this process, one worker's way: one runner per system, its instances reset from case to case). An
instance reset between cases must give the bits of a fresh one, for every native model (the plant, the planner,
the laws, the MPC, the estimator, the wind's seeded turbulence, the sensors' noise): each check runs another case
first, whose outputs differ, so a state that survived a reset would show.
"""

import ctypes
import math

import numpy as np
import pytest
from fmpy.fmi2 import fmi2CallbackFunctions
from fmpy.logging import addLoggerProxy
from native_fmus import LOGGER

from crane_fmu import components, native_batch, systems
from crane_fmu.analysis import fast_metrics, metrics, scenarios
from crane_fmu.compare import contenders, plan, run_score_case
from crane_fmu.cosim import FmiError, simulate
from crane_fmu.cosim.reused import ReusedRunner
from crane_fmu.sweep import spec
from crane_fmu.sweep.runner import case_parameters, run_case, shippable

NOT_FIGURES = ("duration_s", "date")  # when a row was made and how long it took


def _same(a, b):
    """Equal rows: every value the same bits (NaN as NaN), but when they were made."""
    def equal(x, y):
        if isinstance(x, float) and isinstance(y, float):
            return x == y or (math.isnan(x) and math.isnan(y))
        return x == y and type(x) is type(y)

    return a.keys() == b.keys() and all(equal(a[k], b[k]) for k in a if k not in NOT_FIGURES)


def _differing(a, b):
    """``{key: (a's value, b's value)}`` where two rows differ: what a failure names (a row's repr is cut short)."""
    return {k: (a.get(k), b.get(k)) for k in a.keys() | b.keys()
            if k not in NOT_FIGURES and not _same({k: a.get(k)}, {k: b.get(k)})}


def test_the_twin_is_of_this_metrics_module():
    """fast_metrics mirrors metrics.py as it is: a change there must be made in the twin too (the batch path
    computes its figures with metrics.py itself until then)."""
    assert fast_metrics.MIRRORS == metrics.VERSION, "metrics.py changed: mirror it in fast_metrics.py/reductions.c"
    assert fast_metrics.available()


def _signals(rng, n):
    """A block of rows of n points at 1 ms (time, two axes' positions, three angles, two velocities, two demands) and
    its columns: strided views."""
    names = ("t", "x", "y", "theta1", "theta2", "phi", "dx", "dy", "u", "v")
    scale = np.array([1, 1, 1, .05, .05, .05, .3, .3, 1, 1]) * 10.0 ** rng.integers(-3, 2)
    block = rng.standard_normal((n, len(names))) * scale
    block[:, 0] = np.arange(n) * 1e-3
    if rng.random() < 0.3:  # a swing that settles half way
        block[n // 2:, 3:6] *= 1e-6
    if rng.random() < 0.15:
        block[rng.integers(0, n), rng.integers(1, len(names))] = rng.choice([np.nan, np.inf, -np.inf])
    return dict(zip(names, block.T))


@pytest.mark.quick
def test_the_twin_gives_the_metrics_bits_on_any_signals():
    """fast_metrics' figures equal metrics.py's on random runs of 2 to 30 000 points (strided columns, non-finite
    samples, swings that settle), one axis and two angles (the planar crane) and two axes and three angles, every
    metric of the sweeps and of the board: numpy's pairwise sums of squares, efforts, trapezoids and variations,
    its NaN-propagating maxima, its masks of windows and bands."""
    rng = np.random.default_rng(53)
    for trial in range(160):
        n = int(rng.integers(2, 300 if trial % 3 else 30000))
        c = _signals(rng, n)
        copied = {k: v.copy() for k, v in c.items()}  # what the per-case path gives metrics.py: contiguous columns
        completed = bool(trial % 4)
        bounds = {"u_max": 2.0, "v_max": 1.0, "x_min": -1.0, "x_max": 3.0} if trial % 2 else None
        residual_from = float(rng.choice([0.3, 2.0])) * c["t"][-1] if trial % 3 else None
        planar = trial % 5 != 0
        angles = ("theta1", "theta2") if planar else ("theta1", "theta2", "phi")
        axes = ("x", "dx", "u") if planar else (["x", "y"], ["dx", "dy"], ["u", "v"])
        x_d = float(rng.choice([0.0, 2.0, -1.0])) if planar else [float(v) for v in rng.choice([0.0, 2.0, -1.0], 2)]
        moves = []
        for m, s in ((fast_metrics, c), (metrics, copied)):
            s["swing"] = {a: s[a] for a in angles}
            x, dx, u = (s[a] if isinstance(a, str) else [s[k] for k in a] for a in axes)
            moves.append(m.move_metrics(s["t"], x, dx, s["swing"].values(), u, x_d, residual_from, bounds=bounds))
        for twin, numpy_ in ((fast_metrics.closed_loop_metrics(c["t"], c["x"], c["swing"], c["u"], completed),
                              metrics.closed_loop_metrics(copied["t"], copied["x"], copied["swing"], copied["u"],
                                                          completed)), moves):
            numpy_.pop("corr_theta1_theta2", None)  # no study asks for it: the twin leaves it out
            assert _same(twin, numpy_), (trial, n)
        for band in (1e-4, 0.01, 3.0):
            assert fast_metrics.classify(c["t"], c["swing"].values(), completed, band) == metrics.classify(
                copied["t"], list(copied["swing"].values()), completed, band)
            assert _same({"s": fast_metrics.settling_time(c["t"], list(c["swing"].values()), band)},
                         {"s": metrics.settling_time(copied["t"], list(copied["swing"].values()), band)})


@pytest.mark.parametrize("name", ["region_of_attraction", "hard_hits", "theta2_gain_sensitivity"])
def test_the_builtin_studies_give_the_per_case_rows_bit_for_bit(native, name):
    """A sample of each built-in study's cases (every 7th, failing ones among them), in a row on one runner."""
    study = spec.load(spec.BUILTIN_DIR / f"{name}.toml")
    settings = {**study.settings(), "metrics_version": metrics.VERSION}
    system = shippable(systems.prepare(systems.get(study.system), study.step, study.stop_time, check=False),
                       native[2])
    assert native_batch.batchable(system["blobs"].values(), study.algorithm)
    cases = study.cases()[::7]
    batch = list(native_batch.sweep_chunk(("batch", cases), system, settings, study.metrics))
    for case, row in zip(cases, batch, strict=True):
        alone = run_case(case, system, settings, study.metrics)
        assert _same(row, alone), (case, _differing(row, alone))


def test_the_boards_cases_give_the_per_case_rows_bit_for_bit(native):
    """Every built-in controller on every scenario (one case of the paired design), in a row on one worker."""
    cases, blobs, _ = plan(contenders(fmu_dir=native[2]), native[2], cases=1)
    assert {c["scenario"] for c in cases} == set(scenarios.scenarios())
    items = native_batch.items(cases, lambda c: native_batch.batchable([(d, blobs[d]) for d in c["fmus"].values()],
                                                                        c["master"]))
    python_only = {c.model_identifier for c in components.registered("controller") if not c.native}  # one by one
    assert "MpcController3D" not in python_only  # native since mpc3d.c: its cases batched too
    assert all((kind == "batch") == all(c["controller"] not in python_only for c in group) for kind, group in items)
    assert any(kind == "batch" for kind, _ in items)
    batch = [row for item in items for row in native_batch.score_chunk(item, blobs)]
    assert len(batch) == len(cases)
    by_id = {row["case_id"]: row for row in batch}
    for case in cases:
        row, alone = by_id[case["case_id"]], run_score_case(case, blobs)
        assert _same(row, alone), (case["controller"], case["scenario"], _differing(row, alone))


# (system, the case run first, the case checked): each a System built in or of the board, and {instance: values}
def _pairs():
    lqr = contenders(["LqrController"], only=True)[0]
    mpc = contenders(["MpcController"], only=True)[0]
    board = {sid: scenarios.systems_for(lqr, sid, 2) for sid in ("S4", "S5", "S7", "S9", "S10")}
    heavier = {"plant": {"m2": 9.0, "l1": 1.1, "theta1_0": 0.05}}
    pairs = [(run.system, heavier, {}) for run in board["S9"][:1] + board["S10"][:1]]  # the seeded noise and wind
    pairs += [(board["S9"][1].system, board["S9"][0].system.parameters, {}),  # another plant, another seed
              (board["S10"][1].system, board["S10"][0].system.parameters, {}),
              (board["S5"][0].system, {"sensor": {"seed": 2.0}, **heavier}, {}),
              (board["S4"][0].system, {"gust": {"F2_peak": 20.0}, **heavier}, {}),
              (board["S7"][0].system, heavier, {})]  # the planner and the hoist mid-move
    pairs += [(scenarios.systems_for(mpc, "S3", 2)[1].system, scenarios.systems_for(mpc, "S3", 2)[0].system
               .parameters, {})]  # the MPC's plan and warm start
    pairs += [(systems.get(name), heavier, {}) for name in ("paper", "energy", "hard-hit", "lqg-transport")]
    return pairs


@pytest.mark.parametrize("version", [2, 3])
def test_an_instance_reset_gives_a_fresh_instances_bits_for_every_native_model(native, version):
    """Case A, then case B on the same instances (reset), against case B on fresh ones and through the per-case
    master (:func:`simulate`): every output at every point the same bits; A's outputs differ from B's."""
    for system, first, then in _pairs() if version == 2 else _pairs()[:2]:
        system = systems.prepare(system, 1e-3, 4.0, check=False)
        fmus, connections = system.resolve(native[version])
        a, b = (case_parameters({}, system.parameters) for _ in range(2))
        for parameters, changes in ((a, first), (b, then)):
            for instance, values in changes.items():
                parameters.setdefault(instance, {}).update(values)
        with ReusedRunner(fmus, connections) as reused, ReusedRunner(fmus, connections) as fresh:
            rows_a, error_a = reused.run(0.0, 4.0, 1e-3, a)
            rows_a = rows_a.copy()
            rows_b, error_b = reused.run(0.0, 4.0, 1e-3, b)
            expected, error = fresh.run(0.0, 4.0, 1e-3, b)
            assert reused.fresh == 1  # reset, not instantiated again
            assert (error_a, error_b, error) == (None, None, None), system.name
            assert not np.array_equal(rows_a, rows_b), system.name
            assert np.array_equal(rows_b, expected), (system.name, first)
        columns = simulate(fmus, connections, 4.0, 1e-3, parameters=b).columns()  # the per-case master's run
        assert np.array_equal(expected, np.column_stack([columns[n] for n in ["time", *reused.output_names]]))


def test_the_operations_of_a_runs_setup_are_made_once_and_given_each_runs_values(native):
    """Runs A, B, A again of the same parameters' names on one runner: the operations that set them up are made once
    for the fresh instances and once for the reset ones (not once a run), and each run sets its own values (B's rows
    differ from A's; A's again are A's bits)."""
    system = systems.prepare(systems.get("lqr"), 1e-3, 2.0)
    fmus, connections = system.resolve(native[2])
    a = {**system.parameters, "plant": {**system.parameters.get("plant", {}), "theta1_0": 0.05, "m2": 9.0}}
    b = {**a, "plant": {**a["plant"], "theta1_0": 0.1, "m2": 4.0}}
    with ReusedRunner(fmus, connections) as reused:
        reused.master.initialize = None  # each run set up through run_calls, never the master's way
        first = reused.run(0.0, 2.0, 1e-3, a)[0].copy()
        other = reused.run(0.0, 2.0, 1e-3, b)[0].copy()
        again = reused.run(0.0, 2.0, 1e-3, a)[0].copy()
        assert len(reused._plans) == 2 and reused.fresh == 1
    assert not np.array_equal(first, other)
    assert np.array_equal(first, again)


def test_an_instance_that_cannot_reset_is_made_again(native, monkeypatch):
    """An FMU that cannot reset (its fmi2Reset answering fmi2Error: here the controller's, replaced by a C-callable
    function that does just that) is freed and instantiated again for the next case, with the same bits."""
    system = systems.prepare(systems.get("lqr"), 1e-3, 2.0)
    fmus, connections = system.resolve(native[2])
    with ReusedRunner(fmus, connections) as reused, ReusedRunner(fmus, connections) as fresh:
        reused.run(0.0, 2.0, 1e-3, {"plant": {"theta1_0": 0.05}})
        instance = reused.instances["controller"]
        refuse = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p)(lambda component: 3)  # fmi2Error

        class CannotReset:  # the FMU's library, but its fmi2Reset
            def __init__(self, library):
                self.library = library

            def __getitem__(self, name):
                return refuse if name == "fmi2Reset" else self.library[name]

        def refused():
            raise FmiError(instance.name, "fmi2Reset", None, "error", [])

        monkeypatch.setattr(instance, "_library", CannotReset(instance._library))
        monkeypatch.setattr(instance, "reset", refused)  # fmpy's call of the same function
        rows, error = reused.run(0.0, 2.0, 1e-3, system.parameters)
        assert reused.fresh == 2 and error is None
        assert reused.instances["controller"] is not instance
        assert np.array_equal(rows, fresh.run(0.0, 2.0, 1e-3, system.parameters)[0])


def test_a_case_that_fails_on_kept_instances_says_why_after_another_host_used_fmpys_logger(native):
    """A runner's instances outlive the call that made them (kept per thread, from one test or chunk to the next);
    meanwhile another host in the process may point fmpy's logger proxy (one target per process) at its own logger,
    as tests/native_fmus.py does. A case that fails on them still gives the FMU's reason, as the per-case path does
    (CI once found region_of_attraction's case at 3 deg, l1 1 m failing without it: its row differed)."""
    system = systems.prepare(systems.get("paper"), 1e-3, 1.0, check=False)
    fmus, connections = system.resolve(native[2])
    parameters = case_parameters({"plant.theta1_0": math.radians(3), "plant.l1": 1.0, "controller.l1": 1.0,
                                  "controller.b3_form": "printed", "controller.w_theta2": 1.0}, system.parameters)
    other = fmi2CallbackFunctions()
    other.logger = LOGGER  # the tests' own, kept for the whole process: the proxy may call it at any time after
    with ReusedRunner(fmus, connections) as runs:
        addLoggerProxy(ctypes.byref(other))  # after the instances were made
        error = runs.run(0.0, 1.0, 1e-3, parameters)[1]
    with pytest.raises(FmiError) as alone:
        simulate(fmus, connections, 1.0, 1e-3, parameters=parameters)
    assert str(error) == str(alone.value)
    assert ": input u must be finite, got " in str(error)  # the plant's reason, not only its status
