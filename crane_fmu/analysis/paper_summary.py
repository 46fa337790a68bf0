"""Turns the runs of the reproduction into the figures' metrics (``metrics.json``)."""

import math

import numpy as np
from scipy.integrate import solve_ivp

from crane_fmu.model import controller, plant
from crane_fmu.model.parameters import ControllerGains, PlantParameters

from . import linear
from .reproduce import FORM_KEYS, FORMS


def continuous_reference(gains, p, stop_time, state0=(0.0, 0.0, math.pi / 18, 0.0, 0.0, 0.0)):
    """Continuous-time closed loop (u = law(state) at every instant), DOP853 at rtol 1e-10.

    Stops where a swing angle passes 90 degrees. Returns scipy's solution:
    ``sol.t[-1]`` is where it ended, ``sol.sol(t)`` the dense states.
    """
    def field(t, s):
        return plant.derivative(s, controller.control(s, p, gains), p)

    def too_far(t, s):
        return math.pi / 2 - max(abs(s[2]), abs(s[4]))

    too_far.terminal = True
    return solve_ivp(field, (0.0, stop_time), state0, method="DOP853", dense_output=True,
                     rtol=1e-10, atol=1e-12, events=too_far)


def b3_sign_check(state=(0.0, 0.0, 0.3, 0.2, -0.2, 0.1)):
    """The model's d(theta2'')/du by central difference, against the printed and derived b3."""
    p = PlantParameters()
    _, q1, w1, q2, w2 = state[1:]
    du = 1e-4
    numeric = (plant.angular_accelerations(q1, w1, q2, w2, du, p)[1]
               - plant.angular_accelerations(q1, w1, q2, w2, -du, p)[1]) / (2 * du)
    printed = controller.drift_and_input_gain(q1, w1, q2, w2, p, "printed")[1][2]
    derived = controller.drift_and_input_gain(q1, w1, q2, w2, p, "derived")[1][2]
    return {"state": list(state), "d_ddtheta2_du": numeric, "b3_printed": printed, "b3_derived": derived}


def _by_group(results, group):
    return {name: r for name, r in results.items() if r["case"]["group"] == group}


def _freq_table(results, group, key):
    rows = []
    for r in _by_group(results, group).values():
        plant_values = r["case"]["plant"]
        p = PlantParameters(l1=plant_values.get("l1", 1.0), l2=plant_values.get("l2", 0.5))
        rows.append({key: plant_values[key if key != "theta1_0_deg" else "theta1_0"],
                     **r["metrics"], "linear_freqs_hz": linear.natural_frequencies(p)})
    if key == "theta1_0_deg":
        for row in rows:
            row[key] = round(math.degrees(row[key]), 6)
    return rows


def _roa(results, form):
    key = FORM_KEYS[form]
    rows = sorted((r["case"]["plant"]["theta1_0"], r["metrics"]["outcome"])
                  for r in _by_group(results, "roa").values() if r["case"]["name"].startswith(f"roa_{key}_"))
    contiguous = 0.0
    for angle, outcome in rows:
        if outcome != "converges":
            break
        contiguous = math.degrees(angle)
    return {"angles_deg": [round(math.degrees(a), 6) for a, _ in rows],
            "outcomes": [o for _, o in rows],
            "largest_converging_deg": contiguous,
            "converging_deg": [round(math.degrees(a), 6) for a, o in rows if o == "converges"]}


def _step_study(results, form):
    key = FORM_KEYS[form]
    runs = sorted((r for r in _by_group(results, "step").values() if r["case"]["name"].startswith(f"step_{key}_")),
                  key=lambda r: r["case"]["step"])
    gains = ControllerGains(**FORMS[form])
    stop = runs[0]["case"]["stop_time"]
    ref = continuous_reference(gains, PlantParameters(), stop)
    ref_end = float(ref.t[-1])
    rows = []
    for r in runs:
        sig = {k: np.array(v) for k, v in r["signals"].items()}
        common = sig["time"] <= ref_end
        exact = ref.sol(sig["time"][common])
        deviation = {
            "max_angle_deg": math.degrees(max(np.abs(sig["plant.theta1"][common] - exact[2]).max(),
                                              np.abs(sig["plant.theta2"][common] - exact[4]).max())),
            "max_x_m": float(np.abs(sig["plant.x"][common] - exact[0]).max()),
            "over_s": float(sig["time"][common][-1]),
        }
        rows.append({"step_s": r["case"]["step"], "outcome": r["metrics"]["outcome"],
                     "end_time_s": r["metrics"]["end_time_s"], "deviation": deviation})
    converging = [row["step_s"] for row in rows if row["outcome"] == "converges"]
    return {"reference_end_s": ref_end, "reference_stop_s": stop, "runs": rows,
            "largest_converging_step_s": max(converging) if converging else None}


def summarise(results, quick):
    """Metrics of every figure and study, as written to ``metrics.json``."""
    fig7 = _by_group(results, "fig7")
    fig8 = _by_group(results, "fig8")
    poles = {form: [complex(z) for z in linear.closed_loop_poles(PlantParameters(), ControllerGains(**s))]
             for form, s in FORMS.items()}
    fig8_poles = {f"l1={l1:g}": [complex(z) for z in linear.closed_loop_poles(
        PlantParameters(l1=l1), ControllerGains())] for l1 in (0.5, 1.0, 1.5)}
    return {
        "quick": quick,
        "settings": {"m1": 3.0, "m2": 7.0, "g": 9.8, "master": "gauss-seidel",
                     "gains": "K1 = diag(0.92, 4, 122), K2 = diag(0.84, 2, 310)"},
        "fig4": _freq_table(results, "fig4", "theta1_0_deg"),
        "fig5": _freq_table(results, "fig5", "l2"),
        "fig7": {"open loop": fig7["fig7_open_loop"]["metrics"],
                 **{form: {**fig7[f"fig7_{FORM_KEYS[form]}"]["metrics"],
                           "error": fig7[f"fig7_{FORM_KEYS[form]}"]["error"]} for form in FORMS}},
        "fig8": {form: [{"l1": r["case"]["plant"]["l1"], **r["metrics"]}
                        for r in sorted((r for r in fig8.values()
                                         if r["case"]["name"].startswith(f"fig8_{FORM_KEYS[form]}_")),
                                        key=lambda r: r["case"]["plant"]["l1"])] for form in FORMS},
        "region_of_attraction": {form: _roa(results, form) for form in FORMS},
        "communication_step": {form: _step_study(results, form) for form in FORMS},
        "linear": {"closed_loop_poles": poles, "closed_loop_poles_by_l1": fig8_poles,
                   "natural_frequencies_hz": {f"l1={l1:g}, l2={l2:g}": linear.natural_frequencies(
                       PlantParameters(l1=l1, l2=l2)) for l1, l2 in
                       ((1.0, 0.25), (1.0, 0.5), (1.0, 0.75), (1.0, 1.0), (0.5, 0.5), (1.5, 0.5))}},
        "errata": {"b3_sign": b3_sign_check()},
    }
