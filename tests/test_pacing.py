"""Real-time pacing, its timing and the watchdog, exactly, with a fake clock; the runner with real FMUs.

The fake clock's times are binary fractions, so every expected time below is exact: an assertion of
equality, not a tolerance, guards "deadlines on the absolute grid t0 + j*period".
"""

import math
import threading

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.cosim import ArrayRecorder, Master, open_instance, simulate
from crane_fmu.cosim.external import ExternalInstance
from crane_fmu.cosim.pacing import Pacer, Timing, Watchdog, percentile
from crane_fmu.cosim.realtime import Runner
from crane_fmu.model import lqr


class FakeClock:
    """``now`` advances only by ``sleep`` (which overshoots by ``overshoot``) and by the work (``spend``)."""

    def __init__(self, now=100.0, overshoot=0.0):
        self.now, self.overshoot, self.sleeps = now, overshoot, []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(seconds)
        self.now += seconds + self.overshoot

    def spend(self, seconds):
        self.now += seconds


def test_deadlines_stay_on_the_absolute_grid_whatever_the_sleep_overshoots():
    """Each sleep overshoots by 1/4 s: a loop of sleep(period) would drift 3/8 s a cycle; the pacer's
    deadlines stay at t0 + j*period and each cycle starts exactly 1/4 s late."""
    clock = FakeClock(overshoot=0.25)
    pacer = Pacer(1.0, clock, clock.sleep)
    starts = []
    for _ in range(6):
        assert pacer.cycle(lambda: (starts.append(clock.now), clock.spend(0.125)))
    assert starts == [100.0, 101.25, 102.25, 103.25, 104.25, 105.25]
    assert list(pacer.timing.deadlines) == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    assert list(pacer.timing.lateness) == [0.0, 0.25, 0.25, 0.25, 0.25, 0.25]
    assert list(pacer.timing.work) == [0.125] * 6
    assert clock.sleeps == [0.875, 0.625, 0.625, 0.625, 0.625]  # to the deadline, not a period
    assert pacer.timing.misses == 0


def test_a_late_cycle_is_a_miss_and_the_next_ones_catch_up_on_the_grid():
    """Cycle 1 works 2.5 periods: it misses, cycle 2 starts at once 1.5 late and misses too, cycle 3 starts
    at once 0.75 late and ends exactly at its next deadline (on time), cycle 4 starts on its deadline: no
    cycle is dropped and none drifts."""
    clock = FakeClock()
    pacer = Pacer(1.0, clock, clock.sleep)
    for seconds in (0.5, 2.5, 0.25, 0.25, 0.25, 0.25):
        pacer.cycle(lambda s=seconds: clock.spend(s))
    assert list(pacer.timing.lateness) == [0.0, 0.0, 1.5, 0.75, 0.0, 0.0]
    assert list(pacer.timing.missed) == [0, 1, 1, 0, 0, 0]
    assert clock.sleeps == [0.5, 0.75]  # before cycles 1 and 5 only
    assert clock.now == 105.25 and pacer.timing.end == 5.25
    summary = pacer.timing.summary()
    assert summary["cycles"] == 6 and summary["misses"] == 2 and summary["lateness_max"] == 1.5


def test_a_sleep_that_says_stop_ends_the_pacing_without_the_work():
    stop = threading.Event()
    clock = FakeClock()
    ran = []

    def sleep(seconds):
        clock.sleep(seconds)
        stop.set()
        return True

    pacer = Pacer(1.0, clock, sleep)
    assert pacer.cycle(lambda: (ran.append(1), clock.spend(0.25)))
    assert not pacer.cycle(lambda: ran.append(2))
    assert ran == [1] and len(pacer.timing) == 1


