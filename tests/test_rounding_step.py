"""A communication step within rounding of zero is no step, in every component FMU as in the one-FMU systems
(issue 50): hosts that add up their steps end a run with the remainder ``stop - t`` (OMSimulator: 1.03e-13 s
after 10,000 steps of 1 ms, 1.1e-10 s after 10^5), and a component that took it as a step would move on by a
step the run never had (on main: the state estimator, the sensors, the wind and the plants did; lqg-transport's
last row in OMSimulator then differed from ours by 1.7e-2).

Every FMU of every kind (the Python FMUs, the native components; FMI 2.0 and 3.0) is stepped as a host steps it,
with inputs away from zero, then given the remainder: every output reads bit for bit what it read before, and a
step of 1 ms after it is taken as one.
"""

from pathlib import Path

import numpy as np
import pytest
from fmu_kinds import FMU_KINDS
from native_fmus import close, open_native

REMAINDERS = (1.0302869668521453e-13, 1.1e-10)  # OMSimulator's last step after 10^4 and 10^5 steps of 1 ms
H = 1e-3


def _outputs_around_the_remainder(path, version, remainder):
    """``(outputs before, outputs after the remainder, outputs after one more step)``."""
    fmu, vr, set_, get = open_native(path, version)
    try:
        from fmpy import read_model_description

        md = read_model_description(str(path))
        inputs = [v.name for v in md.modelVariables if v.causality == "input" and v.type in ("Real", "Float64")]
        outputs = [vr[v.name] for v in md.modelVariables if v.causality == "output"
                   and v.type in ("Real", "Float64")]
        if inputs:
            set_([vr[n] for n in inputs], [0.1 * (k + 1) for k in range(len(inputs))])
        fmu.exitInitializationMode()
        t = 0.0
        for _ in range(5):
            fmu.doStep(t, H)
            t += H
        before = np.array(get(outputs))
        fmu.doStep(t, remainder)
        after = np.array(get(outputs))
        fmu.doStep(t + remainder, H)
        later = np.array(get(outputs))
    finally:
        close(fmu)
    return before, after, later


@pytest.mark.parametrize("remainder", REMAINDERS, ids=["1e-13 s", "1e-10 s"])
@pytest.mark.parametrize("kind", list(FMU_KINDS))
@pytest.mark.parametrize("version", [2, 3])
def test_a_remainder_step_changes_no_output(fmu_kinds, kind, version, remainder):
    folder = Path(fmu_kinds[kind][version])
    paths = sorted(folder.glob("*.fmu"))
    assert paths, folder
    moved, checked = [], 0
    for path in paths:
        before, after, later = _outputs_around_the_remainder(path, version, remainder)
        checked += 1
        if not np.array_equal(before.view(np.int64), after.view(np.int64)):
            moved.append(f"{path.name}: {np.max(np.abs(after - before)):.3g}")
    assert moved == [], f"{len(moved)} of {checked} FMUs took the remainder as a step: " + "; ".join(moved)
