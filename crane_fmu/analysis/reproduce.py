"""Reproduction of the paper's Figures 4, 5, 7 and 8 through the co-simulated FMUs.

Every number comes from running CranePlant.fmu (and BacksteppingController.fmu)
with the project's master; scipy only supplies the continuous-time reference of
the communication-step study and the linear analysis. Nothing is tuned: the
cases are the paper's, and the verdict rules in ``report.py`` are fixed.
"""

import json
import math
import os
from collections import namedtuple
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from crane_fmu.cosim import ArrayRecorder, FmiError, crane_system, simulate, write_csv

from . import metrics

Case = namedtuple("Case", "name group stop_time step plant controller output_interval")
Case.__doc__ = ("One co-simulation: plant and controller parameters (controller None = free swing), "
                "stop time and communication step [s], CSV output interval [s].")

# The controller forms compared in Figures 7 and 8: the paper's law with the
# printed and with the re-derived b3, and the law without the theta2 row.
FORMS = {
    "printed b3": {"b3_form": "printed"},
    "derived b3": {"b3_form": "derived"},
    "weights (1,1,0)": {"w_theta2": 0.0},
}
FORM_KEYS = {"printed b3": "printed", "derived b3": "derived", "weights (1,1,0)": "w110"}
STEPS = (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 1e-1)


def plan(quick=False):
    """The cases of the full reproduction, or of the quick one (every figure, fewer cases)."""
    rad = math.radians
    cases = []
    amplitudes = (10, 20) if quick else (5, 10, 15, 20)
    lengths = (0.25, 1.0) if quick else (0.25, 0.5, 0.75, 1.0)
    free_time = 20.0 if quick else 30.0
    for a in amplitudes:  # Figure 4: l1 = 1 m, l2 = 0.25 m
        cases.append(Case(f"fig4_theta1_{a}deg", "fig4", free_time, 0.01,
                          {"l1": 1.0, "l2": 0.25, "theta1_0": rad(a)}, None, 0.01))
    for l2 in lengths:  # Figure 5: l1 = 1 m, 10 degrees
        cases.append(Case(f"fig5_l2_{l2:g}m", "fig5", free_time, 0.01,
                          {"l1": 1.0, "l2": l2, "theta1_0": rad(10)}, None, 0.01))
    loop_time = 20.0 if quick else 30.0
    cases.append(Case("fig7_open_loop", "fig7", loop_time, 1e-3, {}, None, 0.01))
    for form, settings in FORMS.items():
        cases.append(Case(f"fig7_{FORM_KEYS[form]}", "fig7", loop_time, 1e-3, {}, settings, 0.01))
        for l1 in ((0.5, 1.5) if quick else (0.5, 1.0, 1.5)):  # Figure 8: l2 = 0.5 m
            cases.append(Case(f"fig8_{FORM_KEYS[form]}_l1_{l1:g}m", "fig8", loop_time, 1e-3,
                              {"l1": l1}, {**settings, "l1": l1}, 0.01))
        angles = np.arange(5.0, 20.1, 5.0) if quick else np.arange(0.5, 20.01, 0.5)
        for a in angles:  # region of attraction
            cases.append(Case(f"roa_{FORM_KEYS[form]}_{a:g}deg", "roa", 10.0 if quick else 20.0, 1e-3,
                              {"theta1_0": rad(a)}, settings, 0.05))
        for h in ((1e-3, 1e-2, 1e-1) if quick else STEPS):  # communication step
            cases.append(Case(f"step_{FORM_KEYS[form]}_h_{h:g}s", "step", 10.0 if quick else 20.0, h,
                              {}, settings, max(h, 0.01)))
    return cases


def run_case(case, fmu_dir, csv_dir):
    """Co-simulate one case through the FMUs; write its CSV; return its metrics and coarse signals."""
    fmus, connections = crane_system(fmu_dir, controller=case.controller is not None)
    parameters = {"plant": case.plant}
    if case.controller is not None:
        parameters["controller"] = case.controller
    recorder = ArrayRecorder()
    error = None
    try:
        simulate(fmus, connections, case.stop_time, case.step, "gauss-seidel", parameters, recorder)
    except FmiError as exc:
        error = str(exc)
    columns = recorder.columns()
    every = max(1, round(case.output_interval / case.step))
    write_csv(Path(csv_dir) / f"{case.name}.csv", columns, every)
    t = columns["time"]
    x, th1, th2 = columns["plant.x"], columns["plant.theta1"], columns["plant.theta2"]
    result = {"case": case._asdict(), "error": error, "completed": error is None}
    if case.controller is None:
        result["metrics"] = free_swing_metrics(t, th1, th2, case.plant.get("theta1_0", math.pi / 18))
    else:
        result["metrics"] = metrics.closed_loop_metrics(t, x, th1, th2, columns["controller.u"], error is None)
    keep = ["time", "plant.x", "plant.theta1", "plant.theta2"] + (
        ["controller.u"] if case.controller is not None else [])
    result["signals"] = {k: columns[k][::every].tolist() for k in keep}
    return result


def free_swing_metrics(t, theta1, theta2, theta1_0):
    """Largest angles, the Figure 4 ratio, and the frequencies present in each angle."""
    return {
        "max_theta1_deg": math.degrees(metrics.peak_abs(theta1)),
        "max_theta2_deg": math.degrees(metrics.peak_abs(theta2)),
        "ratio_max_theta2_to_theta1_0": metrics.peak_abs(theta2) / theta1_0,
        "rms_theta1_deg": math.degrees(metrics.rms(theta1)),
        "freqs_theta1_hz": metrics.dominant_frequencies(t, theta1),
        "freqs_theta2_hz": metrics.dominant_frequencies(t, theta2),
    }


def _run_all(cases, fmu_dir, csv_dir, workers, log):
    results = {}
    if workers == 1:
        for i, case in enumerate(cases):
            results[case.name] = run_case(case, fmu_dir, csv_dir)
            log(f"  [{i + 1}/{len(cases)}] {case.name}")
        return results
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(run_case, c, fmu_dir, csv_dir): c for c in cases}
        for i, future in enumerate(futures):
            results[futures[future].name] = future.result()
            if (i + 1) % 20 == 0 or i + 1 == len(cases):
                log(f"  {i + 1}/{len(cases)} runs done")
    return results


def reproduce(out_dir, fmu_dir="build/fmus", quick=False, workers=None, log=print):
    """Run every case, then write figures, CSVs, ``metrics.json`` and ``REPORT.md`` to ``out_dir``.

    Returns
    -------
    dict
        The metrics written to ``metrics.json``.
    """
    from . import figures, paper_summary, report

    out_dir = Path(out_dir)
    csv_dir = out_dir / "runs"
    csv_dir.mkdir(parents=True, exist_ok=True)
    cases = plan(quick)
    workers = workers or os.cpu_count() or 1
    log(f"running {len(cases)} co-simulations on {workers} worker(s)")
    results = _run_all(cases, fmu_dir, csv_dir, workers, log)
    summary = paper_summary.summarise(results, quick)
    (out_dir / "metrics.json").write_text(json.dumps(summary, indent=2, default=_jsonable))
    for path in figures.draw_all(results, out_dir):
        log(f"wrote {path}")
    (out_dir / "REPORT.md").write_text(report.render(summary))
    log(f"wrote {out_dir / 'metrics.json'} and {out_dir / 'REPORT.md'}")
    return summary


def _jsonable(value):
    if isinstance(value, complex | np.complexfloating):
        return [value.real, value.imag]
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
