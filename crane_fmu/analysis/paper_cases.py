"""The co-simulations of the paper reproduction: typed cases, each naming its system and controller form."""

import math
from collections import namedtuple

import numpy as np

Form = namedtuple("Form", "key label controller")
Form.__doc__ = "A controller form: its key (file names), label (report) and controller parameters."

# The controller forms compared in Figures 7 and 8: the paper's law with the
# printed and with the re-derived b3, and the law without the theta2 row.
FORMS = (
    Form("printed", "printed b3", {"b3_form": "printed"}),
    Form("derived", "derived b3", {"b3_form": "derived"}),
    Form("w110", "weights (1,1,0)", {"w_theta2": 0.0}),
)
PAPER_LAW = ("printed b3", "derived b3")  # eq (21) with W = I, b3 as printed / as corrected
ALTERNATIVE = "weights (1,1,0)"
STEPS = (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 1e-1)

Case = namedtuple("Case", "name figure system form stop_time step plant controller output_interval")
Case.__doc__ = ("One co-simulation of a built-in system (``free`` or ``paper``): the figure or study it belongs "
                "to, the controller form (None without controller), stop time and communication step [s], plant "
                "and controller parameters, CSV output interval [s].")


def plan(quick=False):
    """The cases of the full reproduction, or of the quick one (every figure, fewer cases)."""
    rad = math.radians
    cases = []
    amplitudes = (10, 20) if quick else (5, 10, 15, 20)
    lengths = (0.25, 1.0) if quick else (0.25, 0.5, 0.75, 1.0)
    free_time = 20.0 if quick else 30.0
    for a in amplitudes:  # Figure 4: l1 = 1 m, l2 = 0.25 m
        cases.append(Case(f"fig4_theta1_{a}deg", "fig4", "free", None, free_time, 0.01,
                          {"l1": 1.0, "l2": 0.25, "theta1_0": rad(a)}, {}, 0.01))
    for l2 in lengths:  # Figure 5: l1 = 1 m, 10 degrees
        cases.append(Case(f"fig5_l2_{l2:g}m", "fig5", "free", None, free_time, 0.01,
                          {"l1": 1.0, "l2": l2, "theta1_0": rad(10)}, {}, 0.01))
    loop_time = 20.0 if quick else 30.0
    cases.append(Case("fig7_open_loop", "fig7", "free", None, loop_time, 1e-3, {}, {}, 0.01))
    for form in FORMS:
        cases.append(Case(f"fig7_{form.key}", "fig7", "paper", form, loop_time, 1e-3, {}, form.controller, 0.01))
        for l1 in ((0.5, 1.5) if quick else (0.5, 1.0, 1.5)):  # Figure 8: l2 = 0.5 m
            cases.append(Case(f"fig8_{form.key}_l1_{l1:g}m", "fig8", "paper", form, loop_time, 1e-3,
                              {"l1": l1}, {**form.controller, "l1": l1}, 0.01))
        angles = np.arange(5.0, 20.1, 5.0) if quick else np.arange(0.5, 20.01, 0.5)
        for a in angles:  # region of attraction
            cases.append(Case(f"roa_{form.key}_{a:g}deg", "roa", "paper", form, 10.0 if quick else 20.0, 1e-3,
                              {"theta1_0": rad(a)}, form.controller, 0.05))
        for h in ((1e-3, 1e-2, 1e-1) if quick else STEPS):  # communication step
            cases.append(Case(f"step_{form.key}_h_{h:g}s", "step", "paper", form, 10.0 if quick else 20.0, h,
                              {}, form.controller, max(h, 0.01)))
    return cases