def test_timing_percentiles_summary_and_csv(tmp_path):
    timing = Timing(0.01)
    lateness = [0.001 * i for i in range(100)]  # 0 to 99 ms: cycles 10 to 99 end after their next deadline
    for j, late in enumerate(lateness):
        timing.add(0.01 * j, late, 0.0005)
    for q in (0, 50, 99, 100):
        assert percentile(timing.lateness, q) == pytest.approx(np.percentile(lateness, q), abs=1e-15)
    summary = timing.summary()
    assert summary["misses"] == sum(late + 0.0005 > 0.01 for late in lateness) == 90
    assert summary["lateness_max"] == 0.099
    assert math.isnan(percentile([], 50))
    # the real-time factor: the simulated time over the wall time to the end of the last cycle's period, or
    # of its work if that ended later (here: 99.5 ms after its deadline)
    assert timing.end == pytest.approx(0.99 + 0.099 + 0.0005) and timing.wall() == timing.end
    assert f"real-time factor {1.0 / 1.0895:.4f}" in timing.describe(simulated=1.0)
    on_time = Timing(0.01)
    for j in range(100):
        on_time.add(0.01 * j, 0.002, 0.001)
    assert on_time.wall() == pytest.approx(1.0) and "real-time factor 1.0000" in on_time.describe(simulated=1.0)
    timing.write_csv(tmp_path / "t.csv", start_time=2.0)
    rows = (tmp_path / "t.csv").read_text().splitlines()
    assert rows[0] == "cycle,deadline_s,lateness_s,work_s,missed,time"
    assert len(rows) == 101 and rows[11].split(",")[4] == "1" and rows[10].split(",")[4] == "0"
    assert float(rows[100].split(",")[5]) == pytest.approx(2.99)


def test_watchdog_holds_after_the_timeout_and_resumes_on_a_write():
    dog = Watchdog(0.5, "zero")
    assert dog.check(10.5, 10.0) is None  # exactly the timeout: not yet silent
    assert dog.check(10.5 + 2**-20, 10.0) == "hold"
    assert dog.check(11.0, 10.0) is None  # still holding: said once
    assert dog.check(11.0, 10.75) == "resume"
    assert "held at zero" in dog.describe(0.6, "controller's outputs")
    assert "at their last values" in Watchdog(1.0, "last").describe(1.2, "x")
    for bad in ((0.0, "zero"), (math.inf, "zero"), (1.0, "sometimes")):
        with pytest.raises(ValueError):
            Watchdog(*bad)


# --- the runner over real FMUs ---


def _lqr_master(fmu_dir, external=True):
    """The lqr system at its step, its controller an ExternalInstance (or the FMU): ``(master, parameters)``."""
    system = systems.prepare(systems.get("lqr"), 1e-3)
    fmus, connections = system.resolve(fmu_dir)
    instances = {name: ExternalInstance(path, name) if external and name == "controller" else open_instance(path, name)
                 for name, path in fmus.items()}
    return Master(instances, connections), system.parameters


