"""The controller for hard hits: no hole in its region of attraction, the LQR near rest, through the FMUs."""

import math

import numpy as np
import pytest

from crane_fmu import systems
from crane_fmu.analysis import metrics
from crane_fmu.cosim import ArrayRecorder, run
from crane_fmu.model import hard_hit, lqr

ANGLES = range(0, 65, 5)  # issue 28: every initial hook angle 0-60 deg in 5-deg steps, payload in line, at rest


@pytest.mark.quick
def test_near_rest_it_is_the_lqr():
    """Below the energy of theta_near the law is the LqrController with its default weights, bit for bit."""
    c, ref = hard_hit.COMPONENT.check({}), lqr.COMPONENT.check({})
    assert c.near == ref.gains and c.far == lqr.design(hard_hit.plant_parameters(hard_hit.COMPONENT.defaults()),
                                                      [5.0, 0.0, 400.0, 10.0, 50.0, 5.0], 0.5, 1e-3)
    for s in ((0.1, 0.2, 0.05, 0.1, 0.04, -0.2), (-1.0, 0.5, -0.1, 0.0, -0.1, 0.0)):
        assert hard_hit.blend(c, s) == 0.0 and hard_hit.control(c, s) == lqr.control(ref, s)
    assert hard_hit.blend(c, (0.0, 0.0, math.radians(14.0), 0.0, math.radians(14.0), 0.0)) == pytest.approx(1.0)


@pytest.mark.quick
@pytest.mark.parametrize("values, message", [
    ({"theta_far": math.radians(10.0)}, "theta_far must be > theta_near = 0.1832595714594046 and < pi/2, got "
                                        "0.17453292519943295"),
    ({"r_far": 0.0}, "r_far must be > 0 and finite, got 0.0"),
    ({"q_x_far": -1.0}, "q_x_far must be >= 0 and finite, got -1.0"),
])
def test_parameter_rules(values, message):
    with pytest.raises(ValueError) as info:
        hard_hit.COMPONENT.check(values)
    assert str(info.value) == message


def test_no_hole_in_the_region_of_attraction(fmu_dir):
    """Issue 28 through the FMUs (Section V plant, |u| <= 2 m/s2, |v| <= 1 m/s, h = 1 ms, 20 s): from every
    angle of :data:`ANGLES` both angles settle within 0.1 deg; from 60 deg within 0.5 deg by 10 s; from 10 deg
    within 0.1 deg by 3.5 s (the LQR's performance the issue keeps); the drive's limits hold."""
    system = systems.get("hard-hit")
    settled = {}
    for angle in ANGLES:
        c = run(system.with_parameters({"plant": {"theta1_0": math.radians(angle)}}), fmu_dir,
                recorder=ArrayRecorder()).columns()
        m = metrics.move_metrics(c["time"], c["plant.x"], c["plant.dx"], (c["plant.theta1"], c["plant.theta2"]),
                                 c["controller.u"], 0.0)
        settled[angle] = (m["settling_0.5deg_s"], m["settling_0.1deg_s"])
        assert np.abs(c["controller.u"]).max() <= 2.0 and np.abs(c["plant.dx"]).max() <= 1.0 + 1e-9
    assert all(s[1] is not None for s in settled.values()), settled
    assert settled[60][0] <= 10.0, settled[60]
    assert settled[10][1] <= 3.5, settled[10]
