"""Turns the runs of the reproduction into the figures' metrics (``metrics.json``)."""

import dataclasses
import math

import numpy as np
from scipy.integrate import solve_ivp

from crane_fmu.model import backstepping, plant
from crane_fmu.model.parameters import ControllerGains, PlantParameters

from . import linear
from .metrics import CONVERGING
from .paper_cases import FORMS


def continuous_reference(gains, p, stop_time, state0=(0.0, 0.0, math.pi / 18, 0.0, 0.0, 0.0)):
    """Continuous-time closed loop (u = law(state) at every instant), DOP853 at rtol 1e-10.

    Stops where a swing angle passes 90 degrees. Returns scipy's solution:
    ``sol.t[-1]`` is where it ended, ``sol.sol(t)`` the dense states.
    """
    def field(t, s):
        return plant.derivative(s, backstepping.control(s, p, gains), p)

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
    printed = backstepping.drift_and_input_gain(q1, w1, q2, w2, p, "printed")[1][2]
    derived = backstepping.drift_and_input_gain(q1, w1, q2, w2, p, "derived")[1][2]
    return {"state": list(state), "d_ddtheta2_du": numeric, "b3_printed": printed, "b3_derived": derived}


def _runs(results, figure, form=None):
    """The runs of one figure or study (of one controller form)."""
    return [r for r in results.values() if r["case"].figure == figure and (form is None or r["case"].form == form)]


def _freq_table(results, group, key):
    rows = []
    for r in _runs(results, group):
        plant_values = r["case"].plant
        p = PlantParameters(l1=plant_values.get("l1", 1.0), l2=plant_values.get("l2", 0.5))
        rows.append({key: plant_values[key if key != "theta1_0_deg" else "theta1_0"],
                     **r["metrics"], "linear_freqs_hz": linear.natural_frequencies(p), "l1": p.l1, "l2": p.l2,
                     "case_theta1_0_deg": round(math.degrees(plant_values.get("theta1_0", math.pi / 18)), 6)})
    if key == "theta1_0_deg":
        for row in rows:
            row[key] = round(math.degrees(row[key]), 6)
    return rows


def _roa(results, form):
    rows = sorted((r["case"].plant["theta1_0"], r["metrics"]["outcome"]) for r in _runs(results, "roa", form))
    contiguous = 0.0
    for angle, outcome in rows:
        if outcome not in CONVERGING:
            break
        contiguous = math.degrees(angle)
    return {"angles_deg": [round(math.degrees(a), 6) for a, _ in rows],
            "outcomes": [o for _, o in rows],
            "largest_converging_deg": contiguous,
            "converging_deg": [round(math.degrees(a), 6) for a, o in rows if o in CONVERGING]}


def _step_study(results, form):
    runs = sorted(_runs(results, "step", form), key=lambda r: r["case"].step)
    gains = ControllerGains(**form.controller)
    stop = runs[0]["case"].stop_time
    ref = continuous_reference(gains, PlantParameters(), stop)
    ref_end = float(ref.t[-1])
    rows = []
    for r in runs:
        sig = {k: np.array(v) for k, v in r["signals"].items()}
        common = sig["time"] <= ref_end
        exact = ref.sol(sig["time"][common])
        deviation = {
            "max_angle_deg": math.degrees(max(np.abs(sig["theta1"][common] - exact[2]).max(),
                                              np.abs(sig["theta2"][common] - exact[4]).max())),
            "max_x_m": float(np.abs(sig["x"][common] - exact[0]).max()),
            "over_s": float(sig["time"][common][-1]),
        }
        rows.append({"step_s": r["case"].step, "outcome": r["metrics"]["outcome"],
                     "end_time_s": r["metrics"]["end_time_s"], "deviation": deviation})
    converging = [row["step_s"] for row in rows if row["outcome"] in CONVERGING]
    return {"reference_end_s": ref_end, "reference_stop_s": stop, "runs": rows,
            "largest_converging_step_s": max(converging) if converging else None}


def summarise(results, quick):
    """Metrics of every figure and study, as written to ``metrics.json``."""
    fig7 = {r["case"].form.key if r["case"].form else None: r for r in _runs(results, "fig7")}
    poles = {f.label: [complex(z) for z in linear.closed_loop_poles(PlantParameters(), ControllerGains(**f.controller))]
             for f in FORMS}
    fig8_poles = {f"l1={l1:g}": [complex(z) for z in linear.closed_loop_poles(
        PlantParameters(l1=l1), ControllerGains())] for l1 in (0.5, 1.0, 1.5)}
    return {
        "quick": quick,
        "settings": {"plant": dataclasses.asdict(PlantParameters()), "gains": dataclasses.asdict(ControllerGains()),
                     "theta1_0_deg": math.degrees(fig7[None]["case"].plant.get("theta1_0", math.pi / 18)),
                     "step_s": fig7[None]["case"].step, "master": "gauss-seidel"},
        "fig4": _freq_table(results, "fig4", "theta1_0_deg"),
        "fig5": _freq_table(results, "fig5", "l2"),
        "fig7": {"open loop": fig7[None]["metrics"],
                 **{f.label: {**fig7[f.key]["metrics"], "error": fig7[f.key]["error"]} for f in FORMS}},
        "fig8": {f.label: [{"l1": r["case"].plant["l1"], **r["metrics"]}
                           for r in sorted(_runs(results, "fig8", f), key=lambda r: r["case"].plant["l1"])]
                 for f in FORMS},
        "region_of_attraction": {f.label: _roa(results, f) for f in FORMS},
        "communication_step": {f.label: _step_study(results, f) for f in FORMS},
        "linear": {"closed_loop_poles": poles, "closed_loop_poles_by_l1": fig8_poles,
                   "natural_frequencies_hz": {f"l1={l1:g}, l2={l2:g}": linear.natural_frequencies(
                       PlantParameters(l1=l1, l2=l2)) for l1, l2 in
                       ((1.0, 0.25), (1.0, 0.5), (1.0, 0.75), (1.0, 1.0), (0.5, 0.5), (1.5, 0.5))}},
        "errata": {"b3_sign": b3_sign_check()},
    }
