"""The master's compiled loop (crane_fmu/cosim/step_loop.c) against its Python loop, on built FMUs.

Both must make the same FMI calls in the same order with the same arguments: the same numbers bit for
bit, the same error at the same point, the same rows recorded before it.
"""

import ctypes
import os
import subprocess
import sys

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.build_scripts.build_fmus import fmi3_dir
from crane_fmu.build_scripts.native import native_dir, ported
from crane_fmu.cosim import FmiError
from crane_fmu.cosim.adapters import open_instance
from crane_fmu.cosim.master import Master
from crane_fmu.cosim.recorder import ArrayRecorder


def _run(system, folder, loop, algorithm="gauss-seidel", step=1e-3, stop_time=2.0, observers=()):
    """``(the master's compiled loop or None, columns, error message or None)`` of a run of ``system``."""
    system = systems.prepare(system, step, stop_time)
    fmus, connections = system.resolve(folder)
    instances = {name: open_instance(path, name) for name, path in fmus.items()}
    recorder, error = ArrayRecorder(), None
    try:
        master = Master(instances, connections, algorithm, loop=loop)
        try:
            master.run(0.0, stop_time, step, [recorder, *observers], system.parameters)
        except FmiError as exc:
            error = str(exc)
    finally:
        for inst in instances.values():
            inst.free()
    return master.compiled, recorder.columns(), error


def _folders(fmu_dir):
    folders = {"python FMI 2.0": fmu_dir, "python FMI 3.0": fmi3_dir(fmu_dir)}
    if (native_dir(fmu_dir) / "CranePlant.fmu").exists():
        folders["native FMI 2.0"] = native_dir(fmu_dir)
    return folders


@pytest.mark.parametrize("algorithm", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("name", ["paper", "transport"])  # transport's controller copies inputs of two instances
def test_the_compiled_loop_gives_the_python_loops_numbers_bit_for_bit(fmu_dir, name, algorithm):
    for label, folder in _folders(fmu_dir).items():
        compiled, fast, _ = _run(systems.get(name), folder, "auto", algorithm)
        # called holding the GIL where some FMU runs Python in this interpreter (as the Python loop calls it):
        # (the native folder holds Python FMUs of the components not ported to C)
        python_inside = label.startswith("python") or not set(systems.get(name).instances.values()) <= set(ported())
        assert isinstance(compiled.lib, ctypes.PyDLL) == python_inside, label
        used, slow, _ = _run(systems.get(name), folder, "python", algorithm)
        assert used is None
        assert fast.keys() == slow.keys() and len(fast["time"]) == 2001
        for column in fast:
            assert np.array_equal(fast[column], slow[column]), (label, column)


def test_a_failing_step_stops_both_loops_at_the_same_point_with_the_same_error(fmu_dir):
    """The paper's loop at h = 10 ms diverges: the plant discards a step; rows up to there are kept."""
    runs = [_run(systems.get("paper"), fmu_dir, loop, step=0.01, stop_time=20.0) for loop in ("auto", "python")]
    (compiled, fast, fast_error), (_, slow, slow_error) = runs
    assert compiled
    assert fast_error is not None and fast_error == slow_error and "plant: fmi2DoStep returned discard" in fast_error
    assert 1 < len(fast["time"]) < 2001
    for column in fast:
        assert np.array_equal(fast[column], slow[column]), column


def test_an_observer_that_takes_single_points_gets_every_point_from_the_python_loop(fmu_dir):
    class Points:
        def start(self, names):
            self.times = []

        def observe(self, time, values):
            self.times.append(time)

    points = Points()
    _, columns, _ = _run(systems.get("paper"), fmu_dir, "auto", observers=[points])
    assert points.times == list(columns["time"])


def test_an_iterative_algorithm_has_no_fixed_plan_and_steps_in_python(fmu_dir):
    compiled, columns, _ = _run(systems.get("paper"), fmu_dir, "auto", "iterative-jacobi")
    assert compiled is None and len(columns["time"]) == 2001


def test_the_environment_can_turn_the_compiled_loop_off():
    code = "from crane_fmu.cosim.compiled_loop import library; print(library() is None)"
    for value, off in (("python", "True"), ("", "False")):
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                              env={**os.environ, "CRANE_FMU_LOOP": value})
        assert done.stdout.strip() == off


def test_an_unknown_loop_is_refused():
    with pytest.raises(ValueError, match="^loop must be auto or python, got 'c'$"):
        Master({}, [], loop="c")


def test_without_a_writable_cache_the_master_steps_in_python(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    code = "from crane_fmu.cosim.compiled_loop import library; print(library() is None)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env={**os.environ, "XDG_CACHE_HOME": str(blocked)})
    assert done.stdout.strip() == "True"
