"""Random cases of the spatial crane's Model Exchange plant, shared by its Python and its C tests."""

import math
import random

from crane_fmu.model import plant3d
from crane_fmu.model import plant3d_continuous as me3


def cases(n=20, seed=3):
    """Random parameters (damping, drive lags, finite limits), states, inputs and modes of the ME plant."""
    rng = random.Random(seed)
    for k in range(n):
        values = {"m1": rng.uniform(0.5, 10), "m2": rng.uniform(0.1, 10), "l1": rng.uniform(0.3, 3),
                  "l2": rng.uniform(0.1, 2), "g": rng.uniform(1, 20), "c1": rng.uniform(0, 5), "c2": rng.uniform(0, 5),
                  "tau_x": rng.choice((0.0, rng.uniform(0.05, 1))), "tau_y": rng.choice((0.0, rng.uniform(0.05, 1))),
                  "ux_max": rng.choice((math.inf, 3.0)), "uy_max": rng.choice((math.inf, 3.0))}
        config = plant3d.COMPONENT.check(values)
        state = tuple(rng.uniform(-1.2, 1.2) for _ in range(12)) + (rng.uniform(0.3, 3), rng.uniform(-1, 1),
                                                                   rng.uniform(-2, 2), rng.uniform(-2, 2))
        inputs = (rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-2, 2),
                  *(rng.uniform(-50, 50) for _ in range(4)))
        mode = me3.FREE if k % 3 == 0 else me3.Mode(*(rng.choice((-1, 0, 1)) for _ in range(4)))
        yield config, state, inputs, mode