def test_lock_step_with_the_lqr_law_outside_equals_the_offline_run(fmu_dir):
    """The runner in lock-step, the LQR's law applied between steps by another thread as a client would,
    records the offline run of the LQR FMU exactly (the same Gauss-Seidel exchange)."""
    steps = 200
    master, parameters = _lqr_master(fmu_dir)
    recorder = ArrayRecorder()
    runner = Runner(master, 0.0, 1e-3, 1.0, parameters, [recorder], lock_step=True)
    names = [v.name for v in runner.variables]
    inputs = [names.index(f"controller.{n}") for n in ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")]
    config = lqr.COMPONENT.check({"h": 1e-3})

    def client():
        for _ in range(steps + 1):
            state = [runner.snapshot().values[i] for i in inputs]
            runner.write({"controller.u": lqr.control(config, state)})
            if runner.steps < steps:
                runner.request_steps(1).result(10)
        runner.stop()

    runner.start()
    thread = threading.Thread(target=client)
    thread.start()
    runner.run()
    thread.join()
    assert runner.finish() == pytest.approx(0.2)
    offline = simulate(*systems.get("lqr").resolve(fmu_dir), 0.2, 1e-3, parameters=parameters).columns()
    served = recorder.columns()
    assert list(served) == list(offline)
    for name in offline:
        assert np.max(np.abs(served[name] - offline[name])) <= 1e-12, name
    assert runner.snapshot().status == "stopped at t = 0.2 s"
    assert isinstance(runner.request_steps(1).exception(), ValueError)  # ended: refused
    for inst in master.instances.values():
        inst.free()


def test_real_time_runner_with_a_fake_clock_holds_a_silent_client_at_zero(fmu_dir):
    """At 10 ms cycles of 10 steps the client writes u = 0.5 once, at the start; the watchdog (45 ms)
    holds u at zero from the first cycle that begins more than 45 ms after that write: cycle 5 (50 ms).
    The run ends by itself at the stop time, every cycle on time."""
    master, parameters = _lqr_master(fmu_dir)
    clock = FakeClock(overshoot=2**-12)  # 0.24 ms late every wake-up
    recorder, lines = ArrayRecorder(), []
    runner = Runner(master, 0.0, 1e-3, 0.1, parameters, [recorder], period_steps=10,
                    watchdog=Watchdog(0.045), clock=clock, sleep=clock.sleep, log=lines.append)
    runner.start()
    runner.write({"controller.u": 0.5})
    runner.run()
    runner.finish()
    timing = runner.pacer.timing
    assert len(timing) == 10 and timing.misses == 0
    assert list(timing.deadlines) == [0.01 * j for j in range(10)]
    assert list(timing.lateness) == [0.0] + [2**-12] * 9
    u = recorder.columns()["controller.u"]
    assert np.all(u[:50] == 0.5) and np.all(u[50:] == 0.0)  # 101 points, 0 to 0.1 s
    assert lines == ["t = 0.05 s: no client write for 0.0502 s (watchdog 0.045 s): controller's outputs held at zero"]
    assert runner.snapshot().status == "finished at t = 0.1 s"
    for inst in master.instances.values():
        inst.free()


def test_only_the_external_outputs_are_writable_and_only_finite_values(fmu_dir):
    master, parameters = _lqr_master(fmu_dir)
    runner = Runner(master, 0.0, 1e-3, None, parameters, lock_step=True, writable=True)
    writable = [v.name for v in runner.variables if v.writable]
    assert writable == ["controller.u"]  # no FMU here declares a tunable parameter
    roles = {v.name: v.role for v in runner.variables}
    assert roles["plant.x"] == "output" and roles["controller.x"] == "input" and roles["plant.l1"] == "parameter"
    assert "controller.h" not in roles  # the external instance's parameters are the client's
    for values, message in (({"plant.x": 1.0}, "plant.x is read-only"), ({"plant.l1": 2.0}, "read-only"),
                            ({"nothing.here": 1.0}, "not served"), ({"controller.u": math.nan}, "finite"),
                            ({"controller.u": "1"}, "finite")):
        with pytest.raises(ValueError, match=message):
            runner.write(values)
    assert isinstance(runner.request_steps(1).exception(), ValueError)  # not started yet
    for inst in master.instances.values():
        inst.free()


GAIN = """
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Gain(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k, self.u, self.y = 2.0, 1.5, 0.0
        self.register_variable(Real("k", causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = self.k * self.u
        return True
"""


def test_writable_opens_tunable_parameters_only_and_they_take_effect_at_the_next_step(tmp_path):
    """An FMU of another maker (stock pythonfmu) with a tunable gain k: without writable it is read-only;
    with it a write reaches the FMU before the next step (y = k u)."""
    from pythonfmu import FmuBuilder

    (tmp_path / "gain.py").write_text(GAIN)
    path = FmuBuilder.build_FMU(tmp_path / "gain.py", dest=tmp_path, needsExecutionTool=False)
    for writable in (False, True):
        gain = open_instance(path, "gain")
        try:
            runner = Runner(Master({"gain": gain}, []), 0.0, 0.5, None, lock_step=True, writable=writable)
            assert {v.name: v.writable for v in runner.variables} == {"gain.y": False, "gain.k": writable}
            runner.start()
            runner.request_steps(1).result(10)
            assert runner.snapshot().values == (3.0, 2.0)  # y, k
            if not writable:
                with pytest.raises(ValueError, match="gain.k is read-only"):
                    runner.write({"gain.k": 4.0})
                continue
            runner.write({"gain.k": 4.0})
            runner.request_steps(1).result(10)
            assert runner.snapshot().values == (6.0, 4.0)
        finally:
            gain.free()
